//! Camera path tracing: the radiance L = B/π seen through each pixel of a pinhole camera (a diffuse surface's
//! radiance is its radiosity over π), estimated with `samples_per_pixel` primary rays jittered uniformly over
//! the pixel, each continued by the path estimator of path_estimator.rs (NEE + MIS + Russian roulette; Kajiya
//! 1986, Veach 1997). Returns the mean radiance and the standard error of that mean per pixel and channel.
//!
//! A primary ray that escapes or reaches the back of a face sees 0 (faces are one-sided). Pixel (x, y) draws
//! from random stream y·width + x, so images are bit-identical for any number of threads.

use std::sync::atomic::{AtomicUsize, Ordering};

use radlab_answer::Image;
use radlab_method::MethodParams;
use radlab_scene::{Camera, Rgb, Scene, sampling};
use radlab_visibility::Accel;
use rayon::prelude::*;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::path_estimator::{DirectSampling, PathEstimator};
use crate::point_estimator::DEFAULT_MAX_DEPTH;
use crate::running_stats::RunningStats;

/// Parameters of camera path tracing, each declared once on its field (doc comment: help; `schemars`
/// attribute: range; default: `impl Default`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct RenderParams {
    /// Paths per pixel for render; the standard error falls as 1/√samples_per_pixel (1 gives a preview with an
    /// infinite standard error).
    #[schemars(range(min = 1))]
    pub samples_per_pixel: u32,
    /// Cap on path segments after the first hit (see `PointParams::max_depth`).
    #[schemars(range(min = 1))]
    pub max_depth: u32,
    /// How direct light is sampled at each path vertex: mis (next-event and hemisphere sampling, power
    /// heuristic), next-event or hemisphere.
    pub direct: DirectSampling,
}

impl Default for RenderParams {
    fn default() -> Self {
        Self {
            samples_per_pixel: 64,
            max_depth: DEFAULT_MAX_DEPTH,
            direct: DirectSampling::Mis,
        }
    }
}

impl MethodParams for RenderParams {}

/// Path-traces `camera`'s pixels: (mean radiance, standard error of the mean), both in W/m²/sr, linear RGB.
/// `progress(pixels_done, pixels_total)` is called from worker threads after each row.
pub fn render(
    scene: &Scene,
    accel: &Accel,
    camera: &Camera,
    params: &RenderParams,
    seed: u64,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> (Image, Image) {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let estimator = PathEstimator::new(scene, accel, params.max_depth, params.direct);
    let frame = camera.frame();
    let done = AtomicUsize::new(0);
    let total = w * h;
    let rows: Vec<Vec<(Rgb, Rgb)>> = (0..h)
        .into_par_iter()
        .map(|y| {
            let row = (0..w)
                .map(|x| {
                    let mut rng = sampling::rng(seed, (y * w + x) as u64);
                    let mut stats = RunningStats::default();
                    for _ in 0..params.samples_per_pixel {
                        let (jx, jy) = (sampling::uniform(&mut rng), sampling::uniform(&mut rng));
                        let ray = frame.ray(x as f64 + jx, y as f64 + jy);
                        let radiance = match accel.intersect(&ray) {
                            Some(hit) if scene.faces[hit.face].normal.dot(ray.dir) < 0.0 => {
                                estimator.radiosity(
                                    hit.face,
                                    hit.point,
                                    scene.faces[hit.face].normal,
                                    &mut rng,
                                ) * std::f64::consts::FRAC_1_PI
                            }
                            _ => Rgb::ZERO,
                        };
                        stats.push(radiance);
                    }
                    (stats.mean(), stats.std_error())
                })
                .collect();
            progress(done.fetch_add(w, Ordering::AcqRel) + w, total);
            row
        })
        .collect();
    let (mean, se): (Vec<Rgb>, Vec<Rgb>) = rows.into_iter().flatten().unzip();
    let image = |pixels| Image {
        width: camera.width,
        height: camera.height,
        pixels,
    };
    (image(mean), image(se))
}

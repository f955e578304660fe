//! Primary-ray rendering of any [`Solution`]: each pixel shows the radiance L = B/π (W/m²/sr) of the first
//! surface its ray hits (a diffuse surface's radiance is its radiosity over π), averaged over jittered
//! sub-pixel samples. Surfaces are one-sided: a face seen from behind is black, as in the path tracer. Rows
//! are rendered in parallel; sample positions derive from (seed, pixel), so the image does not depend on the
//! thread count.

use rayon::prelude::*;

use radlab_method::Solution;
use radlab_scene::{Camera, Rgb, Scene, sampling};
use radlab_visibility::Accel;

/// A linear RGB image, row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Pixels, row-major.
    pub pixels: Vec<Rgb>,
}

impl Image {
    /// The pixel at column x, row y.
    pub fn get(&self, x: u32, y: u32) -> Rgb {
        self.pixels[(y * self.width + x) as usize]
    }
}

/// Renders the radiance B/π of `solution` seen through `camera`, `spp` jittered samples per pixel
/// (1 = pixel centres). Rays that escape the scene are black. `progress(pixels_done, pixels_total)` is
/// called from worker threads after each row: with a final gather every sample is a gather, so an image
/// can take minutes.
pub fn render_solution(
    scene: &Scene,
    accel: &Accel,
    camera: &Camera,
    solution: &dyn Solution,
    spp: u32,
    seed: u64,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Image {
    let (w, h) = (camera.width, camera.height);
    let spp = spp.max(1);
    let total = (w * h) as usize;
    let done = std::sync::atomic::AtomicUsize::new(0);
    let mut pixels = vec![Rgb::ZERO; total];
    pixels
        .par_chunks_mut(w as usize)
        .enumerate()
        .for_each(|(y, row)| {
            for (x, px) in row.iter_mut().enumerate() {
                let mut sum = Rgb::ZERO;
                let mut r = sampling::rng(seed, (y as u64) * w as u64 + x as u64);
                for s in 0..spp {
                    let (jx, jy) = if spp == 1 && s == 0 {
                        (0.5, 0.5)
                    } else {
                        (sampling::uniform(&mut r), sampling::uniform(&mut r))
                    };
                    let ray = camera.ray(x as f64 + jx, y as f64 + jy);
                    if let Some(hit) = accel.intersect(&ray)
                        && scene.faces[hit.face].normal.dot(ray.dir) < 0.0
                    {
                        sum += solution.radiosity_at(hit.face, hit.point) / std::f64::consts::PI;
                    }
                }
                *px = sum / spp as f64;
            }
            let n = row.len();
            progress(
                done.fetch_add(n, std::sync::atomic::Ordering::AcqRel) + n,
                total,
            );
        });
    Image {
        width: w,
        height: h,
        pixels,
    }
}

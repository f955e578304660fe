//! The per-point radiosity estimator, radlab's reference: at each surface point x, the mean of N independent
//! samples of B(x) = E(x) + ρ(x) H(x) from the path estimator (path_estimator.rs: next-event estimation and
//! cosine-weighted hemisphere sampling combined by multiple importance sampling, Veach 1997; Russian roulette),
//! with the standard error of that mean, s/√N, per channel. Unbiased and independent of any mesh.
//!
//! The N samples of a point are split into fixed chunks of [`SAMPLES_PER_CHUNK`]; chunk c of point i draws from
//! random stream (i, c) and chunks are merged in order (running_stats.rs), so the answer is bit-identical for
//! any number of threads while a single point can still use them all.

use std::sync::atomic::{AtomicU32, AtomicUsize, Ordering};

use glam::DVec3;
use radlab_method::MethodParams;
use radlab_scene::{
    FaceId, Rgb, Scene,
    sampling::{self, Rng},
};
use radlab_visibility::Accel;
use rayon::prelude::*;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::path_estimator::{DirectSampling, PathEstimator};
use crate::running_stats::RunningStats;

/// Samples per work item (fixed, so results do not depend on how work is spread over threads).
pub const SAMPLES_PER_CHUNK: u32 = 256;

/// Default number of path segments after which a path is cut (see [`PointParams::max_depth`]).
pub const DEFAULT_MAX_DEPTH: u32 = 100_000;

/// Parameters of the per-point estimator, each declared once on its field (doc comment: help; `schemars`
/// attribute: range; default: `impl Default`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct PointParams {
    /// Paths per point; the standard error falls as 1/√samples (2 or more give a standard error).
    #[schemars(range(min = 1))]
    pub samples: u32,
    /// Cap on path segments (1: direct light only); Russian roulette ends paths without bias, the cap only
    /// guards against runaway paths.
    ///
    /// The cap could only bias by ρ_max^max_depth (relative), e.g. 4.5e-44 at ρ = 0.999.
    #[schemars(range(min = 1))]
    pub max_depth: u32,
    /// How direct light is sampled at each path vertex: mis (next-event and hemisphere sampling, power
    /// heuristic), next-event or hemisphere.
    pub direct: DirectSampling,
}

impl Default for PointParams {
    fn default() -> Self {
        Self {
            samples: 1024,
            max_depth: DEFAULT_MAX_DEPTH,
            direct: DirectSampling::Mis,
        }
    }
}

impl MethodParams for PointParams {}

/// A point on a surface at which radiosity is estimated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// The face it lies on (its emission and reflectance apply; rays leaving it ignore it).
    pub face: FaceId,
    /// Position (on the face).
    pub point: DVec3,
    /// Unit normal: the hemisphere gathered over. Normally the face's normal (its front).
    pub normal: DVec3,
}

impl SurfacePoint {
    /// The point `point` on face `face` of `scene`, gathering over the face's front.
    pub fn on_face(scene: &Scene, face: FaceId, point: DVec3) -> Self {
        Self {
            face,
            point,
            normal: scene.faces[face].normal,
        }
    }
}

impl From<&radlab_method::EvalPoint> for SurfacePoint {
    fn from(p: &radlab_method::EvalPoint) -> Self {
        Self {
            face: p.face,
            point: p.point,
            normal: p.normal,
        }
    }
}

/// The surface points of evaluation points (e.g. [`radlab_method::evaluation_points`]), in their order.
pub fn surface_points(points: &[radlab_method::EvalPoint]) -> Vec<SurfacePoint> {
    points.iter().map(SurfacePoint::from).collect()
}

/// The estimate at one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointEstimate {
    /// Mean radiosity B (W/m², per channel).
    pub mean: Rgb,
    /// Standard error of the mean per channel (infinite with fewer than 2 samples).
    pub std_error: Rgb,
}

/// Estimates B at every point with `params.samples` paths each; see the module documentation.
pub fn estimate_points(
    scene: &Scene,
    accel: &Accel,
    points: &[SurfacePoint],
    params: &PointParams,
    seed: u64,
) -> Vec<PointEstimate> {
    estimate_points_with_progress(scene, accel, points, params, seed, &|_, _| {})
}

/// As [`estimate_points`], calling `progress(points_done, points_total)` from worker threads as points
/// complete (calls may arrive slightly out of order; the last one made reports the total).
pub fn estimate_points_with_progress(
    scene: &Scene,
    accel: &Accel,
    points: &[SurfacePoint],
    params: &PointParams,
    seed: u64,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Vec<PointEstimate> {
    let chunks = params.samples.div_ceil(SAMPLES_PER_CHUNK).max(1);
    let estimator = PathEstimator::new(scene, accel, params.max_depth, params.direct);
    let remaining: Vec<AtomicU32> = points.iter().map(|_| AtomicU32::new(chunks)).collect();
    let done = AtomicUsize::new(0);
    let total = points.len();
    let chunk_done = |i: usize| {
        if remaining[i].fetch_sub(1, Ordering::AcqRel) == 1 {
            progress(done.fetch_add(1, Ordering::AcqRel) + 1, total);
        }
    };
    sample_points(points, params.samples, 0, seed, &chunk_done, &|p, rng| {
        estimator.radiosity(p.face, p.point, p.normal, rng)
    })
    .iter()
    .map(|s| PointEstimate {
        mean: s.mean(),
        std_error: s.std_error(),
    })
    .collect()
}

/// One sample of the radiosity B leaving a surface point, drawn from the given stream: what a per-point
/// estimator supplies to [`sample_points`].
pub type PointSampler<'s> = dyn Fn(&SurfacePoint, &mut Rng) -> Rgb + Sync + 's;

/// `samples` draws of `sample` at every point, in chunks of [`SAMPLES_PER_CHUNK`]: chunk c of point i draws
/// from stream (i, `first_chunk` + c) of `seed`, and a point's chunks are merged in order, so the result is the
/// same for any number of threads. `chunk_done(i)` is called (from worker threads) as each chunk of point i
/// finishes.
pub fn sample_points(
    points: &[SurfacePoint],
    samples: u32,
    first_chunk: u64,
    seed: u64,
    chunk_done: &(dyn Fn(usize) + Sync),
    sample: &PointSampler,
) -> Vec<RunningStats> {
    let chunks = samples.div_ceil(SAMPLES_PER_CHUNK).max(1) as usize;
    let parts: Vec<RunningStats> = (0..points.len() * chunks)
        .into_par_iter()
        .map(|item| {
            let (i, c) = (item / chunks, item % chunks);
            let p = &points[i];
            let first = c as u32 * SAMPLES_PER_CHUNK;
            let count = SAMPLES_PER_CHUNK.min(samples - first.min(samples));
            let mut rng = sampling::rng(seed, ((i as u64) << 32) | (first_chunk + c as u64));
            let mut stats = RunningStats::default();
            for _ in 0..count {
                stats.push(sample(p, &mut rng));
            }
            chunk_done(i);
            stats
        })
        .collect();
    parts
        .chunks(chunks)
        .map(|point_parts| {
            let mut s = RunningStats::default();
            point_parts.iter().for_each(|p| s.merge(p));
            s
        })
        .collect()
}

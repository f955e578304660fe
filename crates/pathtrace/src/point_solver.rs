//! Path tracing as a stepped method: the per-point estimator (point_estimator.rs; B(x) = E(x) + ρ(x) H(x)
//! with next-event estimation and MIS, Veach 1997) run at a fixed set of query points, each
//! [`Solver::step`] adding paths to every point: `initial_samples` in the first step, then as many as the
//! points already have (doubling), until `samples` paths per point. The error of the mean falls as
//! 1/√paths, so a trace of error against time has slope −1/2 on log axes.
//!
//! A path tracer answers only where it has traced, so it is built with its query points (the runner hands
//! it the experiment's evaluation points, `probe` its input points). Its [`Solution`] returns the running
//! mean at those points (matched by face and exact coordinates) and, at any other point, a fresh estimate
//! with as many paths as the points have (a stream derived from the seed and the point's coordinates, so it
//! is reproducible). The cost of answering is in the steps: time and rays grow linearly with the number of
//! points, where a finite-element method pays for the whole scene once.
//!
//! Random streams: step k's chunk c of point i draws from stream (i, global chunk index) of
//! mix64(seed ^ [`METHOD_STREAM_TAG`]), so the method never reuses the reference estimator's streams, even
//! with the same seed, and the answer is bit-identical for any number of threads. Rays are counted through the
//! shared [`Accel`]'s counter around each step.

use std::collections::HashMap;

use glam::DVec3;
use radlab_method::{MethodParams, Solution, SolveError, Solver, Stats, Step};
use radlab_scene::{FaceId, Rgb, Scene, sampling::mix64};
use radlab_visibility::Accel;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::path_estimator::{DirectSampling, PathEstimator};
use crate::point_estimator::{
    DEFAULT_MAX_DEPTH, PointEstimate, PointParams, SAMPLES_PER_CHUNK, SurfacePoint,
    estimate_points, sample_points,
};
use crate::running_stats::RunningStats;

/// Mixed into the seed so the method's streams differ from the reference estimator's.
pub const METHOD_STREAM_TAG: u64 = 0x7061_7468_7472_6163; // "pathtrac"

/// Parameters of path tracing as a method, each declared once on its field (doc comment: help; `schemars`
/// attribute: range; default: `impl Default`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct PathTraceParams {
    /// Paths per point when the method stops; the standard error falls as 1/√samples (2 or more give a
    /// standard error).
    #[schemars(range(min = 1))]
    pub samples: u32,
    /// Paths per point added by the first step, at most samples; each later step doubles the paths.
    #[schemars(range(min = 1))]
    pub initial_samples: u32,
    /// Cap on path segments (1: direct light only); Russian roulette ends paths without bias.
    #[schemars(range(min = 1))]
    pub max_depth: u32,
    /// How direct light is sampled at each path vertex: mis (next-event and hemisphere sampling, power
    /// heuristic), next-event or hemisphere.
    pub direct: DirectSampling,
}

impl Default for PathTraceParams {
    fn default() -> Self {
        Self {
            samples: 1024,
            initial_samples: 16,
            max_depth: DEFAULT_MAX_DEPTH,
            direct: DirectSampling::Mis,
        }
    }
}

impl MethodParams for PathTraceParams {
    fn check_combination(&self) -> Result<(), SolveError> {
        if self.initial_samples > self.samples {
            return Err(SolveError::param(
                "initial_samples",
                format!(
                    "{} must be between 1 and samples ({})",
                    self.initial_samples, self.samples
                ),
            ));
        }
        Ok(())
    }
}

/// Path tracing at a fixed set of points, advanced by doubling the paths per point.
pub struct PathTraceSolver<'a> {
    scene: &'a Scene,
    accel: &'a Accel,
    params: PathTraceParams,
    seed: u64,
    points: Vec<SurfacePoint>,
    index: HashMap<(FaceId, [u64; 3]), usize>,
    stats: Vec<RunningStats>,
    /// Paths per point so far.
    samples: u32,
    /// Chunks per point drawn so far (the next chunk's stream index).
    chunks: u64,
    steps: u64,
    rays: u64,
}

impl std::fmt::Debug for PathTraceSolver<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PathTraceSolver")
            .field("points", &self.points.len())
            .field("samples", &self.samples)
            .field("params", &self.params)
            .finish()
    }
}

fn point_key(face: FaceId, p: DVec3) -> (FaceId, [u64; 3]) {
    (face, [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
}

impl<'a> PathTraceSolver<'a> {
    /// Path tracing at `points` (no paths yet: the first step traces `initial_samples` per point).
    pub fn new(
        scene: &'a Scene,
        accel: &'a Accel,
        params: PathTraceParams,
        seed: u64,
        points: Vec<SurfacePoint>,
    ) -> Result<Self, SolveError> {
        params.validate()?;
        if let Some((i, p)) = points
            .iter()
            .enumerate()
            .find(|(_, p)| p.face >= scene.faces.len())
        {
            return Err(SolveError::param(
                "points",
                format!(
                    "point {i} names face {} but the scene has {} faces",
                    p.face,
                    scene.faces.len()
                ),
            ));
        }
        let index = points
            .iter()
            .enumerate()
            .map(|(i, p)| (point_key(p.face, p.point), i))
            .collect();
        Ok(Self {
            scene,
            accel,
            seed: mix64(seed ^ METHOD_STREAM_TAG),
            stats: vec![RunningStats::default(); points.len()],
            points,
            index,
            params,
            samples: 0,
            chunks: 0,
            steps: 0,
            rays: 0,
        })
    }

    /// Paths per point so far.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// The query points.
    pub fn points(&self) -> &[SurfacePoint] {
        &self.points
    }

    /// Mean and standard error at every query point, in their order.
    pub fn estimates(&self) -> Vec<PointEstimate> {
        self.stats
            .iter()
            .map(|s| PointEstimate {
                mean: s.mean(),
                std_error: s.std_error(),
            })
            .collect()
    }

    /// The estimate at a query point, if it is one.
    pub fn estimate_at(&self, face: FaceId, point: DVec3) -> Option<PointEstimate> {
        self.index
            .get(&point_key(face, point))
            .map(|&i| PointEstimate {
                mean: self.stats[i].mean(),
                std_error: self.stats[i].std_error(),
            })
    }

    /// Paths the next step adds per point.
    fn next_batch(&self) -> u32 {
        let want = if self.samples == 0 {
            self.params.initial_samples
        } else {
            self.samples
        };
        want.min(self.params.samples - self.samples)
    }
}

impl Solver for PathTraceSolver<'_> {
    fn step(&mut self) -> Result<Step, SolveError> {
        let batch = self.next_batch();
        if batch == 0 {
            return Ok(Step::Converged);
        }
        let chunks = batch.div_ceil(SAMPLES_PER_CHUNK) as usize;
        let estimator = PathEstimator::new(
            self.scene,
            self.accel,
            self.params.max_depth,
            self.params.direct,
        );
        let rays0 = self.accel.rays_cast();
        let batch_stats = sample_points(
            &estimator,
            &self.points,
            batch,
            self.chunks,
            self.seed,
            &|_| {},
        );
        for (s, b) in self.stats.iter_mut().zip(&batch_stats) {
            s.merge(b);
        }
        self.rays += self.accel.rays_cast() - rays0;
        self.chunks += chunks as u64;
        self.samples += batch;
        self.steps += 1;
        if self.stats.iter().any(|s| !s.mean().is_finite()) {
            return Err(SolveError::Numerical(
                "a path produced a non-finite radiosity".into(),
            ));
        }
        Ok(if self.samples >= self.params.samples {
            Step::Converged
        } else {
            Step::Continue
        })
    }

    fn solution(&self) -> &dyn Solution {
        self
    }

    fn stats(&self) -> Stats {
        Stats {
            steps: self.steps,
            elements: 0,
            links: 0,
            form_factors: 0,
            rays: self.rays,
            bytes: (self.points.capacity() * size_of::<SurfacePoint>()
                + self.stats.capacity() * size_of::<RunningStats>()
                + self.index.capacity() * (size_of::<(FaceId, [u64; 3])>() + 8))
                as u64,
            residual: None,
        }
    }
}

impl Solution for PathTraceSolver<'_> {
    /// The running mean at a query point; elsewhere a fresh estimate with the paths per point so far (at least
    /// `initial_samples`), from a stream keyed by the point.
    fn radiosity_at(&self, face: FaceId, point: DVec3) -> Rgb {
        if let Some(e) = self.estimate_at(face, point) {
            return e.mean;
        }
        if face >= self.scene.faces.len() {
            return Rgb::splat(f64::NAN);
        }
        let key = mix64(
            point.x.to_bits() ^ mix64(point.y.to_bits() ^ mix64(point.z.to_bits() ^ face as u64)),
        );
        let params = PointParams {
            samples: self.samples.max(self.params.initial_samples),
            max_depth: self.params.max_depth,
            direct: self.params.direct,
        };
        let p = [SurfacePoint {
            face,
            point,
            normal: self.scene.faces[face].normal,
        }];
        estimate_points(self.scene, self.accel, &p, &params, mix64(self.seed ^ key))[0].mean
    }
}

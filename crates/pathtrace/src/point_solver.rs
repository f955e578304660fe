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

use glam::DVec3;
use radlab_method::{MethodParams, Solution, SolveError, Solver, Stats, Step};
use radlab_scene::{FaceId, Rgb, Scene, sampling::mix64};
use radlab_visibility::Accel;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::path_estimator::{DirectSampling, PathEstimator};
use crate::point_estimator::{
    DEFAULT_MAX_DEPTH, PointEstimate, PointSampler, SAMPLES_PER_CHUNK, SurfacePoint, sample_points,
};
use crate::query_points::{QueryPoints, coordinate_hash};
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
        SteppedPoints::check_schedule(self.initial_samples, self.samples)
    }
}

/// Running estimates at a fixed set of query points, advanced by doubling the samples per point: the schedule,
/// random streams, statistics and counts that every per-point sampler stepped as a method shares (path tracing
/// here, bidirectional path tracing in radlab-bdpt). Step k's chunk c of point i draws from stream
/// (i, global chunk index) of the seed given, so results do not depend on the thread count.
#[derive(Clone, Debug)]
pub struct SteppedPoints {
    points: QueryPoints,
    stats: Vec<RunningStats>,
    seed: u64,
    initial_samples: u32,
    target: u32,
    /// Samples per point so far.
    samples: u32,
    /// Chunks per point drawn so far (the next chunk's stream index).
    chunks: u64,
    steps: u64,
    rays: u64,
}

impl SteppedPoints {
    /// No samples yet at `points`: the first step draws `initial_samples` per point from streams of `seed`,
    /// each later one as many as the points have, until `samples` per point.
    pub fn new(points: QueryPoints, seed: u64, initial_samples: u32, samples: u32) -> Self {
        Self {
            stats: vec![RunningStats::default(); points.len()],
            points,
            seed,
            initial_samples,
            target: samples,
            samples: 0,
            chunks: 0,
            steps: 0,
            rays: 0,
        }
    }

    /// Checks a schedule's parameters: `initial_samples` (the key named in the error) must not exceed
    /// `samples`.
    pub fn check_schedule(initial_samples: u32, samples: u32) -> Result<(), SolveError> {
        if initial_samples > samples {
            return Err(SolveError::param(
                "initial_samples",
                format!("{initial_samples} must be between 1 and samples ({samples})"),
            ));
        }
        Ok(())
    }

    /// Samples per point so far.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// Samples for a fresh estimate off the query set: as many as the points have, at least
    /// `initial_samples`.
    pub fn fresh_samples(&self) -> u32 {
        self.samples.max(self.initial_samples)
    }

    /// The seed the points' streams derive from.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// The query points.
    pub fn points(&self) -> &[SurfacePoint] {
        self.points.points()
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
        self.points.find(face, point).map(|i| PointEstimate {
            mean: self.stats[i].mean(),
            std_error: self.stats[i].std_error(),
        })
    }

    /// Samples the next step adds per point.
    fn next_batch(&self) -> u32 {
        let want = if self.samples == 0 {
            self.initial_samples
        } else {
            self.samples
        };
        want.min(self.target - self.samples)
    }

    /// Adds the next batch of `sample` draws at every point, counting the rays cast through `accel`.
    pub fn step(&mut self, accel: &Accel, sample: &PointSampler) -> Result<Step, SolveError> {
        let batch = self.next_batch();
        if batch == 0 {
            return Ok(Step::Converged);
        }
        let chunks = batch.div_ceil(SAMPLES_PER_CHUNK) as usize;
        let rays0 = accel.rays_cast();
        let batch_stats = sample_points(
            self.points.points(),
            batch,
            self.chunks,
            self.seed,
            &|_| {},
            sample,
        );
        for (s, b) in self.stats.iter_mut().zip(&batch_stats) {
            s.merge(b);
        }
        self.rays += accel.rays_cast() - rays0;
        self.chunks += chunks as u64;
        self.samples += batch;
        self.steps += 1;
        if self.stats.iter().any(|s| !s.mean().is_finite()) {
            return Err(SolveError::Numerical(
                "a path produced a non-finite radiosity".into(),
            ));
        }
        Ok(if self.samples >= self.target {
            Step::Converged
        } else {
            Step::Continue
        })
    }

    /// The answer at (`face`, `point`): the running mean at a query point; elsewhere the mean of
    /// [`SteppedPoints::fresh_samples`] draws of `sample` at the point (on the face's front) from the streams of
    /// mix64(seed ⊕ [`coordinate_hash`]), reproducible in any order; NaN on a face the scene lacks.
    pub fn radiosity_at(
        &self,
        scene: &Scene,
        face: FaceId,
        point: DVec3,
        sample: &PointSampler,
    ) -> Rgb {
        if let Some(e) = self.estimate_at(face, point) {
            return e.mean;
        }
        if face >= scene.faces.len() {
            return Rgb::splat(f64::NAN);
        }
        let p = [SurfacePoint {
            face,
            point,
            normal: scene.faces[face].normal,
        }];
        let seed = mix64(self.seed ^ coordinate_hash(face, point));
        sample_points(&p, self.fresh_samples(), 0, seed, &|_| {}, sample)[0].mean()
    }

    /// Steps, rays and bytes so far (no elements, links or form factors).
    pub fn stats(&self) -> Stats {
        Stats {
            steps: self.steps,
            elements: 0,
            links: 0,
            form_factors: 0,
            rays: self.rays,
            bytes: (self.points.bytes() + self.stats.capacity() * size_of::<RunningStats>()) as u64,
            residual: None,
        }
    }
}

/// Path tracing at a fixed set of points, advanced by doubling the paths per point.
pub struct PathTraceSolver<'a> {
    scene: &'a Scene,
    accel: &'a Accel,
    params: PathTraceParams,
    runs: SteppedPoints,
    /// Built once: its emitter distribution costs O(faces), which answering per point must not pay again.
    estimator: PathEstimator<'a>,
}

impl std::fmt::Debug for PathTraceSolver<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PathTraceSolver")
            .field("points", &self.runs.points().len())
            .field("samples", &self.runs.samples())
            .field("params", &self.params)
            .finish()
    }
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
        let runs = SteppedPoints::new(
            QueryPoints::new(scene, points)?,
            mix64(seed ^ METHOD_STREAM_TAG),
            params.initial_samples,
            params.samples,
        );
        Ok(Self {
            scene,
            accel,
            estimator: PathEstimator::new(scene, accel, params.max_depth, params.direct),
            params,
            runs,
        })
    }

    /// Paths per point so far.
    pub fn samples(&self) -> u32 {
        self.runs.samples()
    }

    /// The query points.
    pub fn points(&self) -> &[SurfacePoint] {
        self.runs.points()
    }

    /// Mean and standard error at every query point, in their order.
    pub fn estimates(&self) -> Vec<PointEstimate> {
        self.runs.estimates()
    }

    /// The estimate at a query point, if it is one.
    pub fn estimate_at(&self, face: FaceId, point: DVec3) -> Option<PointEstimate> {
        self.runs.estimate_at(face, point)
    }
}

impl Solver for PathTraceSolver<'_> {
    fn step(&mut self) -> Result<Step, SolveError> {
        let estimator = &self.estimator;
        self.runs.step(self.accel, &|p, rng| {
            estimator.radiosity(p.face, p.point, p.normal, rng)
        })
    }

    fn solution(&self) -> &dyn Solution {
        self
    }

    fn stats(&self) -> Stats {
        self.runs.stats()
    }
}

impl Solution for PathTraceSolver<'_> {
    /// The running mean at a query point; elsewhere a fresh estimate with the paths per point so far (at least
    /// `initial_samples`), from a stream keyed by the point.
    fn radiosity_at(&self, face: FaceId, point: DVec3) -> Rgb {
        self.runs.radiosity_at(self.scene, face, point, &|p, rng| {
            self.estimator.radiosity(p.face, p.point, p.normal, rng)
        })
    }
}

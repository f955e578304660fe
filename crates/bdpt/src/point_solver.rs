//! Bidirectional path tracing as a stepped method: the estimator of bidirectional_estimator.rs (B(x) = E(x) +
//! ρ(x) H(x), light and eye subpaths joined by every strategy and weighted by MIS; Veach 1997, ch. 10) run at
//! a fixed set of query points, each [`Solver::step`] adding samples to every point: `initial_samples`, then
//! as many as the points have (doubling), until `samples` per point. The error of the mean falls as
//! 1/√samples.
//!
//! The schedule, streams and counts are radlab-pathtrace's [`SteppedPoints`]: step k's chunk c of point i
//! draws from stream (i, global chunk index) of mix64(seed ⊕ [`BDPT_STREAM_TAG`]), so results are
//! bit-identical for any number of threads and never reuse the path tracer's streams. At a point off the
//! query set (an image's pixels, a probe) the answer is a fresh estimate from a stream keyed by the point.
//! Rays are counted through the shared [`Accel`]'s counter around each step; bytes are the points, their
//! index and running statistics (subpaths live on the stack of one sample).

use glam::DVec3;
use radlab_method::{MethodParams, Solution, SolveError, Solver, Stats, Step};
use radlab_pathtrace::{PointEstimate, QueryPoints, SteppedPoints, SurfacePoint};
use radlab_scene::{FaceId, Rgb, Scene, sampling::mix64};
use radlab_visibility::Accel;

use crate::bidirectional_estimator::BidirectionalEstimator;
use crate::params::BdptParams;

/// Mixed into the seed so the method's streams differ from every other method's.
pub const BDPT_STREAM_TAG: u64 = 0x6269_6469_7270_6174; // "bidirpat"

/// Bidirectional path tracing at a fixed set of points, advanced by doubling the samples per point.
pub struct BdptSolver<'a> {
    scene: &'a Scene,
    accel: &'a Accel,
    params: BdptParams,
    runs: SteppedPoints,
    /// Built once: its emitter distribution costs O(faces), which answering per point must not pay again.
    estimator: BidirectionalEstimator<'a>,
}

impl std::fmt::Debug for BdptSolver<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BdptSolver")
            .field("points", &self.runs.points().len())
            .field("samples", &self.runs.samples())
            .field("params", &self.params)
            .finish()
    }
}

impl<'a> BdptSolver<'a> {
    /// Bidirectional path tracing at `points` (nothing traced yet); an error naming the key for bad
    /// parameters or points off the scene.
    pub fn new(
        scene: &'a Scene,
        accel: &'a Accel,
        params: BdptParams,
        seed: u64,
        points: Vec<SurfacePoint>,
    ) -> Result<Self, SolveError> {
        params.validate()?;
        let runs = SteppedPoints::new(
            QueryPoints::new(scene, points)?,
            mix64(seed ^ BDPT_STREAM_TAG),
            params.initial_samples,
            params.samples,
        );
        let estimator = BidirectionalEstimator::new(
            scene,
            accel,
            params.max_depth,
            params.max_light_vertices,
            params.heuristic,
        );
        Ok(Self {
            scene,
            accel,
            params,
            runs,
            estimator,
        })
    }

    /// Samples per point so far.
    pub fn samples(&self) -> u32 {
        self.runs.samples()
    }

    /// Mean and standard error at every query point, in their order.
    pub fn estimates(&self) -> Vec<PointEstimate> {
        self.runs.estimates()
    }
}

impl Solver for BdptSolver<'_> {
    fn step(&mut self) -> Result<Step, SolveError> {
        let estimator = &self.estimator;
        self.runs
            .step(self.accel, &|p, rng| estimator.radiosity(p, rng))
    }

    fn solution(&self) -> &dyn Solution {
        self
    }

    fn stats(&self) -> Stats {
        self.runs.stats()
    }
}

impl Solution for BdptSolver<'_> {
    /// The running mean at a query point; elsewhere a fresh estimate with the samples per point so far (at
    /// least `initial_samples`), from a stream keyed by the point.
    fn radiosity_at(&self, face: FaceId, point: DVec3) -> Rgb {
        self.runs.radiosity_at(self.scene, face, point, &|p, rng| {
            self.estimator.radiosity(p, rng)
        })
    }
}

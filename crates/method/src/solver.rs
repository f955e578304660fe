//! The two traits every method meets the runner at: a [`Solution`] answers radiosity at a
//! surface point; a [`Solver`] advances one unit of work per [`Solver::step`] so the runner can time, trace and
//! stop it. Solvers never print, write files or read the clock for reports.

use glam::DVec3;

use crate::SolveError;
use radlab_scene::{FaceId, Rgb};

/// A view-independent diffuse solution over the scene's surfaces.
pub trait Solution: Sync {
    /// Radiosity leaving `face` at `point` (W/m², linear RGB), as this method represents it.
    fn radiosity_at(&self, face: FaceId, point: DVec3) -> Rgb;

    /// Kernel evaluations (point-to-polygon factors and the like) spent answering queries so far: a final
    /// gather's work, which [`Stats::form_factors`] (solving only) leaves out. Zero for a method that answers
    /// without evaluating kernels.
    fn answer_kernel_evaluations(&self) -> u64 {
        0
    }
}

/// What a step achieved.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// More work would change the answer.
    Continue,
    /// The method's own stopping rule is met; further steps do nothing.
    Converged,
    /// The method's own cap on its work (matrix `max_iterations`, progressive `max_shots`, the hierarchical
    /// engine's `max_steps`) was reached before its stopping rule was met; further steps do nothing. Not a
    /// convergence: reports say so.
    Capped,
}

/// Counters a solver reports after any step. Zero where a method has no such thing.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stats {
    /// Steps taken.
    pub steps: u64,
    /// Elements (leaves of the solution's representation).
    pub elements: u64,
    /// Links or matrix entries held.
    pub links: u64,
    /// Form factors computed (each quadrature of a pair counts once).
    pub form_factors: u64,
    /// Rays cast by this solver.
    pub rays: u64,
    /// Bytes of memory the solver holds (its own data, not the scene or the BVH), including what its solution
    /// has built to answer queries (a reconstruction's data).
    pub bytes: u64,
    /// The method's own residual or remaining-energy measure (relative), if it has one.
    pub residual: Option<f64>,
}

/// One method, advanced one unit of work at a time.
pub trait Solver: Send {
    /// Does one unit of work.
    fn step(&mut self) -> Result<Step, SolveError>;
    /// The current solution.
    fn solution(&self) -> &dyn Solution;
    /// Counters after the steps so far.
    fn stats(&self) -> Stats;
    /// The method's own counters beyond [`Stats`], by name (an irradiance cache's records and the query points
    /// it answered by interpolation, say); none by default. The runner writes them to `runs.csv`.
    fn counters(&self) -> Vec<(&'static str, u64)> {
        Vec::new()
    }
}

/// A solution that is constant per face (used for tests, and by methods whose elements are whole faces).
#[derive(Clone, Debug)]
pub struct PerFaceSolution {
    /// Radiosity per face.
    pub radiosity: Vec<Rgb>,
}

impl Solution for PerFaceSolution {
    fn radiosity_at(&self, face: FaceId, _point: DVec3) -> Rgb {
        self.radiosity[face]
    }
}

//! # radlab-method
//!
//! What every radlab method meets the runner at: the [`Solver`] and [`Solution`] traits (one unit of work per
//! step, an answer at any surface point), the counters a method reports ([`Stats`]), typed parameters set
//! from `key=value` pairs or TOML ([`MethodParams`]), the errors that stop a method ([`SolveError`]), the
//! evaluation points every method is measured at and the error metric it is measured by. Nothing in this
//! crate prints, reads the clock or writes files.

pub mod error;
pub mod error_metric;
pub mod eval_points;
pub mod params;
pub mod solver;

pub use error::SolveError;
pub use eval_points::{EvalPoint, evaluation_points};
pub use params::{MethodParams, ParamDecl};
pub use solver::{PerFaceSolution, Solution, Solver, Stats, Step};

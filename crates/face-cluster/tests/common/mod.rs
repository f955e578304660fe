//! Helpers shared by the face-cluster integration tests: parameters from key/value pairs and a solve to
//! convergence.
// Each test file compiles this module on its own and uses part of it.
#![allow(dead_code)]

use radlab_face_cluster::{FaceClusterSolveParams, FaceClusterSolver};
use radlab_method::{MethodParams, SolveError, Solver, Step};

/// The parameters `pairs` give (values as in experiment files), or the error they raise.
pub fn try_params(pairs: &[(&str, &str)]) -> Result<FaceClusterSolveParams, SolveError> {
    let pairs: Vec<(String, String)> = pairs
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    FaceClusterSolveParams::from_pairs(&pairs)
}

/// The parameters `pairs` give, which must be valid.
pub fn params(pairs: &[(&str, &str)]) -> FaceClusterSolveParams {
    try_params(pairs).expect("valid parameters")
}

/// Steps `s` until it stops (at most 500 steps).
pub fn solve(s: &mut FaceClusterSolver<'_>) {
    for _ in 0..500 {
        if s.step().expect("step") != Step::Continue {
            return;
        }
    }
    panic!("no convergence in 500 steps");
}

//! Parameters of matrix radiosity, with their documented defaults and range checks. Set from `key=value`
//! pairs (`--set iteration=conjugate-gradient`) or a TOML table through [`MethodParams`]; every error names
//! the parameter.

use radlab_answer::{AnswerParams, Reconstruction};
use radlab_kernels::form_factor::VisibilitySampling;
use radlab_method::{MethodParams, SolveError};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// How the linear system (I − ρF) B = E is solved.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum Iteration {
    /// Jacobi: every element gathers from the previous iterate (rows in parallel). Error shrinks by about the
    /// spectral radius of ρF (≤ ρ_max) per iteration.
    Jacobi,
    /// Gauss–Seidel: elements gather in order, each from the newest values (sequential). Roughly twice as fast
    /// as Jacobi per iteration count; the classic choice of Cohen & Greenberg (1985). The default.
    #[default]
    GaussSeidel,
    /// Conjugate gradient on the symmetric form (A_i/ρ_i) B_i − Σ_j A_i F_ij B_j = A_i E_i/ρ_i, preconditioned
    /// by its diagonal (rows in parallel). Iterations grow like 1/√(1 − ρ) instead of 1/(1 − ρ): far fewer
    /// at high reflectance.
    ConjugateGradient,
}

/// Default target relative error of B (see [`MatrixParams::tolerance`]).
pub const DEFAULT_TOLERANCE: f64 = 1e-4;
/// Default cap on iterations.
pub const DEFAULT_MAX_ITERATIONS: usize = 100_000;
/// Default receiver quadrature points per axis (2 × 2 points per element).
pub const DEFAULT_QUADRATURE: u32 = 2;
/// Default memory budget for the matrix and the solver's vectors, MiB.
pub const DEFAULT_MEMORY_BUDGET_MIB: f64 = 2048.0;
/// Largest accepted quadrature order per axis.
pub const MAX_QUADRATURE: u32 = 16;

/// Parameters of [`crate::MatrixSolver`], each declared once: its doc comment's first paragraph is the help
/// `radlab methods` prints, its `schemars` attribute the accepted range, and its default is in `impl Default`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct MatrixParams {
    /// Longest element edge in scene units; unset: 1/25 of the scene's bounding-box diagonal
    /// (`radlab_answer::default_element_size`, about 1,700 elements in the Cornell box).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub element_size: Option<f64>,
    /// The iterative solver of (I − ρF) B = E: jacobi, gauss-seidel or conjugate-gradient.
    pub iteration: Iteration,
    /// Target relative error of B in the area-weighted L1 norm.
    ///
    /// Iteration stops when the relative residual falls below `tolerance × (1 − ρ_max)` per channel, which
    /// bounds the error by `tolerance` (‖(I − ρF)⁻¹‖ ≤ 1/(1 − ρ_max) for a reciprocal F with row sums ≤ 1).
    #[schemars(extend("exclusiveMinimum" = 0, "exclusiveMaximum" = 1))]
    pub tolerance: f64,
    /// Cap on iterations; reaching it stops the solver (reported by `MatrixSolver::hit_iteration_cap`).
    #[schemars(range(min = 1))]
    pub max_iterations: usize,
    /// Visibility rays per element pair; the jittered grids also give each element its open share (128 rays:
    /// the part not sealed under a touching panel).
    pub visibility: VisibilitySampling,
    /// Receiver quadrature points per axis for the point-to-polygon kernel (m × m points per element).
    #[schemars(range(min = 1, max = MAX_QUADRATURE))]
    pub quadrature: u32,
    /// Memory the n × n matrix and the solver's vectors may take, MiB; larger problems are refused before
    /// allocating.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub memory_budget_mib: f64,
    /// How points are answered: reconstruction and gather_opening, declared once in radlab-answer.
    #[serde(flatten)]
    pub answer: AnswerParams,
}

/// Default reconstruction of point answers, chosen by measurement (see the crate documentation).
pub const DEFAULT_RECONSTRUCTION: Reconstruction = Reconstruction::FinalGather;

impl Default for MatrixParams {
    fn default() -> Self {
        Self {
            element_size: None,
            iteration: Iteration::default(),
            tolerance: DEFAULT_TOLERANCE,
            max_iterations: DEFAULT_MAX_ITERATIONS,
            visibility: VisibilitySampling::Jittered4x4,
            quadrature: DEFAULT_QUADRATURE,
            memory_budget_mib: DEFAULT_MEMORY_BUDGET_MIB,
            answer: AnswerParams {
                reconstruction: DEFAULT_RECONSTRUCTION,
                ..AnswerParams::default()
            },
        }
    }
}

impl MethodParams for MatrixParams {
    /// An opening other than the default is refused under answers other than a final gather.
    fn check_combination(&self) -> Result<(), SolveError> {
        self.answer.check(&Self::default().answer)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pairs(kv: &[(&str, &str)]) -> Vec<(String, String)> {
        kv.iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
    }

    #[test]
    fn parses_kebab_case_choices() {
        let p = MatrixParams::from_pairs(&pairs(&[
            ("iteration", "conjugate-gradient"),
            ("visibility", "jittered2x2"),
            ("element_size", "0.05"),
        ]))
        .expect("valid");
        assert_eq!(p.iteration, Iteration::ConjugateGradient);
        assert_eq!(p.visibility, VisibilitySampling::Jittered2x2);
        assert_eq!(p.element_size, Some(0.05));
        let p = MatrixParams::from_pairs(&pairs(&[("iteration", "gauss-seidel")])).expect("valid");
        assert_eq!(p.iteration, Iteration::GaussSeidel);
        let p = MatrixParams::from_pairs(&pairs(&[("iteration", "jacobi")])).expect("valid");
        assert_eq!(p.iteration, Iteration::Jacobi);
        assert_eq!(
            MatrixParams::from_pairs(&[]).expect("defaults"),
            MatrixParams::default()
        );
    }

    #[test]
    fn bad_values_name_the_parameter() {
        for (k, v) in [
            ("element_size", "0"),
            ("element_size", "-1"),
            ("tolerance", "0"),
            ("tolerance", "2"),
            ("max_iterations", "0"),
            ("quadrature", "0"),
            ("quadrature", "17"),
            ("memory_budget_mib", "0"),
            ("iteration", "sor"),
            ("visibility", "lots"),
            ("reconstruction", "smooth"),
        ] {
            let e = MatrixParams::from_pairs(&pairs(&[(k, v)]))
                .expect_err("invalid")
                .to_string();
            assert!(e.contains(k), "{k}={v}: {e}");
        }
        let e = MatrixParams::from_pairs(&pairs(&[("elementsize", "1")]))
            .expect_err("unknown")
            .to_string();
        assert!(e.contains("elementsize"), "{e}");
    }

    #[test]
    fn defaults_are_listed() {
        let d = MatrixParams::declarations();
        for name in [
            "iteration",
            "tolerance",
            "quadrature",
            "visibility",
            "reconstruction",
            "gather_opening",
            "near_values",
        ] {
            assert!(d.iter().any(|p| p.name == name), "{name} missing: {d:?}");
        }
        let decls = MatrixParams::declarations();
        assert_eq!(decls.len(), 10);
    }
}

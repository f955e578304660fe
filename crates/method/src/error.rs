//! Errors that stop a method: a bad parameter (named, with the accepted values), a memory budget too small
//! for the work asked, a numerical failure, or a problem with the scene. Each names what is wrong and the fix.

use radlab_scene::SceneError;

/// Something that stops a solver.
#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    /// A parameter is unknown or out of range.
    #[error("parameter '{name}': {message}")]
    Parameter {
        /// The parameter's name.
        name: String,
        /// What is wrong and what values are accepted.
        message: String,
    },
    /// The method would need more memory than its budget allows.
    #[error(
        "{what} needs {needed_bytes} bytes ({needed_mib:.1} MiB) but the memory budget is {budget_bytes} bytes; {hint}"
    )]
    OverBudget {
        /// What is too large.
        what: String,
        /// Bytes it needs.
        needed_bytes: u64,
        /// Same in MiB.
        needed_mib: f64,
        /// The budget.
        budget_bytes: u64,
        /// How to fix it.
        hint: String,
    },
    /// The computation produced a non-finite or otherwise unusable result.
    #[error("numerical failure: {0}")]
    Numerical(String),
    /// A problem with the scene.
    #[error(transparent)]
    Scene(#[from] SceneError),
}

impl SolveError {
    /// A parameter error.
    pub fn param(name: &str, message: impl Into<String>) -> Self {
        Self::Parameter {
            name: name.into(),
            message: message.into(),
        }
    }

    /// An over-budget error for `needed` bytes against `budget` bytes.
    pub fn over_budget(what: &str, needed: u64, budget: u64, hint: &str) -> Self {
        Self::OverBudget {
            what: what.into(),
            needed_bytes: needed,
            needed_mib: needed as f64 / (1024.0 * 1024.0),
            budget_bytes: budget,
            hint: hint.into(),
        }
    }
}

//! Build parameters of a face-cluster hierarchy: the weights of Garland, Willmott & Heckbert's (2001) three
//! merge-cost terms, the number of visibility sample points per node and their seed.
//!
//! The cost of merging regions R₁ and R₂ into R (see [`crate::contraction`]) is
//! w_fit · E_fit + w_dir · E_dir + w_shape · E_shape + w_bal · E_bal, every term dimensionless so the merge order does not
//! change when the scene is scaled.

use serde::{Deserialize, Serialize};

use crate::FaceClusterError;

/// How a face-cluster hierarchy is built. Defaults: all four weights 1, 4 samples per node, seed 1.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", default, deny_unknown_fields)]
pub struct FaceClusterParams {
    /// Weight of planarity, E_fit = (mean squared distance of the region's vertices to their least-squares
    /// plane) / (mean face area of its mesh part). Default 1.
    pub planarity_weight: f64,
    /// Weight of orientation, E_dir = Σ A_f (1 − n̄·n_f)² / Σ A_f with n̄ the region's mean normal. Default 1.
    pub orientation_weight: f64,
    /// Weight of shape, E_shape = 1 − max(γ₁, γ₂)/γ with γ = perimeter²/area (negative when the merged
    /// region is more compact than its rounder part). Default 1.
    pub shape_weight: f64,
    /// Weight of balance, E_bal = |A₁ − A₂| / (A₁ + A₂): radlab's addition to Garland's terms, so regions grow
    /// in step instead of one region taking in its neighbours a face at a time (a deep tree, and a slower
    /// contraction). 0 gives Garland's cost alone. Default 1.
    pub balance_weight: f64,
    /// Representative points per node for visibility rays, 1..=64. Default 4.
    pub samples_per_node: usize,
    /// Seed of the sample points. Default 1.
    pub seed: u64,
}

impl Default for FaceClusterParams {
    fn default() -> Self {
        Self {
            planarity_weight: 1.0,
            orientation_weight: 1.0,
            shape_weight: 1.0,
            balance_weight: 1.0,
            samples_per_node: 4,
            seed: 1,
        }
    }
}

impl FaceClusterParams {
    /// Largest `samples_per_node`.
    pub const MAX_SAMPLES_PER_NODE: usize = 64;

    /// Checks every field.
    pub fn validate(&self) -> Result<(), FaceClusterError> {
        for (field, w) in [
            ("planarity-weight", self.planarity_weight),
            ("orientation-weight", self.orientation_weight),
            ("shape-weight", self.shape_weight),
            ("balance-weight", self.balance_weight),
        ] {
            if !(w.is_finite() && w >= 0.0) {
                return Err(FaceClusterError::InvalidParams {
                    field,
                    message: format!("{w} is not a finite weight >= 0 (the default is 1)"),
                });
            }
        }
        if !(1..=Self::MAX_SAMPLES_PER_NODE).contains(&self.samples_per_node) {
            return Err(FaceClusterError::InvalidParams {
                field: "samples-per-node",
                message: format!(
                    "{} is outside 1..={} (the default is 4)",
                    self.samples_per_node,
                    Self::MAX_SAMPLES_PER_NODE
                ),
            });
        }
        Ok(())
    }
}

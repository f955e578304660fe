//! The irradiance cache's parameters, in Radiance's terms (Ward 1994, "The RADIANCE lighting simulation and
//! rendering system"; rtrace's -aa, -ad, -ar): the accuracy a, hemisphere samples per record, and the bounds
//! on a record's radius, here as fractions of the scene's diagonal so that they do not depend on its scale.

use radlab_method::{MethodParams, SolveError};
use radlab_pathtrace::{DEFAULT_MAX_DEPTH, DirectSampling};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Parameters of the irradiance cache. Each field is declared once: its doc comment's first paragraph is the
/// help `radlab methods` prints, its `schemars` attribute the accepted range, and its default is in
/// `impl Default`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct IrradianceCacheParams {
    /// Accuracy a (Radiance's -aa): a record is used at x when Ward's error ε = ‖x − x_i‖/R_i + √(1 − n·n_i)
    /// is below a; records grow as a⁻², and 0 turns caching off (every query point gathers its own record).
    #[schemars(range(min = 0, max = 1))]
    pub accuracy: f64,
    /// Hemisphere directions gathered per record (Radiance's -ad), stratified in M × N ≈ samples cells,
    /// M = round(√(samples/π)), each continued by a path to termination (Russian roulette).
    #[schemars(range(min = 1))]
    pub samples: u32,
    /// Smallest record radius R as a fraction of the scene's diagonal (Radiance's -ar gives it as scene size
    /// / ar).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub min_radius: f64,
    /// Largest record radius R as a fraction of the scene's diagonal; at least `min_radius`.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub max_radius: f64,
    /// Direct-light samples per answered point: each a next-event shadow ray and, under `mis`, a
    /// cosine-distributed ray, combined by the power heuristic (radlab-pathtrace's estimator).
    #[schemars(range(min = 1))]
    pub direct_samples: u32,
    /// Use Ward & Heckbert's rotational and translational gradients when interpolating.
    pub gradients: bool,
    /// Křivánek et al.'s (2006) neighbour clamping, R_i ≤ R_j + ‖x_i − x_j‖ both ways on insertion.
    pub neighbour_clamp: bool,
    /// Cast a ray between a record and the point it would serve, and skip the record if the ray is blocked:
    /// no light leaks through thin walls, one ray per record used.
    pub leak_test: bool,
    /// Cap on the segments of the paths that continue each gather ray (Russian roulette ends them without
    /// bias; 1 = one bounce after each gather ray).
    #[schemars(range(min = 1))]
    pub max_depth: u32,
    /// Direct-light sampling at the answered points and along the continuation paths.
    pub direct: DirectSampling,
}

impl Default for IrradianceCacheParams {
    fn default() -> Self {
        Self {
            accuracy: 0.15,
            samples: 512,
            min_radius: 0.005,
            max_radius: 0.25,
            direct_samples: 64,
            gradients: true,
            neighbour_clamp: true,
            leak_test: true,
            max_depth: DEFAULT_MAX_DEPTH,
            direct: DirectSampling::Mis,
        }
    }
}

impl MethodParams for IrradianceCacheParams {
    fn check_combination(&self) -> Result<(), SolveError> {
        if self.max_radius < self.min_radius {
            return Err(SolveError::param(
                "max_radius",
                format!(
                    "{} must be at least min_radius ({})",
                    self.max_radius, self.min_radius
                ),
            ));
        }
        Ok(())
    }
}

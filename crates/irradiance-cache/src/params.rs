//! The irradiance cache's parameters, in Radiance's terms (Ward 1994, "The RADIANCE lighting simulation and
//! rendering system"; rtrace's -aa, -ad, -ar): the accuracy a, hemisphere samples per record, and the bounds
//! on a record's radius, here as fractions of the scene's diagonal so that they do not depend on its scale.

use radlab_method::{MethodParams, SolveError};
use radlab_pathtrace::{DEFAULT_MAX_DEPTH, DirectSampling};
use serde::{Deserialize, Serialize};

/// Parameters of the irradiance cache.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct IrradianceCacheParams {
    /// Accuracy a (Radiance's -aa; default 0.15): a record is used at x when Ward's error
    /// ε = ‖x − x_i‖/R_i + √(1 − n·n_i) is below a. Smaller a: more records, less interpolation error
    /// (records ∝ a⁻²). 0 turns caching off: every query point gathers its own record.
    pub accuracy: f64,
    /// Hemisphere directions gathered per record (Radiance's -ad; default 512), stratified in
    /// M × N ≈ samples cells, M = round(√(samples/π)).
    pub samples: u32,
    /// Smallest record radius R as a fraction of the scene's diagonal (default 0.005; Radiance's -ar gives
    /// it as scene size / ar).
    pub min_radius: f64,
    /// Largest record radius R as a fraction of the scene's diagonal (default 0.25).
    pub max_radius: f64,
    /// Direct-light samples per answered point (default 64): each a next-event shadow ray and, under `mis`, a
    /// cosine-distributed ray, combined by the power heuristic (radlab-pathtrace's estimator).
    pub direct_samples: u32,
    /// Use Ward & Heckbert's rotational and translational gradients when interpolating (default true).
    pub gradients: bool,
    /// Křivánek et al.'s (2006) neighbour clamping, R_i ≤ R_j + ‖x_i − x_j‖ both ways on insertion
    /// (default true).
    pub neighbour_clamp: bool,
    /// Cast a ray between a record and the point it would serve, and skip the record if the ray is blocked
    /// (default true): no light leaks through thin walls, one ray per record used.
    pub leak_test: bool,
    /// Cap on the segments of the paths that continue each gather ray (default 100,000; Russian roulette
    /// ends them without bias).
    pub max_depth: u32,
    /// Direct-light sampling at the answered points and along the continuation paths (default `mis`).
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
    fn docs() -> Vec<(&'static str, &'static str)> {
        vec![
            (
                "accuracy",
                "Radiance's -aa (default 0.15): a record serves x while |x - x_i|/R_i + sqrt(1 - n.n_i) < a; \
                 records grow as a^-2; 0 = no caching (a record at every point)",
            ),
            (
                "samples",
                "Radiance's -ad (default 512): stratified hemisphere directions per record, each continued \
                 by a path to termination (Russian roulette)",
            ),
            (
                "min_radius",
                "smallest record radius, fraction of the scene diagonal (default 0.005)",
            ),
            (
                "max_radius",
                "largest record radius, fraction of the scene diagonal (default 0.25)",
            ),
            (
                "direct_samples",
                "direct-light samples per answered point (default 64): a shadow ray plus, under mis, a hemisphere ray",
            ),
            (
                "gradients",
                "interpolate with Ward & Heckbert's rotational and translational gradients (default true)",
            ),
            (
                "neighbour_clamp",
                "Krivanek et al. 2006 neighbour clamping of record radii (default true)",
            ),
            (
                "leak_test",
                "one ray between a record and the point it serves; blocked records are skipped (default true)",
            ),
            (
                "max_depth",
                "cap on the segments of the continuation paths (default 100000)",
            ),
            (
                "direct",
                "direct-light sampling at answered points and along the continuation paths: mis (default), next-event, hemisphere",
            ),
        ]
    }

    fn validate(&self) -> Result<(), SolveError> {
        if !(self.accuracy >= 0.0 && self.accuracy <= 1.0) {
            return Err(SolveError::param(
                "accuracy",
                format!(
                    "{} must be in [0, 1] (Radiance uses 0.05 to 0.3; 0 = no caching)",
                    self.accuracy
                ),
            ));
        }
        if self.samples == 0 {
            return Err(SolveError::param(
                "samples",
                "must be at least 1 (Radiance's -ad is typically 128 to 4096)",
            ));
        }
        if !(self.min_radius > 0.0 && self.min_radius.is_finite()) {
            return Err(SolveError::param(
                "min_radius",
                format!(
                    "{} must be positive and finite (a fraction of the scene diagonal)",
                    self.min_radius
                ),
            ));
        }
        if !(self.max_radius >= self.min_radius && self.max_radius.is_finite()) {
            return Err(SolveError::param(
                "max_radius",
                format!(
                    "{} must be finite and at least min_radius ({})",
                    self.max_radius, self.min_radius
                ),
            ));
        }
        if self.direct_samples == 0 {
            return Err(SolveError::param("direct_samples", "must be at least 1"));
        }
        if self.max_depth == 0 {
            return Err(SolveError::param(
                "max_depth",
                "must be at least 1 (1 = one bounce after each gather ray)",
            ));
        }
        Ok(())
    }
}

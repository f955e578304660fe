//! The bidirectional path tracer's parameters: samples per point and their doubling schedule (as the path
//! tracer's), the cap on path length, and the multiple importance sampling heuristic of Veach & Guibas (1995).

use radlab_method::{MethodParams, SolveError};
use radlab_pathtrace::{DEFAULT_MAX_DEPTH, SteppedPoints};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::mis_weight::Heuristic;

/// Parameters of bidirectional path tracing. Each field is declared once: its doc comment's first paragraph
/// is the help `radlab methods` prints, its `schemars` attribute the accepted range, and its default is in
/// `impl Default`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct BdptParams {
    /// Samples (a light and an eye subpath, joined by every strategy) per point when the method stops; the
    /// standard error falls as 1/√samples.
    #[schemars(range(min = 1))]
    pub samples: u32,
    /// Samples per point added by the first step, at most samples; each later step doubles them.
    #[schemars(range(min = 1))]
    pub initial_samples: u32,
    /// Cap on path segments (1: direct light only); Russian roulette ends subpaths without bias, the cap only
    /// guards against runaway paths (bias at most ρ_max^max_depth, relative).
    #[schemars(range(min = 1))]
    pub max_depth: u32,
    /// Cap on a light subpath's vertices (1: no light subpaths beyond next-event estimation, i.e. path tracing
    /// with MIS); strategies with more light vertices are not used and take no share of the weights. Bounds the
    /// shadow rays per sample at about max_light_vertices × the eye subpath's length in bright enclosures.
    #[schemars(range(min = 1))]
    pub max_light_vertices: u32,
    /// How the strategies that could have made a path share it: balance (w = p/Σp) or power (w = p²/Σp²).
    pub heuristic: Heuristic,
}

impl Default for BdptParams {
    fn default() -> Self {
        Self {
            samples: 256,
            initial_samples: 16,
            max_depth: DEFAULT_MAX_DEPTH,
            max_light_vertices: 4,
            heuristic: Heuristic::Power,
        }
    }
}

impl MethodParams for BdptParams {
    fn check_combination(&self) -> Result<(), SolveError> {
        SteppedPoints::check_schedule(self.initial_samples, self.samples)
    }
}

//! Density estimation's parameters: the particle budget (Shirley et al. 1995), the bandwidth rule
//! h = c √A_s n_s^(−1/6) (the rate that minimises a 2-D kernel estimate's mean integrated squared error,
//! Silverman 1986, §4.3), the boundary correction (Walter et al. 1997), the surface grouping and the answer.

use radlab_method::MethodParams;
use radlab_pathtrace::DEFAULT_MAX_DEPTH;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::local_linear::BoundaryCorrection;

/// How radiosity at a point is answered from the particles.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum DensityReconstruction {
    /// The kernel estimate at the point itself. The default.
    #[default]
    Density,
    /// Gouraud interpolation over the display mesh (element_size) of the estimate at its vertices.
    Mesh,
    /// A final gather (radlab-answer) from the display mesh's elements, valued by the estimate at their
    /// centroids.
    FinalGather,
    /// The particle histogram per input face, Σ Φ_i / (N_e A_f): no smoothing (and exact energy balance).
    Constant,
}

/// Parameters of density estimation. Each field is declared once: its doc comment's first paragraph is the
/// help `radlab methods` prints, its `schemars` attribute the accepted range, and its default is in
/// `impl Default`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct DensityEstimationParams {
    /// Particle landings stored per step (whole emitted particles, each with all its landings).
    #[schemars(range(min = 1))]
    pub particles: u64,
    /// Steps, each tracing `particles` more; the estimate is over all landings so far.
    #[schemars(range(min = 1))]
    pub steps: u32,
    /// c in the bandwidth h = c √A_s n_s^(−1/6) of a surface of projected area A_s holding n_s landings.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub bandwidth: f64,
    /// A fixed bandwidth in scene units for every surface; unset: the rule of `bandwidth`.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub bandwidth_size: Option<f64>,
    /// The boundary treatment: local-linear (Walter et al. 1997), renormalized or none (the plain kernel).
    pub boundary: BoundaryCorrection,
    /// Largest angle (degrees) between a face's normal and its surface seed's for the face to join it.
    #[schemars(extend("exclusiveMinimum" = 0))]
    #[schemars(range(max = 80))]
    pub group_angle: f64,
    /// How radiosity at a point is answered: density, mesh, final-gather or constant.
    pub reconstruction: DensityReconstruction,
    /// Display-mesh element edge in scene units (mesh and final-gather answers); unset: 1/25 of the scene's
    /// bounding diagonal.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub element_size: Option<f64>,
    /// Cap on a particle's reflections (Russian roulette ends them).
    #[schemars(range(min = 1))]
    pub max_depth: u32,
}

impl Default for DensityEstimationParams {
    fn default() -> Self {
        Self {
            particles: 100_000,
            steps: 4,
            bandwidth: 0.5,
            bandwidth_size: None,
            boundary: BoundaryCorrection::LocalLinear,
            group_angle: 30.0,
            reconstruction: DensityReconstruction::Density,
            element_size: None,
            max_depth: DEFAULT_MAX_DEPTH,
        }
    }
}

impl MethodParams for DensityEstimationParams {}

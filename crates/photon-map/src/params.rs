//! The photon map's parameters: Jensen's (2001) photon count and nearest-neighbour count, Christensen's (1999)
//! precomputed-irradiance stride, the final gather's ray count, and progressive photon mapping's α and
//! initial radius (Hachisuka, Ogaki & Jensen 2008). Lengths are fractions of the scene's diagonal.

use radlab_method::MethodParams;
use radlab_pathtrace::{DEFAULT_MAX_DEPTH, DirectSampling};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::density_estimate::DensityFilter;

/// How the photons become radiosity at the query points.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum PhotonMode {
    /// One global map; at each query point, direct light by next-event estimation and one final-gather bounce
    /// whose rays read irradiance precomputed at a subset of the photons (Jensen 1996; Christensen 1999).
    /// Biased (density estimation), not consistent at a fixed photon count. The default.
    #[default]
    FinalGather,
    /// Progressive photon mapping at the query points (Hachisuka, Ogaki & Jensen 2008): each step traces a
    /// new batch of photons and shrinks every point's radius; consistent (the bias vanishes as passes grow).
    Progressive,
}

/// Parameters of the photon map. Each field is declared once: its doc comment's first paragraph is the help
/// `radlab methods` prints, its `schemars` attribute the accepted range, and its default is in `impl Default`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct PhotonMapParams {
    /// How the photons become radiosity at the query points: `final-gather` or `progressive`.
    pub mode: PhotonMode,
    /// Photons stored in the map (final gather), or per pass (progressive); emission goes on in chunks of 256
    /// until at least this many are stored.
    #[schemars(range(min = 1))]
    pub photons: u64,
    /// k, the photons per density estimate (final gather).
    #[schemars(range(min = 1))]
    pub nearest: u32,
    /// The density-estimation filter: `cone` or `epanechnikov`.
    pub filter: DensityFilter,
    /// Final-gather rays per query point.
    #[schemars(range(min = 1))]
    pub gather_samples: u32,
    /// Irradiance is precomputed at every `precompute_stride`-th photon (Christensen 1999).
    #[schemars(range(min = 1))]
    pub precompute_stride: u32,
    /// Direct-light samples per query point, radlab-pathtrace's estimator.
    #[schemars(range(min = 1))]
    pub direct_samples: u32,
    /// Progressive: photon passes, one per step.
    #[schemars(range(min = 1))]
    pub passes: u32,
    /// Progressive: the fraction α of new photons kept per pass (Hachisuka et al. 2008 use 0.7).
    #[schemars(extend("exclusiveMinimum" = 0, "exclusiveMaximum" = 1))]
    pub alpha: f64,
    /// Progressive: the initial gather radius, a fraction of the scene diagonal.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub initial_radius: f64,
    /// A ray from each photon (progressive) or precomputed irradiance point (final gather) to the point it
    /// would serve; blocked ones are skipped: no light through thin walls.
    pub leak_test: bool,
    /// Cap on a photon's reflections (Russian roulette ends them).
    #[schemars(range(min = 1))]
    pub max_depth: u32,
    /// Direct-light sampling at the query points.
    pub direct: DirectSampling,
}

impl Default for PhotonMapParams {
    fn default() -> Self {
        Self {
            mode: PhotonMode::FinalGather,
            photons: 200_000,
            nearest: 50,
            filter: DensityFilter::Cone,
            gather_samples: 64,
            precompute_stride: 4,
            direct_samples: 64,
            passes: 16,
            alpha: 0.7,
            initial_radius: 0.02,
            leak_test: true,
            max_depth: DEFAULT_MAX_DEPTH,
            direct: DirectSampling::Mis,
        }
    }
}

impl MethodParams for PhotonMapParams {}

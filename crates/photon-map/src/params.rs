//! The photon map's parameters: Jensen's (2001) photon count and nearest-neighbour count, Christensen's (1999)
//! precomputed-irradiance stride, the final gather's ray count, and progressive photon mapping's α and
//! initial radius (Hachisuka, Ogaki & Jensen 2008). Lengths are fractions of the scene's diagonal.

use radlab_method::{MethodParams, SolveError};
use radlab_pathtrace::{DEFAULT_MAX_DEPTH, DirectSampling};
use serde::{Deserialize, Serialize};

use crate::density_estimate::DensityFilter;

/// How the photons become radiosity at the query points.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
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

/// Parameters of the photon map.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PhotonMapParams {
    /// `final-gather` (default) or `progressive`.
    pub mode: PhotonMode,
    /// Photons stored in the map (final gather), or per pass (progressive); emission goes on in chunks of 256
    /// until at least this many are stored (default 200,000).
    pub photons: u64,
    /// k, the photons per density estimate (final gather; default 50).
    pub nearest: u32,
    /// The density-estimation filter (default `cone`).
    pub filter: DensityFilter,
    /// Final-gather rays per query point (default 64).
    pub gather_samples: u32,
    /// Irradiance is precomputed at every `precompute_stride`-th photon (default 4; Christensen 1999).
    pub precompute_stride: u32,
    /// Direct-light samples per query point (default 64, as the irradiance cache), radlab-pathtrace's estimator.
    pub direct_samples: u32,
    /// Progressive: photon passes (default 16), one per step.
    pub passes: u32,
    /// Progressive: the fraction α of new photons kept per pass (default 0.7, Hachisuka et al. 2008).
    pub alpha: f64,
    /// Progressive: the initial gather radius, a fraction of the scene diagonal (default 0.02).
    pub initial_radius: f64,
    /// A ray from each photon (progressive) or precomputed irradiance point (final gather) to the point it
    /// would serve; blocked ones are skipped (default true): no light through thin walls.
    pub leak_test: bool,
    /// Cap on a photon's reflections (default 100,000; Russian roulette ends them).
    pub max_depth: u32,
    /// Direct-light sampling at the query points (default `mis`).
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

impl MethodParams for PhotonMapParams {
    fn docs() -> Vec<(&'static str, &'static str)> {
        vec![
            ("mode", "final-gather (default) or progressive"),
            (
                "photons",
                "photons stored (final-gather) or stored per pass (progressive); default 200000",
            ),
            ("nearest", "k, photons per density estimate (default 50)"),
            ("filter", "density filter: cone (default) or epanechnikov"),
            (
                "gather_samples",
                "final-gather rays per query point (default 64)",
            ),
            (
                "precompute_stride",
                "irradiance precomputed at every n-th photon (default 4)",
            ),
            (
                "direct_samples",
                "direct-light samples per query point (default 16)",
            ),
            (
                "passes",
                "progressive: photon passes, one per step (default 16)",
            ),
            (
                "alpha",
                "progressive: share of new photons kept per pass (default 0.7)",
            ),
            (
                "initial_radius",
                "progressive: initial radius, fraction of the scene diagonal (default 0.02)",
            ),
            (
                "leak_test",
                "a ray from each photon or irradiance point used to the point served (default true)",
            ),
            ("max_depth", "cap on photon reflections (default 100000)"),
            (
                "direct",
                "direct-light sampling: mis (default), next-event, hemisphere",
            ),
        ]
    }

    fn validate(&self) -> Result<(), SolveError> {
        let positive = |name: &str, v: u64| {
            if v == 0 {
                Err(SolveError::param(name, "must be at least 1"))
            } else {
                Ok(())
            }
        };
        positive("photons", self.photons)?;
        positive("nearest", self.nearest as u64)?;
        positive("gather_samples", self.gather_samples as u64)?;
        positive("precompute_stride", self.precompute_stride as u64)?;
        positive("direct_samples", self.direct_samples as u64)?;
        positive("passes", self.passes as u64)?;
        positive("max_depth", self.max_depth as u64)?;
        if !(self.alpha > 0.0 && self.alpha < 1.0) {
            return Err(SolveError::param(
                "alpha",
                format!(
                    "{} must be in (0, 1) (Hachisuka et al. use 0.7)",
                    self.alpha
                ),
            ));
        }
        if !(self.initial_radius > 0.0 && self.initial_radius.is_finite()) {
            return Err(SolveError::param(
                "initial_radius",
                format!(
                    "{} must be positive and finite (a fraction of the scene diagonal)",
                    self.initial_radius
                ),
            ));
        }
        Ok(())
    }
}

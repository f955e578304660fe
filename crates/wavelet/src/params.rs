//! Parameters of wavelet radiosity: the basis, the refinement threshold ε and its oracle, how visibility
//! enters a link, the quadrature, the minimum element, the schedule and how points are answered. Each is
//! declared once (doc comment = help, `schemars` attribute = range, [`WaveletParams::default`] = default).

use radlab_answer::{AnswerParams, Reconstruction};
use radlab_hierarchical::{
    ErrorNorm, Gather, HierarchicalParams, LeafVisibility, Oracle, Schedule,
};
use radlab_kernels::form_factor::VisibilitySampling;
use radlab_method::{MethodParams, SolveError};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::basis::Basis;
use crate::link_tensor::Visibility;
use crate::transport::{WaveletGather, WaveletOracle};

/// How radiosity at a point is answered.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum WaveletReconstruction {
    /// The leaf's own basis functions at the point (discontinuous across elements); also accepted as
    /// `constant`, the name other methods give their elements' own values.
    #[serde(alias = "constant")]
    Basis,
    /// Leaf means averaged at the vertices and interpolated (the survey's "Haar with smoothing"); also
    /// accepted as `gouraud`.
    #[serde(alias = "gouraud")]
    Smoothed,
    /// One more gather from every leaf with exact point-to-polygon factors and rays (charged to answering):
    /// the default, chosen by the worst scenes of the defaults suite, where the basis' own answers were
    /// further from the path-traced reference (docs/defaults.md).
    #[default]
    FinalGather,
}

/// Parameters of [`crate::WaveletSolver`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct WaveletParams {
    /// Basis per element: haar (constant), f2 / f3 (flatlets, constant on 2x2 / 3x3 sub-squares), m2 / m3
    /// (Alpert multiwavelets, tensor Legendre of degree 1 / 2).
    pub basis: Basis,
    /// Refinement threshold: a link whose error estimate exceeds it is refined; dimensionless (relative to
    /// the scene's mean radiosity for bekaert-willems and bf). Default 0.003, chosen on the defaults suite's
    /// worst scenes (docs/defaults.md).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub epsilon: f64,
    /// How a link's error is estimated: bekaert-willems (the link's reproduction at the receiver's nodes
    /// against the point-to-element kernel, plus the source's children's misfit to its function), f (form
    /// factor) or bf (radiosity x form factor).
    pub oracle: WaveletOracle,
    /// How visibility enters a link: per-pair (one ray per pair of quadrature nodes) or per-link (one
    /// fraction of 16 jittered rays scaling the whole tensor).
    pub visibility: Visibility,
    /// Where a link's tensor is evaluated: leaf (re-integrated at each leaf below its receiver; exact
    /// form-factor sums, the furnace holds at any reflectance) or receiver (pushed down by the two-scale
    /// relation; M^4 per link only).
    pub gather: WaveletGather,
    /// Gather = leaf: where a leaf below a partly visible link's receiver takes the visibility scaling its
    /// re-integrated tensor from: link (the link's share) or its own rays to the source (centre,
    /// jittered2x2, jittered4x4).
    pub leaf_visibility: LeafVisibility,
    /// Gauss points per side of each element's quadrature (per sub-square for flatlets); unset: the basis'
    /// default (haar 2, f2/f3 2 per sub-square, m2 3, m3 4). At least M for multiwavelets.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schemars(range(min = 1, max = 8))]
    pub quadrature: Option<u32>,
    /// Smallest element edge in scene units; unset: the scene's bounding-box diagonal / 150.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub min_element_size: Option<f64>,
    /// How refinement and solution alternate: two-stage, interleaved or scheduled (as for hierarchical).
    pub schedule: Schedule,
    /// How radiosity at a point is answered: final-gather (one more gather from every leaf), basis (the
    /// leaf's functions) or smoothed (vertex-averaged means).
    pub reconstruction: WaveletReconstruction,
    /// Estimated remaining relative error (area-weighted L1) below which the solution is converged.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub tolerance: f64,
    /// Steps after which the solver stops (reported as capped).
    #[schemars(range(min = 1))]
    pub max_steps: u64,
    /// Memory the elements and links may take, MiB; a refinement beyond it is refused.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub memory_budget_mib: f64,
    /// Shoot unshot radiosity without storing links (Stamminger et al. 1998): each step is a sweep over the
    /// faces that are lit or hold at least a tenth of the largest unshot power, each shot refining its links
    /// with the same oracle and epsilon, then dropping them. The schedule is then not used.
    pub linkless: bool,
    /// Linkless only: a cache of computed links (tensors and their leaf coefficients) of at most this
    /// many MiB, least recently used evicted; 0 = no cache. Results are identical with or without it.
    #[schemars(range(min = 0))]
    pub link_cache_mib: f64,
}

impl Default for WaveletParams {
    fn default() -> Self {
        Self {
            basis: Basis::M2,
            epsilon: 0.003,
            oracle: WaveletOracle::BekaertWillems,
            visibility: Visibility::PerPair,
            gather: WaveletGather::Leaf,
            leaf_visibility: LeafVisibility::Jittered2x2,
            quadrature: None,
            min_element_size: None,
            schedule: Schedule::Scheduled,
            reconstruction: WaveletReconstruction::FinalGather,
            tolerance: 1e-4,
            max_steps: 100_000,
            memory_budget_mib: 4096.0,
            linkless: false,
            link_cache_mib: 0.0,
        }
    }
}

impl MethodParams for WaveletParams {
    fn check_combination(&self) -> Result<(), SolveError> {
        let n = self.points();
        if n < self.basis.min_points() {
            return Err(SolveError::param(
                "quadrature",
                format!(
                    "{n} Gauss points per side cannot integrate the {:?} basis exactly; use at least {}",
                    self.basis,
                    self.basis.min_points()
                ),
            ));
        }
        if self.link_cache_mib > 0.0 && !self.linkless {
            return Err(SolveError::param(
                "link_cache_mib",
                "the link cache serves linkless shooting only; set linkless = true or link_cache_mib = 0",
            ));
        }
        Ok(())
    }
}

impl WaveletParams {
    /// The link cache's bound in bytes (0: none).
    pub fn link_cache_bytes(&self) -> usize {
        (self.link_cache_mib * 1024.0 * 1024.0).clamp(0.0, usize::MAX as f64) as usize
    }

    /// Gauss points per cell and side: the parameter or the basis' default.
    pub fn points(&self) -> usize {
        self.quadrature
            .map(|q| q as usize)
            .unwrap_or(self.basis.default_points())
    }

    /// The engine's parameters (ε, schedule, minimum element, tolerance, steps, budget); the oracle and
    /// visibility are the transport's.
    pub fn engine_params(&self) -> HierarchicalParams {
        HierarchicalParams {
            epsilon: self.epsilon,
            oracle: match self.oracle {
                WaveletOracle::F => Oracle::F,
                _ => Oracle::Bf,
            },
            error_norm: ErrorNorm::Radiosity,
            schedule: self.schedule,
            min_element_size: self.min_element_size,
            visibility: VisibilitySampling::Jittered4x4,
            quadrature: 2,
            tolerance: self.tolerance,
            max_steps: self.max_steps,
            gather: Gather::Link,
            answer: self.reconstruction.answer(),
            memory_budget_mib: self.memory_budget_mib,
            ..HierarchicalParams::default()
        }
    }
}

impl WaveletReconstruction {
    /// The shared answering layer's parameters: basis answers go through the leaf's point evaluation (the
    /// layer's `constant`, which reads [`radlab_hierarchical::Engine::radiosity_at_leaf`]); a final gather
    /// goes over every leaf.
    pub fn answer(self) -> AnswerParams {
        AnswerParams {
            reconstruction: match self {
                Self::Basis => Reconstruction::Constant,
                Self::Smoothed => Reconstruction::Gouraud,
                Self::FinalGather => Reconstruction::FinalGather,
            },
            ..AnswerParams::final_gather(0.0)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_values_name_the_parameter() {
        for (k, v) in [
            ("basis", "m4"),
            ("epsilon", "0"),
            ("visibility", "sometimes"),
            ("quadrature", "0"),
            ("quadrature", "9"),
            ("min_element_size", "-1"),
            ("oracle", "guess"),
            ("reconstruction", "linear"),
            ("gather", "link"),
            ("linkless", "maybe"),
            ("link_cache_mib", "-1"),
        ] {
            let e = WaveletParams::from_pairs(&[(k.to_string(), v.to_string())])
                .expect_err("rejected")
                .to_string();
            assert!(e.contains(k), "{k}={v}: {e}");
        }
        let e = WaveletParams::from_pairs(&[
            ("basis".to_string(), "m3".to_string()),
            ("quadrature".to_string(), "2".to_string()),
        ])
        .expect_err("too few points")
        .to_string();
        assert!(e.contains("quadrature") && e.contains("at least 3"), "{e}");
        let p = WaveletParams::from_pairs(&[
            ("basis".to_string(), "f3".to_string()),
            ("visibility".to_string(), "per-link".to_string()),
            ("reconstruction".to_string(), "smoothed".to_string()),
        ])
        .expect("valid");
        assert_eq!(p.basis, Basis::F3);
        assert_eq!(p.visibility, Visibility::PerLink);
        assert_eq!(p.points(), 2);
        let e = WaveletParams::from_pairs(&[("link_cache_mib".to_string(), "8".to_string())])
            .expect_err("a cache without linkless")
            .to_string();
        assert!(
            e.contains("link_cache_mib") && e.contains("linkless"),
            "{e}"
        );
    }
}

//! Parameters of hierarchical radiosity: the refinement threshold ε and its oracle, the schedule that
//! interleaves refinement and solution (Willmott 2000, §2.4.3), the minimum element size, the transfer's quadrature and
//! visibility sampling, the solver tolerance and the output interpolation. Every choice is a typed enum
//! (serde kebab-case), every field has a documented default, and [`HierarchicalParams::coarse`] and
//! [`HierarchicalParams::reference`] are named presets.

use radlab_answer::{AnswerParams, DEFAULT_GATHER_OPENING, Reconstruction};
use radlab_kernels::form_factor::VisibilitySampling;
use radlab_method::{MethodParams, SolveError};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// The default minimum element size as a fraction of the scene's bounding-box diagonal.
pub const MIN_ELEMENT_SIZE_REL: f64 = 1.0 / 150.0;

/// How a link's error is estimated (Hanrahan, Salzman & Aupperle 1991; Stamminger et al. 1997).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum Oracle {
    /// Form factor: max(F_rs, F_sr), the larger of the link's two form factors. Geometry only, so the
    /// links do not depend on the lighting (HSA91's first oracle).
    F,
    /// Radiosity × form factor: ρ_r B_s max(F_rs, F_sr) / B̄, with B_s the source's current radiosity and
    /// B̄ the scene's area-mean radiosity, so ε stays dimensionless. Refines where light actually flows.
    Bf,
    /// Sampled variation: ρ_r B_s / B̄ times the spread (max − min) of the point-to-polygon kernel over the
    /// receiver's quadrature points and centroid (the largest sample when visibility is partial). Needs
    /// `quadrature` ≥ 2.
    /// The default: on the Cornell box it reaches a given error with the fewest links.
    #[default]
    Variation,
}

/// How link refinement and solution alternate (Willmott 2000, §2.4.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum Schedule {
    /// Refine every link until the oracle is met (with the lighting known before solving: emission only),
    /// then solve. No feedback from the solution to the links.
    TwoStage,
    /// Alternate one refinement pass (each link refined at most once) with one gather/push-pull pass.
    Interleaved,
    /// Stages: refine fully at ε_i, solve to convergence, then ε_{i+1} = ε_i / α, starting from
    /// ε_0 = ε·α^(stages−1) and ending with stages at ε until a stage changes nothing. With lazy linking the
    /// first stage carries direct light only, the next one bounce, and so on.
    #[default]
    Scheduled,
}

/// How a leaf's irradiance is gathered from the links on its path to the root (Hanrahan, Salzman & Aupperle 1991: gather, then push-pull).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum Gather {
    /// The kernel is integrated at each leaf for every link above it: H_leaf = Σ V_as F_{leaf→s} B_s over
    /// the links (a ← s) of the leaf and its ancestors, F by the leaf's own Gauss points. The links still
    /// choose each source's level and carry the visibility; the per-leaf form-factor sums are exact (one in a
    /// closed unoccluded scene), so the furnace holds at any ρ. Costs O(n × links on a path) memory.
    #[default]
    Leaf,
    /// Classic HSA91: each link's coefficient is its receiver's mean, gathered at the receiver and pushed
    /// down unchanged. O(links) memory and work, but a leaf near a grazing source inherits its ancestors'
    /// means: per-leaf form-factor sums err by several ε, magnified by 1/(1 − ρ).
    Link,
}

/// Where a leaf below a partly visible link's receiver takes its visibility from (gather = leaf). A
/// coarse link has one visibility fraction V_rs for its whole receiver; a leaf of it that lies in the shadow of
/// an occluder near the receiver (the floor beside a block, which hides part of a wall behind it) would gather
/// V_rs F_{leaf→s} of the source's light, and one in full view the same share: the shadow is spread over the
/// receiver. With rays, each such leaf measures its own visibility of the source, V_{leaf,s} F_{leaf→s}
/// (Hanrahan, Salzman & Aupperle 1991 estimate visibility per link; this estimates it per leaf-source pair, as
/// the gather evaluates the kernel there). Links that are wholly visible or wholly hidden (V_rs = 1 or 0) keep
/// their fraction, so a scene without shadows casts no more rays.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum LeafVisibility {
    /// Every leaf takes its link's fraction V_rs (HSA91).
    Link,
    /// One ray, between the centroids.
    Centre,
    /// 2 × 2 jittered rays between the leaf and the source: the default. On the Cornell box it took the
    /// hierarchical method's worst point from 43% to 13% for about 10% more time (docs/defaults.md); one
    /// centre ray biased the mean by −0.42%, against −0.14% with these.
    #[default]
    Jittered2x2,
    /// 4 × 4 jittered rays.
    Jittered4x4,
}

impl LeafVisibility {
    /// The ray sampling of a leaf's own visibility, `None` for the link's fraction.
    pub fn sampling(self) -> Option<VisibilitySampling> {
        match self {
            Self::Link => None,
            Self::Centre => Some(VisibilitySampling::Centre),
            Self::Jittered2x2 => Some(VisibilitySampling::Jittered2x2),
            Self::Jittered4x4 => Some(VisibilitySampling::Jittered4x4),
        }
    }
}

/// What the refinement threshold ε bounds (RenderPark's "error norm"; Smits, Arvo & Greenberg 1994 bound the
/// power a link carries).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum ErrorNorm {
    /// The oracle's estimate as is: the irradiance a link brings its receiver, relative to the scene's mean
    /// (HSA91). Every receiver, however small, gets links accurate to ε of its own light.
    #[default]
    Radiosity,
    /// The estimate times A_r / A_scene: the power a link brings its receiver, relative to the scene's.
    /// Small receivers accept coarser links, so the number of links depends on ε and the lighting, not on how
    /// finely the surfaces are tessellated.
    Power,
}

/// Parameters of [`crate::HierarchicalSolver`] and of the methods on its engine (which flatten them into
/// their own), each declared once: its doc comment's first paragraph is the help `radlab methods` prints, its
/// `schemars` attribute the accepted range, and its default is in [`HierarchicalParams::default_params`] (a
/// method on the engine may change it in its own `Default`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct HierarchicalParams {
    /// Refinement threshold ε: a link whose error estimate (the oracle's, scaled as error_norm says) exceeds
    /// it is refined; dimensionless. Default 0.0075 ([`DEFAULT_EPSILON`]), chosen on the defaults suite's worst
    /// scenes (docs/defaults.md).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub epsilon: f64,
    /// How a link's error is estimated: f (form factor), bf (radiosity × form factor) or variation (spread of
    /// the kernel over the receiver's quadrature points; needs quadrature ≥ 2).
    pub oracle: Oracle,
    /// What ε bounds: radiosity (the irradiance a link brings its receiver, relative to the scene's mean) or
    /// power (that times the receiver's share of the scene's area).
    pub error_norm: ErrorNorm,
    /// How refinement and solution alternate: two-stage, interleaved or scheduled.
    pub schedule: Schedule,
    /// Scheduled only: ε is divided by alpha between stages (1 simulates successive bounces).
    #[schemars(range(min = 1))]
    pub alpha: f64,
    /// Scheduled only: number of stages over which ε falls to its final value.
    #[schemars(range(min = 1, max = 64))]
    pub stages: u32,
    /// Interleaved and scheduled only: create the initial links from an input face only once it carries
    /// light (Holzschuch, Sillion & Drettakis 1994).
    pub lazy_linking: bool,
    /// Smallest element edge in scene units: an element is split only if its children's longest edge stays
    /// at least this long; unset: the scene's bounding-box diagonal / 150 ([`MIN_ELEMENT_SIZE_REL`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub min_element_size: Option<f64>,
    /// Visibility rays per link.
    pub visibility: VisibilitySampling,
    /// Gather = leaf: where a leaf below a partly visible link's receiver takes its visibility from: link
    /// (the link's fraction) or its own rays to the source (centre, jittered2x2, jittered4x4).
    pub leaf_visibility: LeafVisibility,
    /// Gauss–Legendre points per side (m, m² points) of the receiver quadrature of the point-to-polygon
    /// kernel.
    #[schemars(range(min = 1, max = 8))]
    pub quadrature: u32,
    /// Estimated remaining relative error (area-weighted L1) below which the solution is converged.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub tolerance: f64,
    /// Steps after which the solver stops (reporting converged, with the residual in the stats).
    #[schemars(range(min = 1))]
    pub max_steps: u64,
    /// How leaves gather from the links above them: leaf (the kernel at each leaf for every link above it) or
    /// link (classic: each link's receiver mean, pushed down).
    pub gather: Gather,
    /// How points are answered: reconstruction and gather_opening, declared once in radlab-answer.
    ///
    /// Gouraud interpolates over each face's quadtree with T-vertices resolved; a final gather goes over the
    /// leaves.
    #[serde(flatten)]
    pub answer: AnswerParams,
    /// Memory the elements and links may take, MiB; a refinement beyond it is refused.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub memory_budget_mib: f64,
}

/// Default reconstruction of point answers: `final-gather`, chosen by measurement against the path-traced
/// reference (docs/methods.md gives the figures): at the default ε on the Cornell box it is several times
/// closer than `constant` or `gouraud`, at the price of answering time (a point-to-polygon kernel per leaf and
/// query, plus rays), so images of finely refined solutions are slow.
pub const DEFAULT_RECONSTRUCTION: Reconstruction = Reconstruction::FinalGather;

/// Default refinement threshold of hierarchical radiosity: the largest of 0.01, 0.0075, 0.005 and 0.0025 at which
/// every small scene of the defaults suite holds its targets (the Cornell box's floors and walls, beside the
/// blocks: 13% at 0.01, 8% at 0.0075, for 1.1-1.4 times the time on those scenes; docs/defaults.md).
pub const DEFAULT_EPSILON: f64 = 0.0075;

impl HierarchicalParams {
    /// The defaults: solve a room-sized scene to about a percent in seconds.
    pub const fn default_params() -> Self {
        Self {
            epsilon: DEFAULT_EPSILON,
            oracle: Oracle::Variation,
            error_norm: ErrorNorm::Radiosity,
            schedule: Schedule::Scheduled,
            alpha: 2.0,
            stages: 3,
            lazy_linking: true,
            min_element_size: None,
            visibility: VisibilitySampling::Jittered4x4,
            leaf_visibility: LeafVisibility::Jittered2x2,
            quadrature: 2,
            tolerance: 1e-4,
            max_steps: 100_000,
            gather: Gather::Leaf,
            answer: AnswerParams {
                reconstruction: DEFAULT_RECONSTRUCTION,
                ..AnswerParams::final_gather(DEFAULT_GATHER_OPENING)
            },
            memory_budget_mib: 4096.0,
        }
    }

    /// A quick, rough solution: ε = 0.05, 2×2 rays, tolerance 1e-3.
    pub const fn coarse() -> Self {
        let mut p = Self::default_params();
        p.epsilon = 0.05;
        p.visibility = VisibilitySampling::Jittered2x2;
        p.tolerance = 1e-3;
        p
    }

    /// A careful solution for reference tables: ε = 0.002, 8×8 rays per link and 4×4 per leaf, 3×3 quadrature,
    /// tolerance 1e-5.
    pub const fn reference() -> Self {
        let mut p = Self::default_params();
        p.epsilon = 0.002;
        p.visibility = VisibilitySampling::Jittered8x8;
        p.leaf_visibility = LeafVisibility::Jittered4x4;
        p.quadrature = 3;
        p.tolerance = 1e-5;
        p
    }

    /// The minimum element edge for `scene`: the parameter, or the scene's diagonal × [`MIN_ELEMENT_SIZE_REL`].
    pub fn resolve_min_size(&self, scene: &radlab_scene::Scene) -> Result<f64, SolveError> {
        let min_size = self
            .min_element_size
            .unwrap_or(MIN_ELEMENT_SIZE_REL * scene.diagonal());
        if !(min_size > 0.0 && min_size.is_finite()) {
            return Err(SolveError::param(
                "min_element_size",
                format!("resolved to {min_size}; the scene's diagonal must be finite and > 0"),
            ));
        }
        Ok(min_size)
    }

    /// The ε of scheduled stage `stage` (0-based): ε·α^(stages−1−stage), never below ε.
    pub fn stage_epsilon(&self, stage: u32) -> f64 {
        let ahead = self.stages.saturating_sub(1).saturating_sub(stage);
        self.epsilon * self.alpha.powi(ahead.min(64) as i32)
    }
}

impl Default for HierarchicalParams {
    fn default() -> Self {
        Self::default_params()
    }
}

impl MethodParams for HierarchicalParams {
    fn check_combination(&self) -> Result<(), SolveError> {
        self.check_engine(&Self::default_params().answer)
    }
}

impl HierarchicalParams {
    /// The checks of every method on the engine, for a method whose default answers are `default`: an
    /// opening or near values other than those defaults are refused under answers other than a final gather,
    /// where they would change nothing.
    pub fn check_engine(&self, default: &AnswerParams) -> Result<(), SolveError> {
        self.answer.check(default)?;
        if self.oracle == Oracle::Variation && self.quadrature < 2 {
            return Err(SolveError::param(
                "quadrature",
                "the variation oracle needs at least 2 Gauss points per side (with 1 it samples the centroid only)",
            ));
        }
        if !(self.epsilon * self.alpha.powi(self.stages as i32 - 1)).is_finite() {
            return Err(SolveError::param(
                "alpha",
                "alpha^(stages-1) x epsilon overflows; lower alpha or stages",
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_validate_and_pairs_parse() {
        for p in [
            HierarchicalParams::default(),
            HierarchicalParams::coarse(),
            HierarchicalParams::reference(),
        ] {
            p.validate().expect("preset is valid");
        }
        let pairs = [
            ("oracle", "variation"),
            ("schedule", "two-stage"),
            ("min_element_size", "0.5"),
            ("reconstruction", "gouraud"),
            ("visibility", "centre"),
            ("leaf_visibility", "link"),
        ]
        .map(|(k, v)| (k.to_string(), v.to_string()));
        let p = HierarchicalParams::from_pairs(&pairs).expect("valid pairs");
        assert_eq!(p.oracle, Oracle::Variation);
        assert_eq!(p.schedule, Schedule::TwoStage);
        assert_eq!(p.min_element_size, Some(0.5));
        assert_eq!(p.answer.reconstruction, Reconstruction::Gouraud);
        assert_eq!(p.visibility, VisibilitySampling::Centre);
        assert_eq!(p.leaf_visibility, LeafVisibility::Link);
        assert_eq!(p.leaf_visibility.sampling(), None);
    }

    #[test]
    fn bad_values_name_the_parameter() {
        for (k, v) in [
            ("epsilon", "0"),
            ("epsilon", "-1"),
            ("alpha", "0.5"),
            ("stages", "0"),
            ("quadrature", "9"),
            ("min_element_size", "-2"),
            ("tolerance", "nan"),
            ("oracle", "fancy"),
            ("max_steps", "0"),
            ("gather_opening", "1"),
            ("gather_opening", "-0.1"),
        ] {
            let e = HierarchicalParams::from_pairs(&[(k.to_string(), v.to_string())])
                .expect_err("rejected")
                .to_string();
            assert!(e.contains(k), "{k}={v}: {e}");
        }
        let e = HierarchicalParams::from_pairs(&[("nope".into(), "1".into())])
            .expect_err("unknown")
            .to_string();
        assert!(e.contains("nope"), "{e}");
        // An opening changes only a final gather's answers: refused under the others, naming the fix.
        let e = HierarchicalParams::from_pairs(&[
            ("reconstruction".into(), "constant".into()),
            ("gather_opening".into(), "0.1".into()),
        ])
        .expect_err("refused")
        .to_string();
        assert!(
            e.contains("gather_opening") && e.contains("final-gather"),
            "{e}"
        );
        let p = HierarchicalParams::from_pairs(&[("gather_opening".into(), "0".into())])
            .expect("a final gather's opening");
        assert_eq!(p.answer.gather_opening, 0.0);
    }

    #[test]
    fn stage_epsilons_fall_to_epsilon() {
        let p = HierarchicalParams {
            epsilon: 0.01,
            alpha: 2.0,
            stages: 3,
            ..HierarchicalParams::default()
        };
        assert_eq!(p.stage_epsilon(0), 0.04);
        assert_eq!(p.stage_epsilon(1), 0.02);
        assert_eq!(p.stage_epsilon(2), 0.01);
        assert_eq!(p.stage_epsilon(7), 0.01);
    }
}

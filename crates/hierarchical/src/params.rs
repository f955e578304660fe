//! Parameters of hierarchical radiosity: the refinement threshold ε and its oracle, the schedule that
//! interleaves refinement and solution (Willmott 2000, §2.4.3), the minimum element size, the transfer's quadrature and
//! visibility sampling, the solver tolerance and the output interpolation. Every choice is a typed enum
//! (serde kebab-case), every field has a documented default, and [`HierarchicalParams::coarse`] and
//! [`HierarchicalParams::reference`] are named presets.

use radlab_answer::Reconstruction;
use radlab_kernels::form_factor::VisibilitySampling;
use radlab_method::{MethodParams, SolveError};
use serde::{Deserialize, Serialize};

/// The default minimum element size as a fraction of the scene's bounding-box diagonal.
pub const MIN_ELEMENT_SIZE_REL: f64 = 1.0 / 150.0;

/// How a link's error is estimated (Hanrahan, Salzman & Aupperle 1991; Stamminger et al. 1997).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
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
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
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
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
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

/// What the refinement threshold ε bounds (RenderPark's "error norm"; Smits, Arvo & Greenberg 1994 bound the
/// power a link carries).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
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

/// Parameters of [`crate::HierarchicalSolver`]. Every field has a default; see [`MethodParams::docs`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct HierarchicalParams {
    /// Refinement threshold ε on the oracle's estimate (dimensionless). Default 0.01.
    pub epsilon: f64,
    /// Refinement oracle. Default [`Oracle::Variation`].
    pub oracle: Oracle,
    /// What ε bounds. Default [`ErrorNorm::Radiosity`].
    pub error_norm: ErrorNorm,
    /// Schedule. Default [`Schedule::Scheduled`].
    pub schedule: Schedule,
    /// Scheduled only: ε is divided by α between stages (α ≥ 1; 1 simulates successive bounces). Default 2.
    pub alpha: f64,
    /// Scheduled only: number of stages over which ε falls to its final value. Default 3.
    pub stages: u32,
    /// Interleaved and scheduled only: create the initial links from an input face only once it carries
    /// light (Holzschuch, Sillion & Drettakis 1994). Default true.
    pub lazy_linking: bool,
    /// Smallest element edge: an element is split only if its children's longest edge stays at least this
    /// long (scene units). Absent: the scene's bounding-box diagonal × [`MIN_ELEMENT_SIZE_REL`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min_element_size: Option<f64>,
    /// Rays per link for its visibility fraction. Default 4×4 jittered (16 rays).
    pub visibility: VisibilitySampling,
    /// Gauss–Legendre points per side (m, m² points) of the receiver quadrature of the point-to-polygon
    /// kernel. Default 2.
    pub quadrature: u32,
    /// The solution is converged when its estimated remaining relative error (area-weighted L1) is below
    /// this. Default 1e-4.
    pub tolerance: f64,
    /// Stop (reporting converged, with the residual in the stats) after this many steps. Default 100000.
    pub max_steps: u64,
    /// How leaves gather from the links above them. Default [`Gather::Leaf`].
    pub gather: Gather,
    /// Point answers: `constant` per leaf, `gouraud` (vertex-interpolated over each face's quadtree, T-vertices
    /// resolved) or `final-gather` (one more gather from every leaf with exact point-to-polygon factors and
    /// rays). Default [`DEFAULT_RECONSTRUCTION`].
    pub reconstruction: Reconstruction,
    /// Refuse to hold more links and elements than this many MiB. Default 4096.
    pub memory_budget_mib: f64,
}

/// Default reconstruction of point answers, chosen by measurement: `final-gather`. At the default ε = 0.01 on
/// the Cornell box (512 points against the path-traced reference) it gave relative L1 3.1% against 7.0%
/// (constant) and 6.8% (gouraud), and a worst point of 27% against 2798% and 1796% (floored max); volume
/// clusters at their default ε = 1e-4: 2.5% against 8.0% and 7.9%. On the room of scenes/room.toml (solve
/// stopped by a 120 s limit, about 9,500 leaves): 4.3% against 8.8% and 9.1%, worst point 2254% against 4122%
/// and 3963% (points in millimetre gaps under objects, which no reconstruction of these elements reaches). The
/// price is answering time: one point-to-polygon kernel per leaf and query plus rays (3.8 s for 512 points
/// over 6,245 leaves, 11 s over 9,449 in the room, on a loaded 2-core machine), so images of finely refined
/// solutions are slow; ask for `constant` to read the leaves themselves. Since links from inner sources send
/// their leaves' radiosity weighted by how much each sees the receiver (the quickstart, idle machine): 1.2%
/// against 4.3% constant at ε = 0.01, volume clusters 1.4% at ε = 1e-4; in the quickstart of 2026-12-02,
/// after later changes, 1.0% against 3.7%, worst point 39% against 2929%.
pub const DEFAULT_RECONSTRUCTION: Reconstruction = Reconstruction::FinalGather;

impl HierarchicalParams {
    /// The defaults: solve a room-sized scene to about a percent in seconds.
    pub const fn default_params() -> Self {
        Self {
            epsilon: 0.01,
            oracle: Oracle::Variation,
            error_norm: ErrorNorm::Radiosity,
            schedule: Schedule::Scheduled,
            alpha: 2.0,
            stages: 3,
            lazy_linking: true,
            min_element_size: None,
            visibility: VisibilitySampling::Jittered4x4,
            quadrature: 2,
            tolerance: 1e-4,
            max_steps: 100_000,
            gather: Gather::Leaf,
            reconstruction: DEFAULT_RECONSTRUCTION,
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

    /// A careful solution for reference tables: ε = 0.002, 8×8 rays, 3×3 quadrature, tolerance 1e-5.
    pub const fn reference() -> Self {
        let mut p = Self::default_params();
        p.epsilon = 0.002;
        p.visibility = VisibilitySampling::Jittered8x8;
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
    fn docs() -> Vec<(&'static str, &'static str)> {
        vec![
            (
                "epsilon",
                "refinement threshold on the oracle's estimate, dimensionless",
            ),
            (
                "oracle",
                "f (form factor) | bf (radiosity x form factor) | variation (spread of kernel samples, default)",
            ),
            (
                "error_norm",
                "radiosity (irradiance a link brings, relative to the mean; hierarchical's default) | power (times \
                 receiver area over scene area; volume-cluster's default)",
            ),
            (
                "schedule",
                "two-stage | interleaved | scheduled (default): how refinement and solution alternate",
            ),
            (
                "alpha",
                "scheduled: epsilon divided by alpha between stages, >= 1 (default 2)",
            ),
            (
                "stages",
                "scheduled: stages over which epsilon falls to its final value, >= 1 (default 3)",
            ),
            (
                "lazy_linking",
                "interleaved/scheduled: link from a face only once it carries light (default true)",
            ),
            (
                "min_element_size",
                "smallest element edge in scene units (default: scene diagonal / 150)",
            ),
            (
                "visibility",
                "rays per link: unoccluded | centre | jittered2x2 | jittered4x4 (default) | jittered8x8",
            ),
            (
                "quadrature",
                "Gauss points per side of the receiver quadrature, 1..=8 (default 2)",
            ),
            (
                "tolerance",
                "estimated relative error at which the solution stops (default 1e-4)",
            ),
            (
                "max_steps",
                "steps after which the solver stops (default 100000)",
            ),
            (
                "gather",
                "leaf (default: kernel at each leaf for every link above it) | link (classic: per-link mean, pushed)",
            ),
            (
                "reconstruction",
                "point answers: constant | gouraud (vertex-interpolated) | final-gather (one more gather from every \
                 leaf, exact point-to-polygon factors and rays; its cost is charged when answering); \
                 hierarchical's and volume-cluster's default is final-gather, chosen by measurement (Cornell box, 512 \
                 points, default epsilon, the quickstart of 2026-12-02: relative L1 1.0% against 3.7% constant for \
                 hierarchical, 1.4% for volume clusters; worst point 39% against 2929% constant); answering costs a kernel per \
                 leaf and query, so images of fine solutions are slow",
            ),
            (
                "memory_budget_mib",
                "refuse to hold more elements and links than this (default 4096)",
            ),
        ]
    }

    fn validate(&self) -> Result<(), SolveError> {
        let positive = |name: &str, x: f64| {
            if x.is_finite() && x > 0.0 {
                Ok(())
            } else {
                Err(SolveError::param(
                    name,
                    format!("{x} must be a finite number > 0"),
                ))
            }
        };
        positive("epsilon", self.epsilon)?;
        positive("tolerance", self.tolerance)?;
        positive("memory_budget_mib", self.memory_budget_mib)?;
        if !(self.alpha.is_finite() && self.alpha >= 1.0) {
            return Err(SolveError::param(
                "alpha",
                format!(
                    "{} must be a finite number >= 1 (epsilon is divided by alpha between stages)",
                    self.alpha
                ),
            ));
        }
        if self.stages == 0 || self.stages > 64 {
            return Err(SolveError::param(
                "stages",
                format!("{} must be within 1..=64", self.stages),
            ));
        }
        if let Some(s) = self.min_element_size {
            positive("min_element_size", s)?;
        }
        if !(1..=8).contains(&self.quadrature) {
            return Err(SolveError::param(
                "quadrature",
                format!(
                    "{} must be within 1..=8 (Gauss points per side)",
                    self.quadrature
                ),
            ));
        }
        if self.oracle == Oracle::Variation && self.quadrature < 2 {
            return Err(SolveError::param(
                "quadrature",
                "the variation oracle needs at least 2 Gauss points per side (with 1 it samples the centroid only)",
            ));
        }
        if self.max_steps == 0 {
            return Err(SolveError::param("max_steps", "must be at least 1"));
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
        ]
        .map(|(k, v)| (k.to_string(), v.to_string()));
        let p = HierarchicalParams::from_pairs(&pairs).expect("valid pairs");
        assert_eq!(p.oracle, Oracle::Variation);
        assert_eq!(p.schedule, Schedule::TwoStage);
        assert_eq!(p.min_element_size, Some(0.5));
        assert_eq!(p.reconstruction, Reconstruction::Gouraud);
        assert_eq!(p.visibility, VisibilitySampling::Centre);
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

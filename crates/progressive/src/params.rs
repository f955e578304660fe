//! Parameters of progressive radiosity, their documented defaults and range checks.
//!
//! Every length is in scene units and every default is relative to the scene's bounding-box diagonal
//! ([`DEFAULT_ELEMENT_SIZE_REL`]), so the same defaults mesh a 1 mm box and a 100 m hall
//! alike. The adaptive threshold is a relative radiosity contrast and the stopping rule a fraction of the
//! emitted power, so neither depends on the scene's scale or on its light's strength.

use radlab_answer::{AnswerParams, Reconstruction, element_size_or};
use radlab_kernels::form_factor::VisibilitySampling;
use radlab_method::{MethodParams, SolveError};
use radlab_scene::Scene;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Default element size as a fraction of the scene's bounding-box diagonal: 1/30, finer than matrix and mesh Monte
/// Carlo radiosity's 1/25 ([`radlab_answer::DEFAULT_ELEMENT_SIZE_REL`]). At 1/25 the Cornell box's floors and
/// walls answered 12% off at their worst point (the back wall a millimetre above the floor; 6% and 8% at seeds 2
/// and 3, as the order of equal shots moves it), at 1/30 8%, 5% and 8%, for 1.7 times the time there; the
/// furnished room takes about as long either way (docs/defaults.md).
pub const DEFAULT_ELEMENT_SIZE_REL: f64 = 1.0 / 30.0;

/// Progressive radiosity's default element size for `scene`: [`DEFAULT_ELEMENT_SIZE_REL`] × its bounding-box
/// diagonal.
pub fn default_element_size(scene: &Scene) -> f64 {
    DEFAULT_ELEMENT_SIZE_REL * scene.diagonal()
}
/// Default shooting patch size as a multiple of the element size: 1, every element shoots its own radiosity (no
/// substructuring). With patches of 2 × 2 elements (2, the default until 2026-12-06) a patch shot its mean
/// uniformly, and a receiver close to a patch with a shadow across it saw that mean: the furnished room's floor
/// under its ball answered 21% bright at its worst point and the Cornell box 14%, against 8% and 12% at 1 with
/// [`DEFAULT_QUADRATURE`] (docs/defaults.md).
pub const DEFAULT_PATCH_FACTOR: f64 = 1.0;
/// Default receiver quadrature, m × m points per element: 2. With every element shooting, one point (the
/// centroid) answered a ρ = 0.9 room +0.58% bright on the whole, 2 × 2 points −0.10% (docs/defaults.md).
pub const DEFAULT_QUADRATURE: u32 = 2;
/// Default smallest element adaptive subdivision may create, as a fraction of the element size (two levels).
pub const DEFAULT_MIN_ELEMENT_FACTOR: f64 = 0.25;
/// Default relative contrast between neighbouring elements above which both are split.
pub const DEFAULT_ADAPTIVE_THRESHOLD: f64 = 0.3;
/// Default stopping rule: stop once the unshot power is below this fraction of the emitted power.
pub const DEFAULT_STOP_UNSHOT_FRACTION: f64 = 2e-3;
/// Default memory the solver may hold for its elements, patches and neighbour lists, in MiB.
pub const DEFAULT_MEMORY_BUDGET_MIB: f64 = 2048.0;

/// What a shot sends.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum Overshoot {
    /// Plain Southwell shooting (Cohen, Chen, Wallace & Greenberg 1988): a patch sends exactly its unshot
    /// radiosity ΔB_j, so unshot radiosity stays non-negative and falls monotonically.
    None,
    /// Ambient overshooting (Feda & Purgathofer 1992; analysed as over-relaxed Southwell iteration by Gortler,
    /// Cohen & Slusallek 1993): a patch light has reached sends ΔB_j + ρ_j B_amb, its unshot radiosity plus an
    /// estimate of what it will still receive (the ambient radiosity of Cohen et al. 1988 with a measured
    /// interreflection factor); unshot radiosity may go negative and later shots correct it. Same fixed point.
    #[default]
    Ambient,
}

/// Parameters of [`crate::ProgressiveSolver`], each declared once: its doc comment's first paragraph is the
/// help `radlab methods` prints, its `schemars` attribute the accepted range, and its default is in
/// `impl Default`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct ProgressiveParams {
    /// Receiving element size (longest edge, scene units); unset: 1/30 of the scene's bounding diagonal
    /// ([`DEFAULT_ELEMENT_SIZE_REL`]).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub element_size: Option<f64>,
    /// Shooting patch size (scene units), at least element_size; larger shoots from patches of several
    /// elements (substructuring); unset: element_size ([`DEFAULT_PATCH_FACTOR`]), every element shoots.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub patch_size: Option<f64>,
    /// Shots per call of step(); the answer does not depend on it, only the granularity of a trace.
    #[schemars(range(min = 1))]
    pub shots_per_step: u32,
    /// Visibility rays between a receiving element and a shooting patch that emits (direct light, hence
    /// shadows).
    pub visibility: VisibilitySampling,
    /// Visibility rays for shots from patches that do not emit (interreflected light, smoother); when both
    /// settings are jittered, each element also gets its open share (128 rays: the part not sealed under a
    /// touching panel).
    pub indirect_visibility: VisibilitySampling,
    /// Receiver quadrature: m × m points per element at which the point-to-polygon factor is evaluated (1: the
    /// centroid); default 2 ([`DEFAULT_QUADRATURE`]).
    #[schemars(range(min = 1, max = 16))]
    pub quadrature: u32,
    /// Stop once the unshot power is at most this fraction of the emitted power (worst channel); use
    /// max_shots to run a fixed number of shots.
    #[schemars(range(max = 1), extend("exclusiveMinimum" = 0))]
    pub stop_unshot_fraction: f64,
    /// Stop after this many shots whatever the unshot power; unset: no limit.
    #[schemars(range(min = 1))]
    pub max_shots: Option<u64>,
    /// Split elements across radiosity contrasts above adaptive_threshold.
    pub adaptive: bool,
    /// Relative contrast |B_a − B_b| / max(B_a, B_b) (channel sums) between neighbouring elements of a face
    /// above which both are split; set adaptive = false to turn subdivision off.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub adaptive_threshold: f64,
    /// Smallest element edge adaptive subdivision may create (scene units); unset: element_size / 4.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub min_element_size: Option<f64>,
    /// Add the ambient term (Cohen et al. 1988) to displayed radiosity.
    ///
    /// Off by default: it is an estimate, not part of the solution, and is kept out of error measurements
    /// unless asked for.
    pub ambient: bool,
    /// Memory the solver may hold (MiB); a mesh or refinement beyond it is an error.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub memory_budget_mib: f64,
    /// What a shot sends: none (plain Southwell shooting, the unshot radiosity) or ambient (the unshot
    /// radiosity plus the ambient estimate of what the patch will still receive, Feda & Purgathofer 1992).
    ///
    /// Ambient overshooting needs far fewer shots at high reflectance (see the crate documentation).
    pub overshoot: Overshoot,
    /// How points are answered: reconstruction and gather_opening, declared once in radlab-answer.
    #[serde(flatten)]
    pub answer: AnswerParams,
}

/// Default reconstruction of point answers, chosen by measurement (see the crate documentation).
pub const DEFAULT_RECONSTRUCTION: Reconstruction = Reconstruction::FinalGather;

impl Default for ProgressiveParams {
    fn default() -> Self {
        Self {
            element_size: None,
            patch_size: None,
            shots_per_step: 1,
            visibility: VisibilitySampling::Jittered4x4,
            indirect_visibility: VisibilitySampling::Jittered2x2,
            quadrature: DEFAULT_QUADRATURE,
            stop_unshot_fraction: DEFAULT_STOP_UNSHOT_FRACTION,
            max_shots: None,
            adaptive: true,
            adaptive_threshold: DEFAULT_ADAPTIVE_THRESHOLD,
            min_element_size: None,
            ambient: false,
            memory_budget_mib: DEFAULT_MEMORY_BUDGET_MIB,
            overshoot: Overshoot::default(),
            answer: AnswerParams {
                reconstruction: DEFAULT_RECONSTRUCTION,
                ..AnswerParams::default()
            },
        }
    }
}

impl ProgressiveParams {
    /// Settings under which progressive radiosity solves the matrix method's discretisation on the regular mesh
    /// of `element_size` (no substructuring, no adaptive subdivision, one visibility estimate for every pair),
    /// to a tight tolerance: for cross-checks against `radlab-matrix` (set the same `quadrature` in both).
    pub fn fixed_mesh(element_size: f64, visibility: VisibilitySampling) -> Self {
        Self {
            element_size: Some(element_size),
            patch_size: Some(element_size),
            visibility,
            indirect_visibility: visibility,
            adaptive: false,
            stop_unshot_fraction: 1e-6,
            ..Self::default()
        }
    }
}

/// Lengths resolved against a scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Resolved {
    pub element_size: f64,
    pub patch_size: f64,
    pub min_element_size: f64,
}

impl ProgressiveParams {
    /// The lengths for `scene`, checked against each other.
    pub(crate) fn resolve(&self, scene: &Scene) -> Result<Resolved, SolveError> {
        self.validate()?;
        let element_size = element_size_or(self.element_size, DEFAULT_ELEMENT_SIZE_REL, scene)?;
        let patch_size = self
            .patch_size
            .unwrap_or(DEFAULT_PATCH_FACTOR * element_size);
        if patch_size < element_size {
            return Err(SolveError::param(
                "patch_size",
                format!(
                    "{patch_size} is smaller than element_size {element_size}; patches shoot and elements \
                     receive, so a patch must be at least one element (set patch_size = element_size to turn \
                     substructuring off)"
                ),
            ));
        }
        let min_element_size = self
            .min_element_size
            .unwrap_or(DEFAULT_MIN_ELEMENT_FACTOR * element_size);
        if min_element_size > element_size {
            return Err(SolveError::param(
                "min_element_size",
                format!(
                    "{min_element_size} is larger than element_size {element_size}; adaptive subdivision \
                     only makes elements smaller"
                ),
            ));
        }
        Ok(Resolved {
            element_size,
            patch_size,
            min_element_size,
        })
    }
}

impl MethodParams for ProgressiveParams {
    /// An opening other than the default is refused under answers other than a final gather.
    fn check_combination(&self) -> Result<(), SolveError> {
        self.answer.check(&Self::default().answer)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pairs(kv: &[(&str, &str)]) -> Vec<(String, String)> {
        kv.iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
    }

    #[test]
    fn defaults_validate_and_parse_from_pairs() {
        assert!(ProgressiveParams::default().validate().is_ok());
        let p = ProgressiveParams::from_pairs(&pairs(&[
            ("visibility", "centre"),
            ("element_size", "0.1"),
            ("adaptive", "false"),
            ("max_shots", "10"),
            ("overshoot", "none"),
        ]))
        .expect("valid");
        assert_eq!(p.overshoot, Overshoot::None);
        assert_eq!(p.visibility, VisibilitySampling::Centre);
        assert_eq!(p.element_size, Some(0.1));
        assert!(!p.adaptive);
        assert_eq!(p.max_shots, Some(10));
        for d in ProgressiveParams::declarations() {
            assert!(!d.help.is_empty(), "{} undocumented", d.name);
        }
    }

    #[test]
    fn bad_values_name_the_parameter() {
        for (k, v) in [
            ("element_size", "-1"),
            ("element_size", "nan"),
            ("patch_size", "0"),
            ("min_element_size", "inf"),
            ("shots_per_step", "0"),
            ("quadrature", "0"),
            ("quadrature", "17"),
            ("stop_unshot_fraction", "0"),
            ("stop_unshot_fraction", "1.5"),
            ("max_shots", "0"),
            ("adaptive_threshold", "-0.1"),
            ("memory_budget_mib", "0"),
            ("visibility", "sometimes"),
            ("overshoot", "sor"),
            ("shots_per_step", "-3"),
            ("reconstruction", "smooth"),
        ] {
            let e = ProgressiveParams::from_pairs(&pairs(&[(k, v)]))
                .expect_err(k)
                .to_string();
            assert!(e.contains(&format!("'{k}'")), "{k}={v}: {e}");
        }
        let e = ProgressiveParams::from_pairs(&pairs(&[("elementsize", "1")]))
            .expect_err("unknown")
            .to_string();
        assert!(
            e.contains("elementsize") && e.contains("element_size"),
            "{e}"
        );
    }

    #[test]
    fn lengths_resolve_against_each_other() {
        let scene = radlab_scene::builtin("furnace-cube").expect("scene");
        let r = ProgressiveParams::default().resolve(&scene).expect("ok");
        assert!((r.element_size - default_element_size(&scene)).abs() < 1e-15);
        assert!((r.patch_size - DEFAULT_PATCH_FACTOR * r.element_size).abs() < 1e-15);
        assert!((r.min_element_size - 0.25 * r.element_size).abs() < 1e-15);
        let p = ProgressiveParams {
            element_size: Some(0.2),
            patch_size: Some(0.1),
            ..Default::default()
        };
        let e = p.resolve(&scene).expect_err("patch < element").to_string();
        assert!(e.contains("'patch_size'"), "{e}");
        let p = ProgressiveParams {
            element_size: Some(0.2),
            min_element_size: Some(0.3),
            ..Default::default()
        };
        let e = p.resolve(&scene).expect_err("min > element").to_string();
        assert!(e.contains("'min_element_size'"), "{e}");
    }
}

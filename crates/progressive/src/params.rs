//! Parameters of progressive radiosity, their documented defaults and range checks.
//!
//! Every length is in scene units and every default is relative to the scene's bounding-box diagonal
//! (through [`radlab_answer::default_element_size`]), so the same defaults mesh a 1 mm box and a 100 m hall
//! alike. The adaptive threshold is a relative radiosity contrast and the stopping rule a fraction of the
//! emitted power, so neither depends on the scene's scale or on its light's strength.

use radlab_answer::{Reconstruction, default_element_size};
use radlab_kernels::form_factor::VisibilitySampling;
use radlab_method::{MethodParams, SolveError};
use radlab_scene::Scene;
use serde::{Deserialize, Serialize};

/// Default shooting patch size as a multiple of the element size: each patch shoots from about 2 × 2 elements.
pub const DEFAULT_PATCH_FACTOR: f64 = 2.0;
/// Default smallest element adaptive subdivision may create, as a fraction of the element size (two levels).
pub const DEFAULT_MIN_ELEMENT_FACTOR: f64 = 0.25;
/// Default relative contrast between neighbouring elements above which both are split.
pub const DEFAULT_ADAPTIVE_THRESHOLD: f64 = 0.3;
/// Default stopping rule: stop once the unshot power is below this fraction of the emitted power.
pub const DEFAULT_STOP_UNSHOT_FRACTION: f64 = 2e-3;
/// Default memory the solver may hold for its elements, patches and neighbour lists, in MiB.
pub const DEFAULT_MEMORY_BUDGET_MIB: f64 = 2048.0;

/// What a shot sends.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
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

/// Parameters of [`crate::ProgressiveSolver`]. Every field has a documented default (see [`MethodParams::docs`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ProgressiveParams {
    /// Receiving element size (longest edge, scene units). Default: 1/20 of the scene's bounding diagonal.
    pub element_size: Option<f64>,
    /// Shooting patch size (scene units), at least `element_size`; equal to it turns substructuring off.
    /// Default: [`DEFAULT_PATCH_FACTOR`] × element size.
    pub patch_size: Option<f64>,
    /// Shots per call of `step()` (the answer does not depend on it, only the granularity of a trace). Default 1.
    pub shots_per_step: u32,
    /// Visibility estimate between a receiving element and a shooting patch that emits (direct light, hence
    /// shadows). Default `jittered4x4` (16 rays).
    pub visibility: VisibilitySampling,
    /// Visibility estimate for shots from patches that do not emit (interreflected light, smoother). Default
    /// `jittered2x2` (4 rays).
    pub indirect_visibility: VisibilitySampling,
    /// Receiver quadrature: m × m points per element at which the point-to-polygon factor is evaluated. Default 1
    /// (the centroid).
    pub quadrature: u32,
    /// Stop once the unshot power is at most this fraction of the emitted power (worst channel). Default 2e-3.
    pub stop_unshot_fraction: f64,
    /// Stop after this many shots whatever the unshot power. Default: no limit.
    pub max_shots: Option<u64>,
    /// Adaptive subdivision of elements across large radiosity contrasts. Default on.
    pub adaptive: bool,
    /// Relative contrast |B_a − B_b| / max(B_a, B_b) (channel sums) between neighbouring elements of a face
    /// above which both are split. Default [`DEFAULT_ADAPTIVE_THRESHOLD`].
    pub adaptive_threshold: f64,
    /// Smallest element edge adaptive subdivision may create (scene units). Default: element size / 4.
    pub min_element_size: Option<f64>,
    /// Add the ambient term (Cohen et al. 1988) to displayed radiosity. Default off: it is an estimate, not part
    /// of the solution, and is kept out of error measurements unless asked for.
    pub ambient: bool,
    /// Memory the solver may hold (MiB); a mesh or refinement beyond it is an error. Default 2048.
    pub memory_budget_mib: f64,
    /// What a shot sends: `none` (plain shooting) or `ambient` (overshooting). Default `ambient`, which needs
    /// far fewer shots at high reflectance (see the crate documentation for measurements).
    pub overshoot: Overshoot,
    /// How radiosity at a point is answered from the element values: `constant`, `gouraud` or
    /// `final-gather` (radlab_answer::reconstruction). Default [`DEFAULT_RECONSTRUCTION`].
    pub reconstruction: Reconstruction,
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
            quadrature: 1,
            stop_unshot_fraction: DEFAULT_STOP_UNSHOT_FRACTION,
            max_shots: None,
            adaptive: true,
            adaptive_threshold: DEFAULT_ADAPTIVE_THRESHOLD,
            min_element_size: None,
            ambient: false,
            memory_budget_mib: DEFAULT_MEMORY_BUDGET_MIB,
            overshoot: Overshoot::default(),
            reconstruction: DEFAULT_RECONSTRUCTION,
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

fn positive_length(name: &str, v: Option<f64>) -> Result<(), SolveError> {
    match v {
        Some(x) if !(x.is_finite() && x > 0.0) => Err(SolveError::param(
            name,
            format!("{x} is not a finite length > 0 (scene units); leave it unset for the default"),
        )),
        _ => Ok(()),
    }
}

impl ProgressiveParams {
    /// The lengths for `scene`, checked against each other.
    pub(crate) fn resolve(&self, scene: &Scene) -> Result<Resolved, SolveError> {
        self.validate()?;
        let element_size = match self.element_size {
            Some(x) => x,
            None => default_element_size(scene),
        };
        if !(element_size.is_finite() && element_size > 0.0) {
            return Err(SolveError::param(
                "element_size",
                format!(
                    "the default element size {element_size} is unusable for scene '{}' (bounding diagonal {}); \
                     set element_size explicitly",
                    scene.name,
                    scene.diagonal()
                ),
            ));
        }
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
    fn docs() -> Vec<(&'static str, &'static str)> {
        vec![
            (
                "element_size",
                "receiving element size, scene units (default: 1/20 of the scene's bounding diagonal)",
            ),
            (
                "patch_size",
                "shooting patch size, >= element_size; equal turns substructuring off (default: 2 x element_size)",
            ),
            (
                "shots_per_step",
                "shots per step(); does not change the answer (default 1)",
            ),
            (
                "visibility",
                "visibility between a receiving element and an emitting shooter (direct light): unoccluded | \
                 centre | jittered2x2 | jittered4x4 | jittered8x8 (default jittered4x4, 16 rays)",
            ),
            (
                "indirect_visibility",
                "visibility for shots from patches that do not emit (interreflection), same choices \
                 (default jittered2x2, 4 rays); when both settings are jittered, each element also gets its \
                 open share (128 rays: the part not sealed under a touching panel)",
            ),
            (
                "quadrature",
                "m: m x m receiver points per element for the point-to-polygon factor, 1..16 (default 1)",
            ),
            (
                "stop_unshot_fraction",
                "stop when unshot power <= this fraction of emitted power, (0, 1] (default 2e-3)",
            ),
            (
                "max_shots",
                "stop after this many shots (default: no limit)",
            ),
            (
                "adaptive",
                "split elements across radiosity contrasts above adaptive_threshold (default true)",
            ),
            (
                "adaptive_threshold",
                "relative contrast |Ba - Bb| / max(Ba, Bb) between neighbours that splits them, > 0 (default 0.3)",
            ),
            (
                "min_element_size",
                "smallest element edge adaptive subdivision creates (default: element_size / 4)",
            ),
            (
                "ambient",
                "add the ambient term of Cohen et al. 1988 to displayed radiosity (default false)",
            ),
            (
                "memory_budget_mib",
                "memory the solver may hold, MiB (default 2048)",
            ),
            (
                "overshoot",
                "what a shot sends: none (plain Southwell shooting, unshot radiosity only) | ambient (unshot plus \
                 the ambient estimate of what the patch will still receive, Feda & Purgathofer 1992) \
                 (default ambient)",
            ),
            (
                "reconstruction",
                "point answers from the element values: constant | gouraud (vertex-interpolated) | \
                 final-gather (one more gather with exact point-to-polygon factors and rays, counted in the \
                 answering cost); default final-gather (Cornell box, 512 points: relative L1 2.2% against 8.5% constant and \
                 7.2% gouraud at 110 mm elements; a gather costs rays per query, so images of large meshes are slow)",
            ),
        ]
    }

    fn validate(&self) -> Result<(), SolveError> {
        positive_length("element_size", self.element_size)?;
        positive_length("patch_size", self.patch_size)?;
        positive_length("min_element_size", self.min_element_size)?;
        if self.shots_per_step == 0 {
            return Err(SolveError::param("shots_per_step", "must be at least 1"));
        }
        if !(1..=16).contains(&self.quadrature) {
            return Err(SolveError::param(
                "quadrature",
                format!(
                    "{} is outside 1..=16 (m x m receiver points per element)",
                    self.quadrature
                ),
            ));
        }
        let f = self.stop_unshot_fraction;
        if !(f.is_finite() && f > 0.0 && f <= 1.0) {
            return Err(SolveError::param(
                "stop_unshot_fraction",
                format!(
                    "{f} is outside (0, 1]; it is the fraction of emitted power left unshot at which to stop \
                     (use max_shots to run a fixed number of shots)"
                ),
            ));
        }
        if self.max_shots == Some(0) {
            return Err(SolveError::param(
                "max_shots",
                "must be at least 1 (leave it unset for no limit)",
            ));
        }
        let t = self.adaptive_threshold;
        if !(t.is_finite() && t > 0.0) {
            return Err(SolveError::param(
                "adaptive_threshold",
                format!(
                    "{t} is not a finite relative contrast > 0 (e.g. 0.3); set adaptive = false to turn \
                     subdivision off"
                ),
            ));
        }
        let m = self.memory_budget_mib;
        if !(m.is_finite() && m > 0.0) {
            return Err(SolveError::param(
                "memory_budget_mib",
                format!("{m} is not a finite number of MiB > 0"),
            ));
        }
        Ok(())
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
        let names: Vec<&str> = ProgressiveParams::docs().iter().map(|d| d.0).collect();
        for (k, _) in ProgressiveParams::default_values() {
            assert!(names.contains(&k.as_str()), "{k} undocumented");
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
        assert!((r.patch_size - 2.0 * r.element_size).abs() < 1e-15);
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

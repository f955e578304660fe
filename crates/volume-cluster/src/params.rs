//! Parameters of volume-clustered hierarchical radiosity: the cluster transfer mode, and every parameter of
//! the hierarchical engine it runs on (radlab-hierarchical's [`HierarchicalParams`], same names, same
//! defaults, same checks), so the oracles, schedules, visibility sampling and output work as they do for
//! patches.

use radlab_answer::{AnswerParams, NearValues};
use radlab_hierarchical::{ErrorNorm, HierarchicalParams};
use radlab_method::{MethodParams, SolveError};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// How light crosses a link with a cluster end.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum Transfer {
    /// A cluster acts as projected area A/4 in every direction (Smits et al. 1994 β links; Sillion 1995
    /// isotropic clusters). O(1) per link; a flat cluster facing a light gets a quarter of the truth.
    Isotropic,
    /// A cluster source sends its faces' Σ A_i max(0, n_i·d) B_i toward the receiver exactly (summing its faces
    /// where its normal cone straddles d), a cluster receiver hands each face its own cosine share through the
    /// normal cones (Smits et al. 1994 α links; Sillion 1995 oriented clusters). O(1) per link but for
    /// straddling ends; the default: its exact source gives it the lowest error of the three, by little since
    /// it shares directional's receiver (concentric spheres, 1e3 / 3e3 faces, ρ = 0.5: mean |B − 2|/2 0.126 /
    /// 0.189% against directional's 0.135 / 0.199%; the Cornell box alike within 0.01%).
    #[default]
    Alpha,
    /// Clusters keep order-2 spherical-harmonic descriptions of the intensity they send and the irradiance
    /// they receive; faces are reached only through push. O(1) per link.
    Directional,
}

/// Whether the discrete operator's rows are rescaled to sum to one in a closed scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum RowNormalisation {
    /// Where the enclosure rays find the scene closed (every ray from every face hits the front of a face),
    /// each leaf's gathered irradiance is divided by its row sum, so every row sums to exactly one as the
    /// exact form factors of an enclosure do (Goral et al. 1984). Cluster links' point approximations leave
    /// row defects of about 1e-3 (α, directional) to 1e-1 (isotropic, inner faces of the concentric
    /// spheres), which the furnace B = E/(1 − ρ) multiplies by ρ/(1 − ρ): 1000 at ρ = 0.999. Open scenes
    /// are left alone. Not the default: with it a closed furnace holds by construction, whatever the
    /// transfer, so the furnace would no longer test the transfer.
    ClosedScenes,
    /// Never: the rows are what the transfer computes. The default.
    #[default]
    Off,
}

/// Parameters of [`crate::VolumeClusterSolver`]: its own, and the hierarchical engine's flattened in (all but
/// `lazy_linking`), each declared once on its field (doc comment: help; `schemars` attribute: range; default:
/// `impl Default`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(default)]
pub struct VolumeClusterParams {
    /// How light crosses a link with a cluster end: isotropic (a cluster is projected area A/4 every way),
    /// alpha (per-face cosines through normal cones, exact sources) or directional (alpha's receiver,
    /// spherical-harmonic sources).
    pub transfer: Transfer,
    /// off (the rows are what the transfer computes) or closed-scenes (where every enclosure ray hits the
    /// front of a face, each leaf's row is rescaled to sum to one, as an enclosure's form factors do).
    ///
    /// With closed-scenes a closed furnace holds by construction, whatever the transfer.
    pub row_normalisation: RowNormalisation,
    /// The widest normal cone (half-angle, degrees) at which a cluster straddled by a link takes it whole
    /// under alpha and directional, every face receiving the faces' mean clamped cosine; 0 hands every
    /// straddled link down to the faces.
    ///
    /// Every face below it receives the faces' mean clamped cosine
    /// ([`crate::normal_cone::NormalCone::mean_clamped_cosine`], within sin(2θ)/2 of a face square to the
    /// link for θ ≤ 45°). Wider straddled clusters hand the link to their children, down to the faces where
    /// the surface turns away from the source: on a smooth surface about √m of a cluster's m faces, a cost per
    /// link that grows with the number of faces.
    #[schemars(range(min = 0), extend("exclusiveMaximum" = 90))]
    pub straddle_angle: f64,
    /// The hierarchical engine's parameters (ε, oracle, schedule, visibility, gather, interpolation, …).
    #[serde(flatten)]
    pub engine: HierarchicalParams,
}

impl Default for VolumeClusterParams {
    /// The engine's defaults, but ε bounds the power a link carries ([`ErrorNorm::Power`]): with the
    /// radiosity norm every face, however small, would need links accurate to ε of its own light, which
    /// drives links back down to the faces and the k² of plain hierarchical radiosity.
    fn default() -> Self {
        Self {
            transfer: Transfer::default(),
            row_normalisation: RowNormalisation::default(),
            straddle_angle: DEFAULT_STRADDLE_ANGLE,
            engine: HierarchicalParams {
                error_norm: ErrorNorm::Power,
                epsilon: DEFAULT_EPSILON,
                // Near values: the elements near the point that pass on most of a value's error (factor ≥
                // 0.01) read their values gathered once more, where the clusters' values under a scanned
                // mesh left the floor 19% bright (chosen on the suite, docs/defaults.md).
                answer: AnswerParams {
                    near_values: NearValues::Regathered,
                    ..HierarchicalParams::default().answer
                },
                ..HierarchicalParams::default()
            },
        }
    }
}

/// Default ε (power norm): a link may carry up to this fraction of the scene's power.
pub const DEFAULT_EPSILON: f64 = 1e-4;

/// Default [`VolumeClusterParams::straddle_angle`], in degrees.
pub const DEFAULT_STRADDLE_ANGLE: f64 = 5.0;

impl MethodParams for VolumeClusterParams {
    const REFUSED: &'static [(&'static str, &'static str)] = &[(
        "lazy_linking",
        "volume clusters start from one root self-link, so there are no initial links to make lazily; \
         remove the parameter",
    )];

    fn check_combination(&self) -> Result<(), SolveError> {
        self.engine.check_engine(&Self::default().engine.answer)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transfer_and_engine_keys_parse_and_unknown_keys_are_named() {
        let p = VolumeClusterParams::from_pairs(&[
            ("transfer".into(), "isotropic".into()),
            ("epsilon".into(), "0.05".into()),
        ])
        .expect("valid");
        assert_eq!(p.transfer, Transfer::Isotropic);
        assert_eq!(p.engine.epsilon, 0.05);
        for (k, v) in [
            ("transfer", "sideways"),
            ("epsilon", "-1"),
            ("nope", "1"),
            ("straddle_angle", "90"),
            ("straddle_angle", "-1"),
            ("straddle_angle", "nan"),
            ("straddle_angle", "\"wide\""),
        ] {
            let e = VolumeClusterParams::from_pairs(&[(k.into(), v.into())])
                .expect_err("rejected")
                .to_string();
            assert!(e.contains(k), "{k}={v}: {e}");
        }
        let decls = VolumeClusterParams::declarations();
        let default = |name: &str| {
            decls
                .iter()
                .find(|d| d.name == name)
                .map(|d| d.default.clone())
        };
        assert_eq!(
            default("epsilon"),
            Some(DEFAULT_EPSILON.to_string()),
            "listed epsilon default"
        );
        assert_eq!(default("error_norm").as_deref(), Some("power"));
        assert_eq!(
            default("gather_opening"),
            Some(radlab_answer::DEFAULT_GATHER_OPENING.to_string())
        );
        // The opening changes only a final gather: another value under other answers is refused, naming the
        // fix; the default is not.
        let e = VolumeClusterParams::from_pairs(&[
            ("reconstruction".into(), "gouraud".into()),
            ("gather_opening".into(), "0.1".into()),
        ])
        .expect_err("refused")
        .to_string();
        assert!(
            e.contains("gather_opening") && e.contains("final-gather"),
            "{e}"
        );
        VolumeClusterParams::from_pairs(&[("reconstruction".into(), "gouraud".into())])
            .expect("the default opening stands under gouraud");
        assert_eq!(default("lazy_linking"), None, "refused, not listed");
        let e = VolumeClusterParams::from_pairs(&[("lazy_linking".into(), "true".into())])
            .expect_err("refused")
            .to_string();
        assert!(e.contains("lazy_linking") && e.contains("remove"), "{e}");
        // Only the keys given are overridden; the rest keep this method's defaults.
        let p =
            VolumeClusterParams::from_pairs(&[("quadrature".into(), "3".into())]).expect("valid");
        assert_eq!(p.engine.epsilon, DEFAULT_EPSILON);
        assert_eq!(p.engine.error_norm, ErrorNorm::Power);
    }
}

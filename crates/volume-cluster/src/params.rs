//! Parameters of volume-clustered hierarchical radiosity: the cluster transfer mode, and every parameter of
//! the hierarchical engine it runs on (radlab-hierarchical's [`HierarchicalParams`], same names, same
//! defaults, same checks), so the oracles, schedules, visibility sampling and output work as they do for
//! patches.

use radlab_hierarchical::{ErrorNorm, HierarchicalParams};
use radlab_method::{MethodParams, SolveError};
use serde::{Deserialize, Serialize};

/// How light crosses a link with a cluster end.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
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
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
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

/// Parameters of [`crate::VolumeClusterSolver`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VolumeClusterParams {
    /// Cluster transfer. Default [`Transfer::Alpha`].
    pub transfer: Transfer,
    /// Row normalisation. Default [`RowNormalisation::Off`].
    pub row_normalisation: RowNormalisation,
    /// The widest normal cone, as a half-angle in degrees, at which a receiving cluster that a link straddles
    /// (some of its faces turned toward the source, some away) takes the link as a whole under the α and
    /// directional transfers: every face below it receives the faces' mean clamped cosine
    /// ([`crate::normal_cone::NormalCone::mean_clamped_cosine`], within sin(2θ)/2 of a face square to the
    /// link for θ ≤ 45°). Wider straddled clusters hand the link to their children, down to the faces where the surface
    /// turns away from the source: on a smooth surface about √m of a cluster's m faces, a cost per link that
    /// grows with the number of faces. 0 takes every straddled link down to the faces. Default
    /// 5 (`DEFAULT_STRADDLE_ANGLE`).
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
    fn docs() -> Vec<(&'static str, &'static str)> {
        let mut d = vec![(
            "transfer",
            "isotropic (A/4 clusters) | alpha (default: per-face cosines through normal cones, exact sources) | \
             directional (the same receiver, spherical-harmonic sources): how light crosses a link with a cluster \
             end",
        )];
        d.push((
            "row_normalisation",
            "off (default: the rows are what the transfer computes) | closed-scenes (where every enclosure ray \
             hits the front of a face, each leaf's row is rescaled to sum to one, as an enclosure's form factors \
             do; a closed furnace then holds by construction)",
        ));
        d.push((
            "straddle_angle",
            "the widest normal cone (half-angle, degrees, in [0, 90)) at which a cluster straddled by a link takes \
             it whole, every face receiving the faces' mean clamped cosine, under alpha and directional (default \
             5; 0 hands every straddled link down to the faces, at a cost per link growing with the face count)",
        ));
        d.extend(
            HierarchicalParams::docs()
                .into_iter()
                .filter(|(k, _)| *k != "lazy_linking")
                .map(|(k, v)| match k {
                    "epsilon" => (
                        k,
                        "refinement threshold: the largest power a link may carry unresolved, as a fraction of \
                         the scene's (default 1e-4)",
                    ),
                    "error_norm" => (
                        k,
                        "power (default: a link's estimate times its receiver's share of the scene's area) | \
                         radiosity (irradiance relative to the mean; drives links down to every face)",
                    ),
                    _ => (k, v),
                }),
        );
        d
    }

    fn validate(&self) -> Result<(), SolveError> {
        if !(self.straddle_angle >= 0.0 && self.straddle_angle < 90.0) {
            return Err(SolveError::param(
                "straddle_angle",
                format!(
                    "{} is not a half-angle in degrees in [0, 90); use e.g. {DEFAULT_STRADDLE_ANGLE} \
                     (the default), or 0 to take straddled links down to the faces",
                    self.straddle_angle
                ),
            ));
        }
        self.engine.validate()
    }

    fn default_values() -> Vec<(String, String)> {
        let transfer = toml::Value::try_from(Transfer::default())
            .map_or_else(|_| String::new(), |v| v.to_string());
        let rows = toml::Value::try_from(RowNormalisation::default())
            .map_or_else(|_| String::new(), |v| v.to_string());
        let mut v = vec![
            ("transfer".to_string(), transfer),
            ("row_normalisation".to_string(), rows),
            (
                "straddle_angle".to_string(),
                toml::Value::Float(DEFAULT_STRADDLE_ANGLE).to_string(),
            ),
        ];
        // This method's own engine defaults (ε and the error norm differ from hierarchical's).
        if let Ok(toml::Value::Table(t)) = toml::Value::try_from(Self::default().engine) {
            v.extend(
                t.into_iter()
                    .filter(|(k, _)| k != "lazy_linking")
                    .map(|(k, x)| (k, x.to_string())),
            );
        }
        v
    }

    /// Takes `transfer` out and reads the rest as the engine's parameters, so an unknown key is named by the
    /// engine's strict reader.
    fn from_table(mut table: toml::Table) -> Result<Self, SolveError> {
        let transfer = own_key(
            &mut table,
            "transfer",
            "use isotropic, alpha or directional",
        )?;
        let row_normalisation =
            own_key(&mut table, "row_normalisation", "use closed-scenes or off")?;
        let straddle_angle = own_key::<Option<f64>>(
            &mut table,
            "straddle_angle",
            "use a half-angle in degrees such as 5",
        )?
        .unwrap_or(DEFAULT_STRADDLE_ANGLE);
        if table.remove("lazy_linking").is_some() {
            return Err(SolveError::param(
                "lazy_linking",
                "volume clusters start from one root self-link, so there are no initial links to make lazily; \
                 remove the parameter",
            ));
        }
        // The user's keys over this method's defaults, read by the engine's strict reader.
        let mut full = toml::Table::try_from(Self::default().engine)
            .map_err(|e| SolveError::param("parameters", e.to_string()))?;
        full.extend(table);
        let engine = HierarchicalParams::from_table(full)?;
        let p = Self {
            transfer,
            row_normalisation,
            straddle_angle,
            engine,
        };
        p.validate()?;
        Ok(p)
    }
}

/// Takes `key` out of `table` and reads it as a `T` (its default if absent); `fix` says how to fix a bad
/// value.
fn own_key<T: serde::de::DeserializeOwned + Default>(
    table: &mut toml::Table,
    key: &str,
    fix: &str,
) -> Result<T, SolveError> {
    let Some(v) = table.remove(key) else {
        return Ok(T::default());
    };
    v.try_into::<T>()
        .map_err(|e| SolveError::param(key, format!("{}; {fix}", e.message())))
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
        let defaults = VolumeClusterParams::default_values();
        let eps = defaults
            .iter()
            .find(|(k, _)| k == "epsilon")
            .map(|(_, v)| v.as_str());
        assert_eq!(
            eps,
            Some(&*DEFAULT_EPSILON.to_string()),
            "listed epsilon default"
        );
        let norm = defaults
            .iter()
            .find(|(k, _)| k == "error_norm")
            .map(|(_, v)| v.as_str());
        assert_eq!(norm, Some("\"power\""), "listed error_norm default");
        let names: Vec<&str> = VolumeClusterParams::docs().iter().map(|d| d.0).collect();
        for (k, _) in VolumeClusterParams::default_values() {
            assert!(names.contains(&k.as_str()), "{k} undocumented");
        }
    }
}

//! Builtin scenes, addressed as `builtin:NAME[?k=v&...]`. Each has documented parameters with defaults;
//! unknown names and parameters are errors that list what exists.

mod analytic;
mod cornell;
mod detailed_meshes;
mod furnace_sphere;
pub mod primitives;
pub mod spectrum_rgb;

pub use cornell::{cornell_fov_deg, cornell_light_exitance, cornell_reflectances};
pub use spectrum_rgb::{
    linear_srgb_to_xyz, reflectance_rgb_from_xyz, reflectance_xyz_from_rgb, xyy_to_xyz,
};

use glam::DVec3;

use crate::{Rgb, Scene, SceneError};

/// A builtin scene's parameter: name, default, documentation.
pub type BuiltinParam = (&'static str, &'static str, &'static str);

/// Description of one builtin scene.
pub struct BuiltinInfo {
    /// Its name after `builtin:`.
    pub name: &'static str,
    /// What it is and what it tests.
    pub doc: &'static str,
    /// Its parameters.
    pub params: &'static [BuiltinParam],
    build: fn(&Args) -> Result<Scene, SceneError>,
}

/// Every builtin scene.
pub fn builtins() -> Vec<BuiltinInfo> {
    let mut all = analytic::infos();
    all.extend(furnace_sphere::infos());
    all.extend(cornell::infos());
    all.extend(detailed_meshes::infos());
    all
}

/// Parsed `k=v` arguments of a builtin spec, with typed getters that check ranges and name the parameter.
pub struct Args {
    scene: &'static str,
    pairs: Vec<(String, String)>,
}

impl Args {
    fn raw(&self, key: &str) -> Option<&str> {
        self.pairs
            .iter()
            .rev()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    fn err(&self, key: &str, msg: String) -> SceneError {
        SceneError::Invalid {
            field: format!("builtin:{} parameter '{key}'", self.scene),
            message: msg,
        }
    }

    /// A finite number within [lo, hi].
    pub fn f64(&self, key: &str, default: f64, lo: f64, hi: f64) -> Result<f64, SceneError> {
        let Some(v) = self.raw(key) else {
            return Ok(default);
        };
        let x: f64 = v
            .parse()
            .map_err(|_| self.err(key, format!("'{v}' is not a number")))?;
        if !(x.is_finite() && x >= lo && x <= hi) {
            return Err(self.err(key, format!("{x} is outside [{lo}, {hi}]")));
        }
        Ok(x)
    }

    /// A value strictly below `hi` (reflectance: [0, 1)).
    pub fn f64_below(&self, key: &str, default: f64, lo: f64, hi: f64) -> Result<f64, SceneError> {
        let x = self.f64(key, default, lo, hi)?;
        if x >= hi {
            return Err(self.err(key, format!("{x} must be below {hi}")));
        }
        Ok(x)
    }

    /// An integer within [lo, hi].
    pub fn usize(
        &self,
        key: &str,
        default: usize,
        lo: usize,
        hi: usize,
    ) -> Result<usize, SceneError> {
        let Some(v) = self.raw(key) else {
            return Ok(default);
        };
        let x: usize = v
            .parse()
            .map_err(|_| self.err(key, format!("'{v}' is not a whole number")))?;
        if x < lo || x > hi {
            return Err(self.err(key, format!("{x} is outside [{lo}, {hi}]")));
        }
        Ok(x)
    }

    /// A grey or `r,g,b` colour, each channel within [lo, hi] (and below `hi` when `below`).
    pub fn rgb(
        &self,
        key: &str,
        default: Rgb,
        lo: f64,
        hi: f64,
        below: bool,
    ) -> Result<Rgb, SceneError> {
        let Some(v) = self.raw(key) else {
            return Ok(default);
        };
        let parts: Vec<&str> = v.split(',').collect();
        let vals: Result<Vec<f64>, _> = parts.iter().map(|s| s.trim().parse::<f64>()).collect();
        let vals =
            vals.map_err(|_| self.err(key, format!("'{v}' is not a number or r,g,b triple")))?;
        let c = match vals[..] {
            [g] => DVec3::splat(g),
            [r, g, b] => DVec3::new(r, g, b),
            _ => return Err(self.err(key, format!("'{v}' needs 1 or 3 numbers"))),
        };
        for x in c.to_array() {
            if !(x.is_finite() && x >= lo && x <= hi) || (below && x >= hi) {
                let range = if below {
                    format!("[{lo}, {hi})")
                } else {
                    format!("[{lo}, {hi}]")
                };
                return Err(self.err(key, format!("{x} is outside {range}")));
            }
        }
        Ok(c)
    }
}

/// Builds a builtin scene from `NAME[?k=v&...]` (the part after `builtin:`).
pub fn builtin(spec: &str) -> Result<Scene, SceneError> {
    let (name, query) = spec.split_once('?').unwrap_or((spec, ""));
    let infos = builtins();
    let Some(info) = infos.iter().find(|i| i.name == name) else {
        let names: Vec<&str> = infos.iter().map(|i| i.name).collect();
        return Err(SceneError::Unknown(format!(
            "unknown builtin scene '{name}'; builtin scenes are: {}",
            names.join(", ")
        )));
    };
    let mut pairs = Vec::new();
    for kv in query.split('&').filter(|s| !s.is_empty()) {
        let Some((k, v)) = kv.split_once('=') else {
            return Err(SceneError::Invalid {
                field: format!("builtin:{name}"),
                message: format!("'{kv}' should be key=value"),
            });
        };
        if !info.params.iter().any(|p| p.0 == k) {
            let known: Vec<&str> = info.params.iter().map(|p| p.0).collect();
            return Err(SceneError::Invalid {
                field: format!("builtin:{name}"),
                message: format!(
                    "unknown parameter '{k}'; its parameters are: {}",
                    known.join(", ")
                ),
            });
        }
        pairs.push((k.to_string(), v.to_string()));
    }
    (info.build)(&Args {
        scene: info.name,
        pairs,
    })
}

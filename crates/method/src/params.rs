//! Typed method parameters set from `key=value` pairs (the command line's `--set`) or from a TOML table
//! (experiment configs), through serde: unknown keys are errors that name the key and list the known ones.
//!
//! A value is read as a TOML value when it parses as one (`0.5`, `16`, `true`, `"jacobi"`), otherwise as a
//! bare string (`jacobi`), so `--set iteration=jacobi` and `--set element_size=0.02` both work.

use serde::{Serialize, de::DeserializeOwned};

use crate::SolveError;

/// A method's parameter struct: serde-deserialisable with `#[serde(default, deny_unknown_fields)]`,
/// documented field by field in [`MethodParams::docs`].
pub trait MethodParams: Serialize + DeserializeOwned + Default + Clone + std::fmt::Debug {
    /// (name, documentation) for every parameter, in display order.
    fn docs() -> Vec<(&'static str, &'static str)>;

    /// Range checks beyond what the types enforce; errors name the parameter.
    fn validate(&self) -> Result<(), SolveError> {
        Ok(())
    }

    /// Builds from a TOML table, then validates.
    fn from_table(table: toml::Table) -> Result<Self, SolveError> {
        // Deserialise from TOML text so a type error points at the offending `key = value` line.
        let text = toml::to_string(&table).unwrap_or_default();
        let p: Self = toml::from_str(&text).map_err(|e: toml::de::Error| {
            let name = e.span().map_or_else(
                || "parameters".to_string(),
                |span| {
                    let start = text[..span.start].rfind('\n').map_or(0, |i| i + 1);
                    text[start..]
                        .split('=')
                        .next()
                        .unwrap_or_default()
                        .trim()
                        .to_string()
                },
            );
            SolveError::Parameter {
                name,
                message: e.message().to_string(),
            }
        })?;
        p.validate()?;
        Ok(p)
    }

    /// Builds from `key=value` pairs, then validates.
    fn from_pairs(pairs: &[(String, String)]) -> Result<Self, SolveError> {
        Self::from_table(pairs_to_table(pairs)?)
    }

    /// The defaults as (name, value) strings, for `radlab methods`.
    fn default_values() -> Vec<(String, String)> {
        match toml::Value::try_from(Self::default()) {
            Ok(toml::Value::Table(t)) => t.into_iter().map(|(k, v)| (k, v.to_string())).collect(),
            _ => Vec::new(),
        }
    }
}

/// Parses one value as TOML, falling back to a bare string.
pub fn parse_value(v: &str) -> toml::Value {
    match format!("v = {v}").parse::<toml::Table>() {
        Ok(mut t) => t
            .remove("v")
            .unwrap_or_else(|| toml::Value::String(v.to_string())),
        Err(_) => toml::Value::String(v.to_string()),
    }
}

/// Turns `key=value` pairs into a TOML table (later keys win). A key may be dotted (`a.b=1`) for nested tables.
pub fn pairs_to_table(pairs: &[(String, String)]) -> Result<toml::Table, SolveError> {
    let mut t = toml::Table::new();
    for (k, v) in pairs {
        if k.is_empty() {
            return Err(SolveError::param(
                k,
                "empty parameter name; use --set name=value",
            ));
        }
        t.insert(k.clone(), parse_value(v));
    }
    Ok(t)
}

/// Splits `key=value`; the error says how to write it.
pub fn split_pair(s: &str) -> Result<(String, String), SolveError> {
    match s.split_once('=') {
        Some((k, v)) if !k.trim().is_empty() => Ok((k.trim().to_string(), v.trim().to_string())),
        _ => Err(SolveError::param(
            s,
            "expected key=value, e.g. --set element_size=0.05",
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize, PartialEq)]
    #[serde(default, deny_unknown_fields)]
    struct P {
        a: f64,
        b: u32,
        mode: String,
    }
    impl MethodParams for P {
        fn docs() -> Vec<(&'static str, &'static str)> {
            vec![("a", "a number"), ("b", "a count"), ("mode", "a word")]
        }
        fn validate(&self) -> Result<(), SolveError> {
            if self.a < 0.0 {
                Err(SolveError::param("a", "must be >= 0"))
            } else {
                Ok(())
            }
        }
    }

    #[test]
    fn pairs_parse_and_unknown_keys_are_named() {
        let pairs = vec![
            ("a".to_string(), "0.5".to_string()),
            ("mode".to_string(), "jacobi".to_string()),
        ];
        let p = P::from_pairs(&pairs).expect("valid");
        assert_eq!(
            p,
            P {
                a: 0.5,
                b: 0,
                mode: "jacobi".into()
            }
        );
        let err = P::from_pairs(&[("c".into(), "1".into())])
            .expect_err("unknown")
            .to_string();
        assert!(err.contains("unknown field `c`"), "{err}");
        let err = P::from_pairs(&[("a".into(), "-1".into())])
            .expect_err("range")
            .to_string();
        assert!(err.contains("'a'"), "{err}");
        let err = P::from_pairs(&[("b".into(), "x".into())])
            .expect_err("type")
            .to_string();
        assert!(err.contains("'b'"), "{err}");
        assert!(split_pair("novalue").is_err());
    }
}

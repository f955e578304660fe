//! Typed method parameters, each declared once: a field of a params struct, whose doc comment is its help,
//! whose `#[schemars(...)]` attribute is its accepted range, and whose value in the struct's `Default` is its
//! default. The struct derives serde's `Serialize`/`Deserialize` and schemars' `JsonSchema`; from the derived
//! JSON Schema and the defaults come the checks of a `key=value` pair (the command line's `--set`) or a TOML
//! table (experiment configs), the errors for unknown keys and bad values, and the lines `radlab methods`
//! prints ([`MethodParams::declarations`]).
//!
//! A field's doc comment opens with one paragraph of help: what the parameter does, and what leaving it unset
//! means where it is an `Option`. Further paragraphs are for readers of the code. Ranges are written
//! `#[schemars(range(min = 1, max = 16))]` (inclusive) or `#[schemars(extend("exclusiveMinimum" = 0))]`
//! (exclusive, JSON Schema's keywords); every floating-point parameter must also be finite. Checks across
//! parameters that no range expresses stay code, in [`MethodParams::check_combination`].
//!
//! A value is read as a TOML value when it parses as one (`0.5`, `16`, `true`, `"jacobi"`), otherwise as a
//! bare string (`jacobi`), so `--set iteration=jacobi` and `--set element_size=0.02` both work.

use schemars::JsonSchema;
use serde::{Serialize, de::DeserializeOwned};
use serde_json::Value as Json;

use crate::SolveError;

/// One declared parameter, as `radlab methods` lists it and as errors describe it.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamDecl {
    /// The key of `--set key=value` and of a TOML table.
    pub name: String,
    /// What values it takes: "number", "whole number", "true or false", "text", or its choices
    /// ("jacobi, gauss-seidel or conjugate-gradient").
    pub kind: String,
    /// The accepted range, if declared.
    pub range: Option<Range>,
    /// The default, in TOML syntax (choices bare), or `unset` for an optional parameter left unset.
    pub default: String,
    /// The first paragraph of the field's doc comment: what the parameter does.
    pub help: String,
}

impl ParamDecl {
    /// The kind with its range, e.g. "whole number in 1..=16" or "number > 0".
    pub fn accepts(&self) -> String {
        match &self.range {
            Some(r) => format!("{} {}", self.kind, r.phrase(self.kind == WHOLE)),
            None => self.kind.clone(),
        }
    }
}

/// A declared numeric range; each bound is (value, inclusive).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range {
    /// Lower bound.
    pub min: Option<(f64, bool)>,
    /// Upper bound.
    pub max: Option<(f64, bool)>,
}

impl Range {
    /// Whether `x` lies in the range.
    pub fn contains(&self, x: f64) -> bool {
        let above = match self.min {
            Some((m, true)) => x >= m,
            Some((m, false)) => x > m,
            None => true,
        };
        let below = match self.max {
            Some((m, true)) => x <= m,
            Some((m, false)) => x < m,
            None => true,
        };
        above && below
    }

    /// "in 1..=16", "in (0, 1]", "> 0", ">= 1" or "< 90"; `whole` writes a closed range of whole numbers
    /// as Rust's `a..=b`.
    pub fn phrase(&self, whole: bool) -> String {
        match (self.min, self.max) {
            (Some((a, true)), Some((b, true))) if whole => format!("in {a}..={b}"),
            (Some((a, ai)), Some((b, bi))) => format!(
                "in {}{a}, {b}{}",
                if ai { '[' } else { '(' },
                if bi { ']' } else { ')' }
            ),
            (Some((a, true)), None) => format!(">= {a}"),
            (Some((a, false)), None) => format!("> {a}"),
            (None, Some((b, true))) => format!("<= {b}"),
            (None, Some((b, false))) => format!("< {b}"),
            (None, None) => String::new(),
        }
    }
}

/// The kind of an integer parameter.
const WHOLE: &str = "whole number";

/// A method's parameter struct: serde-(de)serialisable with `#[serde(default)]`, and deriving `JsonSchema`
/// so that its fields' doc comments and range attributes declare it (see the module documentation).
pub trait MethodParams:
    Serialize + DeserializeOwned + JsonSchema + Default + Clone + std::fmt::Debug
{
    /// Keys of a flattened parameter set (say the hierarchical engine's) that this method refuses, each with
    /// the reason and the fix. They are left out of [`MethodParams::declarations`].
    const REFUSED: &'static [(&'static str, &'static str)] = &[];

    /// Checks across parameters that no declared range expresses; errors name a parameter and the fix.
    fn check_combination(&self) -> Result<(), SolveError> {
        Ok(())
    }

    /// Every check: each parameter finite and in its declared range, then [`MethodParams::check_combination`].
    fn validate(&self) -> Result<(), SolveError> {
        let values = toml::Table::try_from(self)
            .map_err(|e| SolveError::param("parameters", e.to_string()))?;
        for d in Self::declarations() {
            let Some(v) = values.get(&d.name) else {
                continue;
            };
            let x = match v {
                toml::Value::Float(x) => *x,
                toml::Value::Integer(i) => *i as f64,
                _ => continue,
            };
            if !x.is_finite() || d.range.is_some_and(|r| !r.contains(x)) {
                return Err(out_of_range(&d, v));
            }
        }
        self.check_combination()
    }

    /// Builds from a TOML table over the defaults, then validates. An unknown key is refused with the known
    /// ones listed; a value of the wrong type is refused naming its key and what the key takes.
    fn from_table(table: toml::Table) -> Result<Self, SolveError> {
        let decls = Self::declarations();
        for key in table.keys() {
            if let Some((_, why)) = Self::REFUSED.iter().find(|(k, _)| k == key) {
                return Err(SolveError::param(key, *why));
            }
            if !decls.iter().any(|d| &d.name == key) {
                let known: Vec<&str> = decls.iter().map(|d| d.name.as_str()).collect();
                return Err(SolveError::param(
                    key,
                    format!(
                        "unknown parameter; this method's parameters are {} (see `radlab methods`)",
                        known.join(", ")
                    ),
                ));
            }
        }
        // Over the defaults as a table, so a flattened parameter set keeps this method's own defaults.
        let over_defaults = |t: &toml::Table| {
            let mut full = toml::Table::try_from(Self::default()).unwrap_or_default();
            full.extend(t.clone());
            toml::Value::Table(full).try_into::<Self>()
        };
        let p = over_defaults(&table).map_err(|e| {
            // Name the first key whose value alone does not parse.
            table
                .iter()
                .find_map(|(k, v)| {
                    let single = toml::Table::from_iter([(k.clone(), v.clone())]);
                    let e = over_defaults(&single).err()?;
                    let d = decls.iter().find(|d| &d.name == k)?;
                    Some(SolveError::param(
                        k,
                        format!(
                            "{}; accepted: {} (default {})",
                            e.message().trim_end(),
                            d.accepts(),
                            d.default
                        ),
                    ))
                })
                .unwrap_or_else(|| SolveError::param("parameters", e.message().trim_end()))
        })?;
        p.validate()?;
        Ok(p)
    }

    /// Builds from `key=value` pairs, then validates.
    fn from_pairs(pairs: &[(String, String)]) -> Result<Self, SolveError> {
        Self::from_table(pairs_to_table(pairs)?)
    }

    /// Every parameter, by name (JSON Schema's properties are sorted): name, kind, range, default and help, read from the derived
    /// JSON Schema and from `Default`.
    fn declarations() -> Vec<ParamDecl> {
        let schema = schemars::schema_for!(Self);
        let root = schema.as_value();
        let defaults = toml::Table::try_from(Self::default()).unwrap_or_default();
        let Some(props) = root.get("properties").and_then(Json::as_object) else {
            return Vec::new();
        };
        props
            .iter()
            .filter(|(name, _)| !Self::REFUSED.iter().any(|(k, _)| k == name))
            .map(|(name, prop)| declaration(root, name, prop, defaults.get(name)))
            .collect()
    }
}

/// The error for `v`, out of `d`'s range or not finite.
fn out_of_range(d: &ParamDecl, v: &toml::Value) -> SolveError {
    let fix = if d.default == UNSET {
        "leave it unset for the default".to_string()
    } else {
        format!("the default is {}", d.default)
    };
    SolveError::param(
        &d.name,
        format!("{v} is not a finite {}; {fix}", d.accepts()),
    )
}

/// How an optional parameter's default is shown.
const UNSET: &str = "unset";

/// The declaration of property `name` of the schema `root`.
fn declaration(root: &Json, name: &str, prop: &Json, default: Option<&toml::Value>) -> ParamDecl {
    let target = resolve(root, prop);
    let choices = choices(target);
    let types: Vec<&str> = match target.get("type") {
        Some(Json::String(t)) => vec![t.as_str()],
        Some(Json::Array(a)) => a.iter().filter_map(Json::as_str).collect(),
        _ => Vec::new(),
    };
    let kind = if !choices.is_empty() {
        or_list(&choices)
    } else if types.contains(&"integer") {
        WHOLE.to_string()
    } else if types.contains(&"number") {
        "number".to_string()
    } else if types.contains(&"boolean") {
        "true or false".to_string()
    } else {
        "text".to_string()
    };
    let bound = |key: &str, exclusive: &str| {
        let inclusive = prop.get(key).and_then(Json::as_f64).map(|x| (x, true));
        prop.get(exclusive)
            .and_then(Json::as_f64)
            .map(|x| (x, false))
            .or(inclusive)
    };
    let mut range = Range {
        min: bound("minimum", "exclusiveMinimum"),
        max: bound("maximum", "exclusiveMaximum"),
    };
    // An unsigned type's own minimum of 0 is not a declared range.
    if kind == WHOLE && range.min == Some((0.0, true)) {
        range.min = None;
    }
    let range = (range.min.is_some() || range.max.is_some()).then_some(range);
    let default = match default {
        None => UNSET.to_string(),
        Some(toml::Value::String(s)) if !choices.is_empty() => s.clone(),
        Some(v) => v.to_string(),
    };
    let description = prop.get("description").and_then(Json::as_str).unwrap_or("");
    ParamDecl {
        name: name.to_string(),
        kind,
        range,
        default,
        help: help_line(description),
    }
}

/// The schema a property refers to (`$ref`, or the single `allOf` entry), or the property itself.
fn resolve<'a>(root: &'a Json, prop: &'a Json) -> &'a Json {
    let reference = prop.get("$ref").or_else(|| {
        prop.get("allOf")
            .and_then(Json::as_array)
            .and_then(|a| a.first())
            .and_then(|s| s.get("$ref"))
    });
    reference
        .and_then(Json::as_str)
        .and_then(|r| r.strip_prefix("#/"))
        .and_then(|path| path.split('/').try_fold(root, |v, k| v.get(k)))
        .unwrap_or(prop)
}

/// The string values an enumeration takes (`enum`, or `oneOf` of `const`s).
fn choices(schema: &Json) -> Vec<String> {
    let strings = |a: &Vec<Json>| -> Vec<String> {
        a.iter()
            .filter_map(|v| v.as_str().map(str::to_string))
            .collect()
    };
    if let Some(a) = schema.get("enum").and_then(Json::as_array) {
        return strings(a);
    }
    schema
        .get("oneOf")
        .and_then(Json::as_array)
        .map(|variants| {
            variants
                .iter()
                .flat_map(|v| {
                    v.get("const")
                        .map(|c| vec![c.clone()])
                        .or_else(|| v.get("enum").and_then(Json::as_array).cloned())
                        .unwrap_or_default()
                })
                .filter_map(|v| v.as_str().map(str::to_string))
                .collect()
        })
        .unwrap_or_default()
}

/// "a", "a or b", "a, b or c".
fn or_list(items: &[String]) -> String {
    match items {
        [] => String::new(),
        [one] => one.clone(),
        [rest @ .., last] => format!("{} or {last}", rest.join(", ")),
    }
}

/// The first paragraph of a doc comment on one line, rustdoc's link brackets and code ticks removed.
fn help_line(doc: &str) -> String {
    let first = doc.split("\n\n").next().unwrap_or_default();
    first
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
        .replace("[`", "")
        .replace("`]", "")
        .replace('`', "")
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

    /// How to mix.
    #[derive(
        Clone,
        Copy,
        Debug,
        Default,
        PartialEq,
        serde::Serialize,
        serde::Deserialize,
        schemars::JsonSchema,
    )]
    #[serde(rename_all = "kebab-case")]
    enum Mode {
        /// Evenly.
        #[default]
        Even,
        /// Oddly.
        OddOne,
    }

    /// A test set.
    #[derive(
        Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
    )]
    #[serde(default, deny_unknown_fields)]
    struct P {
        /// A positive number.
        ///
        /// More for readers of the code.
        #[schemars(extend("exclusiveMinimum" = 0))]
        a: f64,
        /// A count in `1..=8`.
        #[schemars(range(min = 1, max = 8))]
        b: u32,
        /// How to mix.
        mode: Mode,
        /// An optional length; unset: chosen by the scene.
        #[schemars(extend("exclusiveMinimum" = 0))]
        length: Option<f64>,
    }

    impl Default for P {
        fn default() -> Self {
            Self {
                a: 0.5,
                b: 2,
                mode: Mode::Even,
                length: None,
            }
        }
    }

    impl MethodParams for P {
        fn check_combination(&self) -> Result<(), SolveError> {
            if self.mode == Mode::OddOne && self.b.is_multiple_of(2) {
                return Err(SolveError::param("b", "odd-one mixing needs an odd b"));
            }
            Ok(())
        }
    }

    fn pairs(kv: &[(&str, &str)]) -> Vec<(String, String)> {
        kv.iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
    }

    #[test]
    fn declarations_come_from_the_fields() {
        let d = P::declarations();
        let names: Vec<&str> = d.iter().map(|d| d.name.as_str()).collect();
        assert_eq!(names, ["a", "b", "length", "mode"]);
        assert_eq!(d[0].help, "A positive number.");
        assert_eq!(d[0].accepts(), "number > 0");
        assert_eq!(d[0].default, "0.5");
        assert_eq!(d[1].accepts(), "whole number in 1..=8");
        assert_eq!(d[1].help, "A count in 1..=8.");
        assert_eq!(d[2].default, UNSET);
        assert_eq!(d[2].accepts(), "number > 0");
        assert_eq!(d[3].kind, "even or odd-one");
        assert_eq!(d[3].default, "even");
    }

    #[test]
    fn pairs_parse_and_bad_keys_and_values_are_named() {
        let p =
            P::from_pairs(&pairs(&[("a", "2"), ("mode", "odd-one"), ("b", "3")])).expect("valid");
        assert_eq!((p.a, p.b, p.mode), (2.0, 3, Mode::OddOne));
        assert_eq!(P::from_pairs(&[]).expect("defaults"), P::default());
        let err = |kv: &[(&str, &str)]| P::from_pairs(&pairs(kv)).expect_err("bad").to_string();
        let e = err(&[("c", "1")]);
        assert!(e.contains("'c'") && e.contains("a, b, length, mode"), "{e}");
        let e = err(&[("a", "0")]);
        assert!(
            e.contains("'a'") && e.contains("> 0") && e.contains("0.5"),
            "{e}"
        );
        let e = err(&[("a", "nan")]);
        assert!(e.contains("'a'") && e.contains("finite"), "{e}");
        let e = err(&[("b", "9")]);
        assert!(e.contains("'b'") && e.contains("1..=8"), "{e}");
        let e = err(&[("b", "x")]);
        assert!(e.contains("'b'") && e.contains("1..=8"), "{e}");
        let e = err(&[("mode", "sideways")]);
        assert!(e.contains("'mode'") && e.contains("even or odd-one"), "{e}");
        let e = err(&[("length", "-1")]);
        assert!(e.contains("'length'") && e.contains("unset"), "{e}");
        let e = err(&[("mode", "odd-one")]);
        assert!(e.contains("'b'") && e.contains("odd"), "{e}");
        assert!(split_pair("novalue").is_err());
    }
}

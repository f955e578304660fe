//! Experiment configs (TOML; documented in experiments/README.md): scenes × methods × parameter sweeps × seeds,
//! with the evaluation points, the reference, limits and outputs. Unknown keys and impossible values are errors
//! naming the key. [`ExperimentConfig::runs`] expands the config into its runs in a fixed order, so run i is the
//! same run on every machine (what `--shard` relies on).

use std::path::Path;

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};

/// A whole experiment.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExperimentConfig {
    /// Name; results go to `results/<name>/` unless `--out` says otherwise.
    pub name: String,
    /// What the experiment asks.
    #[serde(default)]
    pub description: String,
    /// Seeds; every (scene, method, parameter set) runs once per seed.
    #[serde(default = "default_seeds")]
    pub seeds: Vec<u64>,
    /// Evaluation points.
    #[serde(default)]
    pub evaluation: Evaluation,
    /// The reference solution.
    #[serde(default)]
    pub reference: ReferenceConfig,
    /// Stopping rules and resource limits of every run.
    #[serde(default)]
    pub limits: LimitsConfig,
    /// What to write besides the tables.
    #[serde(default)]
    pub outputs: OutputsConfig,
    /// The scenes.
    pub scenes: Vec<SceneEntry>,
    /// The methods.
    pub methods: Vec<MethodEntry>,
}

fn default_seeds() -> Vec<u64> {
    vec![1]
}

/// Evaluation points: area-stratified over the non-emitting faces.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Evaluation {
    /// Number of points.
    pub points: usize,
    /// Seed of their placement.
    pub seed: u64,
    /// Evaluate the error after every `every`-th step (the last step is always evaluated).
    pub every: u64,
    /// Evaluate only once the solving time has grown by this factor since the last evaluation (default
    /// 1.25; 1 = at every `every`-th step), and, for a factor above 1, by at least the last evaluation's
    /// answering time. Keeps the number of evaluations logarithmic in the run's length, which matters when
    /// steps are many (progressive shots), and evaluating from taking more of a run's time than solving, which
    /// matters when answering is costly (a final gather on a heap of small faces).
    pub growth: f64,
}

impl Default for Evaluation {
    fn default() -> Self {
        Self {
            points: 1024,
            seed: 0,
            every: 1,
            growth: 1.25,
        }
    }
}

/// Which reference errors are measured against.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum ReferenceKind {
    /// `furnace` when the scene is a closed surface with one material, `pathtrace` otherwise.
    #[default]
    Auto,
    /// The path tracer's per-point estimate, with its standard error as the noise floor.
    Pathtrace,
    /// B = E/(1−ρ) everywhere (closed scene, one material).
    Furnace,
    /// B = E + ρ Σ_emitters E_e F(x→e) with visibility: exact when light bounces once (e.g. the plate pairs).
    Direct,
}

/// The reference.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ReferenceConfig {
    /// Which reference.
    pub kind: ReferenceKind,
    /// Path-traced samples per evaluation point.
    pub samples: u32,
    /// Samples per pixel of the path-traced reference image.
    pub image_spp: u32,
    /// Seed of the reference.
    pub seed: u64,
}

impl Default for ReferenceConfig {
    fn default() -> Self {
        Self {
            kind: ReferenceKind::Auto,
            samples: 1024,
            image_spp: 64,
            seed: 12345,
        }
    }
}

/// Limits of every run.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LimitsConfig {
    /// Most steps per run.
    pub max_steps: u64,
    /// Most seconds of solver steps per run (then the run stops with outcome `time-limit`).
    pub time_limit: f64,
    /// Stop a run once its relative L1 error is at or below this (0 = never).
    pub target_error: f64,
    /// Run each run in its own child process (contains crashes, enforces the limits below).
    pub isolate: bool,
    /// Memory limit of a child process, MiB (0 = none).
    pub memory_limit_mib: u64,
    /// Wall seconds after which a child is killed (0 = 2 × time_limit + 60), evaluations and set-up included.
    /// A killed run keeps its last evaluation, with the outcome `timeout`.
    pub kill_after: f64,
}

impl Default for LimitsConfig {
    fn default() -> Self {
        Self {
            max_steps: 100_000,
            time_limit: 60.0,
            target_error: 0.0,
            isolate: true,
            memory_limit_mib: 8192,
            kill_after: 0.0,
        }
    }
}

impl LimitsConfig {
    /// Seconds after which a child run is killed.
    pub fn kill_after_secs(&self) -> f64 {
        if self.kill_after > 0.0 {
            self.kill_after
        } else {
            2.0 * self.time_limit + 60.0
        }
    }
}

/// Outputs besides runs.csv, trace.csv, report.md and meta.json.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OutputsConfig {
    /// Plots (PNG and SVG).
    pub plots: bool,
    /// Images: each method's EXR, a false-colour difference PNG, a contact sheet (scenes with a camera).
    pub images: bool,
    /// Image width override (0 = the camera's).
    pub image_width: u32,
    /// Image height override (0 = the camera's).
    pub image_height: u32,
    /// Samples per pixel when rendering a method's solution.
    pub image_spp: u32,
    /// Most paths per pixel of a `pathtrace` run's image: it is rendered at the paths per point the run
    /// reached, capped here (default 64) because a camera image costs pixels × paths.
    pub pathtrace_image_spp: u32,
}

impl Default for OutputsConfig {
    fn default() -> Self {
        Self {
            plots: true,
            images: true,
            image_width: 0,
            image_height: 0,
            image_spp: 4,
            pathtrace_image_spp: 64,
        }
    }
}

/// A scene of the experiment.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneEntry {
    /// Path (relative to the working directory) or `builtin:NAME[?k=v&...]`.
    pub scene: String,
    /// Short label for tables and file names (default: derived from the spec).
    #[serde(default)]
    pub label: Option<String>,
    /// Reference kind for this scene (overrides `[reference] kind`).
    #[serde(default)]
    pub reference: Option<ReferenceKind>,
    /// Path-traced reference samples per point for this scene (overrides `[reference] samples`): a scene
    /// whose darkest points need a smaller standard error than the others (the max error divides by the
    /// reference there) buys it alone.
    #[serde(default)]
    pub reference_samples: Option<u32>,
    /// Scaling family: scenes of one family form a series against their face count in the scaling plots.
    #[serde(default)]
    pub family: Option<String>,
}

/// A method of the experiment, possibly swept over parameters.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MethodEntry {
    /// Method name (see `radlab methods`).
    pub method: String,
    /// Label for tables and plots (default: the method name); must be unique.
    #[serde(default)]
    pub label: Option<String>,
    /// Fixed parameters.
    #[serde(default)]
    pub params: toml::Table,
    /// Swept parameters: `key = [v1, v2, ...]` or `key = { from = a, to = b, steps = n, scale = "log" | "linear" }`.
    /// Several keys sweep their cartesian product.
    #[serde(default)]
    pub sweep: toml::Table,
}

impl MethodEntry {
    /// The label.
    pub fn label(&self) -> String {
        self.label.clone().unwrap_or_else(|| self.method.clone())
    }
}

impl SceneEntry {
    /// The reference settings of this scene: `reference`, with this scene's samples where it sets them.
    pub fn reference_config(&self, reference: &ReferenceConfig) -> ReferenceConfig {
        ReferenceConfig {
            samples: self.reference_samples.unwrap_or(reference.samples),
            ..reference.clone()
        }
    }

    /// The label.
    pub fn label(&self) -> String {
        self.label
            .clone()
            .unwrap_or_else(|| label_from_spec(&self.scene))
    }
}

/// A file-name-safe label from a scene spec.
pub fn label_from_spec(spec: &str) -> String {
    let base = spec.strip_prefix("builtin:").unwrap_or_else(|| {
        Path::new(spec)
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or(spec)
    });
    base.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '.' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// One run: everything that determines its result.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct RunSpec {
    /// Position in the experiment's expansion order.
    pub index: usize,
    /// Scene spec.
    pub scene: String,
    /// Scene label.
    pub scene_label: String,
    /// Scaling family of the scene ("" for none).
    #[serde(default)]
    pub family: String,
    /// Method name.
    pub method: String,
    /// Method label.
    pub label: String,
    /// All parameters (fixed and swept).
    pub params: toml::Table,
    /// The swept parameters' values only, as `k=v` joined by `;` (empty without a sweep).
    pub sweep: String,
    /// Seed.
    pub seed: u64,
}

impl RunSpec {
    /// A stable, file-name-safe identifier: index, scene, label, a digest of the parameters, seed.
    pub fn id(&self) -> String {
        let params = toml::to_string(&self.params).unwrap_or_default();
        format!(
            "{:04}-{}-{}-{}-s{}",
            self.index,
            self.scene_label,
            label_from_spec(&self.label),
            &super::digest::hex(params.as_bytes())[..8],
            self.seed
        )
    }

    /// Parameters as `k=v;k=v` (sorted by key) for tables.
    pub fn params_string(&self) -> String {
        self.params
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect::<Vec<_>>()
            .join(";")
    }
}

fn sweep_values(key: &str, v: &toml::Value, at: &str) -> Result<Vec<toml::Value>> {
    match v {
        toml::Value::Array(a) if !a.is_empty() => Ok(a.clone()),
        toml::Value::Array(_) => bail!("{at}.sweep.{key}: the list of values is empty"),
        toml::Value::Table(t) => {
            for k in t.keys() {
                if !["from", "to", "steps", "scale"].contains(&k.as_str()) {
                    bail!(
                        "{at}.sweep.{key}: unknown key '{k}' (a range has from, to, steps, scale)"
                    );
                }
            }
            let num = |name: &str| -> Result<f64> {
                match t.get(name) {
                    Some(toml::Value::Float(x)) => Ok(*x),
                    Some(toml::Value::Integer(i)) => Ok(*i as f64),
                    _ => bail!("{at}.sweep.{key}.{name}: a number is required"),
                }
            };
            let (from, to) = (num("from")?, num("to")?);
            let steps = match t.get("steps") {
                Some(toml::Value::Integer(n)) if *n >= 2 && *n <= 10_000 => *n as usize,
                _ => bail!("{at}.sweep.{key}.steps: a whole number from 2 to 10000 is required"),
            };
            let log = match t.get("scale").and_then(|s| s.as_str()) {
                None | Some("log") => true,
                Some("linear") => false,
                Some(other) => {
                    bail!("{at}.sweep.{key}.scale: '{other}' is not \"log\" or \"linear\"")
                }
            };
            if log && !(from > 0.0 && to > 0.0) {
                bail!(
                    "{at}.sweep.{key}: a log range needs from and to > 0 (use scale = \"linear\")"
                );
            }
            let ints = matches!(t.get("from"), Some(toml::Value::Integer(_)))
                && matches!(t.get("to"), Some(toml::Value::Integer(_)));
            Ok((0..steps)
                .map(|i| {
                    let s = i as f64 / (steps - 1) as f64;
                    let x = if log {
                        (from.ln() + s * (to.ln() - from.ln())).exp()
                    } else {
                        from + s * (to - from)
                    };
                    if ints {
                        toml::Value::Integer(x.round() as i64)
                    } else {
                        toml::Value::Float(x)
                    }
                })
                .collect())
        }
        other => bail!(
            "{at}.sweep.{key}: expected a list of values or a range table, found {}",
            other.type_str()
        ),
    }
}

impl ExperimentConfig {
    /// Reads and validates a config file; errors name the file and the key.
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("{}: cannot read", path.display()))?;
        let cfg: Self =
            toml::from_str(&text).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
        cfg.validate()
            .with_context(|| format!("{}: invalid experiment", path.display()))?;
        Ok(cfg)
    }

    /// Checks values that serde cannot: ranges, unique labels, known methods, valid parameters.
    pub fn validate(&self) -> Result<()> {
        if self.name.is_empty() || self.name.contains(['/', '\\']) || self.name.starts_with('.') {
            bail!("name: '{}' must be a non-empty plain file name", self.name);
        }
        if self.seeds.is_empty() {
            bail!("seeds: give at least one seed");
        }
        if self.evaluation.points == 0 || self.evaluation.points > 10_000_000 {
            bail!(
                "evaluation.points: {} is outside 1..=10000000",
                self.evaluation.points
            );
        }
        if !(self.evaluation.growth >= 1.0 && self.evaluation.growth.is_finite()) {
            bail!(
                "evaluation.growth: {} must be a finite factor >= 1 (1 evaluates at every eligible step)",
                self.evaluation.growth
            );
        }
        if self.evaluation.every == 0 {
            bail!("evaluation.every: must be at least 1");
        }
        if self.reference.samples < 2 || self.reference.image_spp < 2 {
            bail!(
                "reference.samples and reference.image_spp: must be at least 2 (a standard error needs two samples)"
            );
        }
        for entry in &self.scenes {
            if entry.reference_samples.is_some_and(|n| n < 2) {
                bail!(
                    "scenes '{}': reference_samples must be at least 2 (a standard error needs two samples)",
                    entry.label()
                );
            }
        }
        let l = &self.limits;
        if !(l.time_limit > 0.0 && l.time_limit.is_finite()) {
            bail!(
                "limits.time_limit: {} must be a positive number of seconds",
                l.time_limit
            );
        }
        if l.max_steps == 0 {
            bail!("limits.max_steps: must be at least 1");
        }
        if !(l.target_error >= 0.0 && l.target_error.is_finite()) {
            bail!("limits.target_error: {} must be >= 0", l.target_error);
        }
        if !(l.kill_after >= 0.0 && l.kill_after.is_finite()) {
            bail!("limits.kill_after: {} must be >= 0", l.kill_after);
        }
        if self.outputs.image_spp == 0 {
            bail!("outputs.image_spp: must be at least 1");
        }
        if self.scenes.is_empty() || self.methods.is_empty() {
            bail!(
                "scenes and methods: give at least one of each ([[scenes]] and [[methods]] tables)"
            );
        }
        let mut labels = std::collections::HashSet::new();
        for (i, s) in self.scenes.iter().enumerate() {
            if !labels.insert(s.label()) {
                bail!(
                    "scenes[{i}].label: '{}' is used twice; give each scene a distinct label",
                    s.label()
                );
            }
        }
        let mut labels = std::collections::HashSet::new();
        for (i, m) in self.methods.iter().enumerate() {
            if !labels.insert(m.label()) {
                bail!(
                    "methods[{i}].label: '{}' is used twice; give each method entry a distinct label",
                    m.label()
                );
            }
            for combo in expand_sweep(m, &format!("methods[{i}]"))? {
                super::super::methods::validate_params(&m.method, combo.0)
                    .with_context(|| format!("methods[{i}] ({})", m.label()))?;
            }
        }
        Ok(())
    }

    /// Every run, in expansion order: scenes, then methods, then sweep points, then seeds.
    pub fn runs(&self) -> Result<Vec<RunSpec>> {
        let mut out = Vec::new();
        for s in &self.scenes {
            for (i, m) in self.methods.iter().enumerate() {
                for (params, sweep) in expand_sweep(m, &format!("methods[{i}]"))? {
                    for &seed in &self.seeds {
                        out.push(RunSpec {
                            index: out.len(),
                            scene: s.scene.clone(),
                            scene_label: s.label(),
                            family: s.family.clone().unwrap_or_default(),
                            method: m.method.clone(),
                            label: m.label(),
                            params: params.clone(),
                            sweep: sweep.clone(),
                            seed,
                        });
                    }
                }
            }
        }
        Ok(out)
    }
}

/// The parameter tables of a method entry: fixed params overlaid with each point of the sweep's cartesian
/// product, with the sweep point as `k=v;...`.
pub fn expand_sweep(m: &MethodEntry, at: &str) -> Result<Vec<(toml::Table, String)>> {
    let mut combos: Vec<(toml::Table, Vec<String>)> = vec![(m.params.clone(), Vec::new())];
    for (key, v) in &m.sweep {
        if m.params.contains_key(key) {
            bail!("{at}: '{key}' is both fixed in params and swept; remove one");
        }
        let values = sweep_values(key, v, at)?;
        combos = combos
            .into_iter()
            .flat_map(|(t, s)| {
                values.iter().map(move |v| {
                    let mut t = t.clone();
                    t.insert(key.clone(), v.clone());
                    let mut s = s.clone();
                    s.push(format!("{key}={v}"));
                    (t, s)
                })
            })
            .collect();
    }
    Ok(combos.into_iter().map(|(t, s)| (t, s.join(";"))).collect())
}

//! End-to-end tests of `radlab run`, `plot` and `merge` on tiny experiments in temporary directories: the
//! tables, figures and images exist and parse; complete runs are skipped; shards cover every run once; a
//! crashing, timed-out or out-of-memory run is recorded and the experiment finishes.

use std::path::{Path, PathBuf};
use std::process::Output;

mod support;
use support::{radlab_with_env, text};

const TINY: &str = r#"
name = "tiny"
description = "two scenes, two matrix settings"
seeds = [1]
[evaluation]
points = 48
[reference]
samples = 64
image_spp = 4
[limits]
time_limit = 20
[outputs]
image_width = 24
image_height = 24
image_spp = 1
[[scenes]]
scene = "builtin:furnace-cube?reflectance=0.6&tessellation=2"
label = "furnace"
[[scenes]]
scene = "builtin:cornell"
label = "cornell"
[[methods]]
method = "matrix"
params = { visibility = "centre", quadrature = 1 }
sweep = { iteration = ["jacobi", "conjugate-gradient"] }
"#;

fn write_config(dir: &Path, name: &str, body: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, body).expect("write config");
    p
}

fn csv_rows(p: &Path) -> Vec<csv::StringRecord> {
    let mut r = csv::Reader::from_path(p).expect("csv");
    r.records().map(|x| x.expect("row")).collect()
}

/// `radlab run CFG --out OUT` in `dir`, which must succeed; its output.
fn run_ok(dir: &Path, cfg: &Path, out: &Path) -> Output {
    let o = radlab_with_env(
        dir,
        &[
            "run",
            cfg.to_str().expect("utf8"),
            "--out",
            out.to_str().expect("utf8"),
        ],
        &[],
    );
    assert!(o.status.success(), "{}", text(&o));
    o
}

#[test]
fn tiny_experiment_end_to_end_then_skips() {
    let tmp = tempfile::tempdir().expect("tmp");
    let cfg = write_config(tmp.path(), "tiny.toml", TINY);
    let out = tmp.path().join("out");
    run_ok(tmp.path(), &cfg, &out);
    let runs = csv_rows(&out.join("runs.csv"));
    assert_eq!(runs.len(), 4, "2 scenes x 2 sweep points");
    let trace = csv_rows(&out.join("trace.csv"));
    assert!(trace.len() >= 4);
    let report = std::fs::read_to_string(out.join("report.md")).expect("report");
    assert!(
        report.contains("| matrix |") && report.contains("time to 1%"),
        "{report}"
    );
    for f in [
        "figures/convergence-cornell.png",
        "figures/frontier-furnace.svg",
        "images/contact-sheet-cornell.png",
    ] {
        assert!(out.join(f).exists(), "missing {f}");
    }
    let png = image::open(out.join("figures/frontier-cornell.png")).expect("PNG decodes");
    assert!(png.width() > 100);
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("meta.json")).expect("meta"))
            .expect("json");
    assert_eq!(meta["runs_executed"], 4);
    // The furnace's reference is analytic: its runs converge to a small error, with no noise floor.
    let rdr = csv::Reader::from_path(out.join("runs.csv")).expect("csv");
    let results: Vec<radlab_runner::experiment::execute::RunResult> =
        rdr.into_deserialize().map(|r| r.expect("row")).collect();
    for r in results.iter().filter(|r| r.scene == "furnace") {
        assert_eq!(r.reference, "furnace");
        assert_eq!(r.floor_l1, 0.0);
        assert!(r.l1 < 1e-3, "{r:?}");
        assert_eq!(r.outcome, "converged");
    }
    for r in results.iter().filter(|r| r.scene == "cornell") {
        assert_eq!(r.reference, "pathtrace");
        assert!(r.floor_l1 > 0.0 && r.l1.is_finite(), "{r:?}");
        // Matrix radiosity answers by final gather by default: its answering pass's rays and kernel
        // evaluations are both recorded (a kernel at least per point).
        assert!(
            r.answer_rays > 0 && r.answer_form_factors >= r.points,
            "{r:?}"
        );
    }
    // Each run's per-point file holds every evaluation point, and its worst point is the run's max error.
    for r in &results {
        let p = out.join("runs").join(format!("{}.points.csv", r.id));
        let mut rdr = csv::Reader::from_path(&p).expect("points.csv");
        let worst = rdr
            .deserialize::<std::collections::HashMap<String, f64>>()
            .map(|row| row.expect("row")["rel_error"])
            .fold((0u64, 0.0f64), |(n, m), e| (n + 1, m.max(e)));
        assert_eq!(worst.0, r.points, "{}", p.display());
        assert!(
            (worst.1 - r.max).abs() <= 1e-12 * r.max.max(1.0),
            "{}: worst point {} against the run's max {}",
            p.display(),
            worst.1,
            r.max
        );
    }
    // Run again: everything is skipped.
    let o = run_ok(tmp.path(), &cfg, &out);
    assert!(
        text(&o).contains("0 runs executed, 4 skipped"),
        "{}",
        text(&o)
    );
    // A narrower configuration written to the same directory: the tables hold its runs only, not the files
    // the wider one left there (both conjugate-gradient runs, and Cornell's Jacobi run, whose index moved from
    // 2 to 1 and so runs again).
    let narrow = write_config(
        tmp.path(),
        "narrow.toml",
        &TINY.replace(r#"["jacobi", "conjugate-gradient"]"#, r#"["jacobi"]"#),
    );
    let o = run_ok(tmp.path(), &narrow, &out);
    assert!(
        text(&o).contains("1 runs executed, 1 skipped")
            && text(&o).contains("3 run files in runs/ belong to no run"),
        "{}",
        text(&o)
    );
    let runs = csv_rows(&out.join("runs.csv"));
    assert_eq!(runs.len(), 2, "2 scenes x 1 sweep point");
    assert!(
        runs.iter()
            .all(|r| r.iter().all(|f| !f.contains("conjugate-gradient"))),
        "{runs:?}"
    );
    // plot redraws from the CSVs.
    std::fs::remove_file(out.join("figures/frontier-cornell.png")).expect("rm");
    let o = radlab_with_env(tmp.path(), &["plot", out.to_str().expect("utf8")], &[]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(out.join("figures/frontier-cornell.png").exists());
}

/// A run is skipped only while its scene is the same: a scene file edited under the same name runs again.
#[test]
fn an_edited_scene_file_runs_again() {
    let tmp = tempfile::tempdir().expect("tmp");
    let box_scene = |rho: f64| {
        format!(
            "[materials.furnace]\nreflectance = {rho}\nemission = 1\n\n[[objects]]\ntype = \"box\"\n\
             min = [0, 0, 0]\nmax = [1, 2, 3]\ninward = true\nmaterial = \"furnace\"\n"
        )
    };
    std::fs::write(tmp.path().join("box.toml"), box_scene(0.5)).expect("scene");
    let cfg = write_config(
        tmp.path(),
        "edit.toml",
        r#"
name = "edit"
description = "one scene file, one run"
[evaluation]
points = 16
[reference]
samples = 16
[outputs]
images = false
plots = false
[[scenes]]
scene = "box.toml"
[[methods]]
method = "matrix"
"#,
    );
    let out = tmp.path().join("out");
    for (rho, expect) in [
        (0.5, "1 runs executed, 0 skipped"),
        (0.5, "0 runs executed, 1 skipped"),
        (0.6, "1 runs executed, 0 skipped"),
    ] {
        std::fs::write(tmp.path().join("box.toml"), box_scene(rho)).expect("scene");
        let o = run_ok(tmp.path(), &cfg, &out);
        assert!(text(&o).contains(expect), "ρ = {rho}: {}", text(&o));
    }
}

#[test]
fn shards_cover_every_run_once_and_merge() {
    let tmp = tempfile::tempdir().expect("tmp");
    let body = TINY
        .replace(
            "[[scenes]]\nscene = \"builtin:cornell\"\nlabel = \"cornell\"\n",
            "",
        )
        .replace("seeds = [1]", "seeds = [1, 2, 3]");
    let cfg = write_config(tmp.path(), "tiny.toml", &body);
    let mut ids = Vec::new();
    let mut dirs = Vec::new();
    for i in 0..3 {
        let out = tmp.path().join(format!("shard{i}"));
        let o = radlab_with_env(
            tmp.path(),
            &[
                "run",
                cfg.to_str().expect("utf8"),
                "--out",
                out.to_str().expect("utf8"),
                "--shard",
                &format!("{i}/3"),
            ],
            &[],
        );
        assert!(o.status.success(), "{}", text(&o));
        for r in csv_rows(&out.join("runs.csv")) {
            ids.push(r[0].to_string());
        }
        dirs.push(out);
    }
    ids.sort();
    let n = ids.len();
    ids.dedup();
    assert_eq!(n, 6, "1 scene x 2 sweep points x 3 seeds");
    assert_eq!(ids.len(), 6, "no run in two shards");
    let merged = tmp.path().join("merged");
    let mut args = vec!["merge".to_string(), merged.display().to_string()];
    args.extend(dirs.iter().map(|d| d.display().to_string()));
    let o = radlab_with_env(
        tmp.path(),
        &args.iter().map(String::as_str).collect::<Vec<_>>(),
        &[],
    );
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(csv_rows(&merged.join("runs.csv")).len(), 6);
    let o = radlab_with_env(
        tmp.path(),
        &["run", cfg.to_str().expect("utf8"), "--shard", "3/3"],
        &[],
    );
    assert!(
        !o.status.success() && text(&o).contains("--shard"),
        "{}",
        text(&o)
    );
}

/// Runs the one-scene tiny experiment with `limits` appended to its [limits] table and `env` set; checks the
/// experiment itself succeeds and returns each run's (outcome, message).
fn run_isolated(
    dir: &Path,
    name: &str,
    limits: &str,
    env: &[(&str, &str)],
) -> Vec<(String, String)> {
    let body = TINY
        .replace(
            "[[scenes]]\nscene = \"builtin:cornell\"\nlabel = \"cornell\"\n",
            "",
        )
        .replace("time_limit = 20", &format!("time_limit = 20\n{limits}"));
    let cfg = write_config(dir, &format!("{name}.toml"), &body);
    let out = dir.join(name);
    let o = radlab_with_env(
        dir,
        &[
            "run",
            cfg.to_str().expect("utf8"),
            "--out",
            out.to_str().expect("utf8"),
        ],
        env,
    );
    assert!(o.status.success(), "the experiment finishes: {}", text(&o));
    let rdr = csv::Reader::from_path(out.join("runs.csv")).expect("runs.csv");
    let runs: Vec<radlab_runner::experiment::execute::RunResult> =
        rdr.into_deserialize().map(|r| r.expect("row")).collect();
    assert_eq!(runs.len(), 2);
    runs.into_iter().map(|r| (r.outcome, r.message)).collect()
}

#[test]
fn crash_timeout_and_memory_limit_are_recorded() {
    let tmp = tempfile::tempdir().expect("tmp");
    // A panicking child.
    for (outcome, message) in run_isolated(tmp.path(), "crash", "", &[("RADLAB_FAULT", "panic")]) {
        assert_eq!(outcome, "crash");
        assert!(message.contains("injected fault"), "{message}");
    }
    // A child killed for time.
    for (outcome, message) in run_isolated(tmp.path(), "timeout", "kill_after = 0.001", &[]) {
        assert_eq!(outcome, "timeout", "{message}");
    }
    // A child over its memory limit.
    for (outcome, message) in run_isolated(tmp.path(), "oom", "memory_limit_mib = 1", &[]) {
        assert_eq!(outcome, "out-of-memory", "{message}");
    }
}

#[test]
fn a_run_killed_for_time_keeps_the_steps_it_measured() {
    // Path tracing doubles its paths every step toward 2^26 a point, far past what 4 s allows; killed in a
    // step, the run keeps its last evaluation: its errors, trace and points files, with the outcome timeout.
    let tmp = tempfile::tempdir().expect("tmp");
    let body = TINY
        .replace(
            "[[scenes]]\nscene = \"builtin:cornell\"\nlabel = \"cornell\"\n",
            "",
        )
        .replace("time_limit = 20", "time_limit = 1000\nkill_after = 4")
        .replace(
            "method = \"matrix\"\nparams = { visibility = \"centre\", quadrature = 1 }\n\
             sweep = { iteration = [\"jacobi\", \"conjugate-gradient\"] }",
            "method = \"pathtrace\"\nparams = { initial_samples = 1, samples = 67108864 }",
        );
    let cfg = write_config(tmp.path(), "killed.toml", &body);
    let out = tmp.path().join("killed");
    run_ok(tmp.path(), &cfg, &out);
    let rdr = csv::Reader::from_path(out.join("runs.csv")).expect("runs.csv");
    let runs: Vec<radlab_runner::experiment::execute::RunResult> =
        rdr.into_deserialize().map(|r| r.expect("row")).collect();
    assert_eq!(runs.len(), 1);
    let r = &runs[0];
    assert_eq!(r.outcome, "timeout", "{}", r.message);
    assert!(
        r.message
            .contains(&format!("figures are those of step {}", r.steps)),
        "{}",
        r.message
    );
    assert!(r.steps >= 1 && r.l1.is_finite() && r.wall_s > 0.0, "{r:?}");
    let trace = csv_rows(&out.join("trace.csv"));
    assert!(!trace.is_empty(), "the kept trace");
    let points = csv_rows(&radlab_runner::experiment::execute::points_path(
        &out, &r.id,
    ));
    assert_eq!(points.len(), 48);
    let partial = radlab_runner::experiment::execute::partial_path(&out, &r.id);
    assert!(
        !partial.exists(),
        "the partial result is folded into the run's"
    );
}

#[test]
fn config_errors_name_the_key() {
    let tmp = tempfile::tempdir().expect("tmp");
    let cases = [
        (
            TINY.replace("seeds = [1]", "seeds = [1]\ncolour = 3"),
            "colour",
        ),
        (
            TINY.replace("points = 48", "points = 0"),
            "evaluation.points",
        ),
        (
            TINY.replace("time_limit = 20", "time_limit = -1"),
            "limits.time_limit",
        ),
        (
            TINY.replace("method = \"matrix\"", "method = \"nope\""),
            "unknown method 'nope'",
        ),
        (
            TINY.replace("quadrature = 1 }", "quadrature = 1, bogus = 2 }"),
            "bogus",
        ),
        (
            TINY.replace(
                "iteration = [",
                "element_size = { from = 0.1, to = 0.0, steps = 3 }, x = [",
            ),
            "sweep.element_size",
        ),
        (
            TINY.replace(
                "iteration = [\"jacobi\", \"conjugate-gradient\"]",
                "iteration = []",
            ),
            "sweep.iteration",
        ),
        (TINY.replace("seeds = [1]", "seeds = []"), "seeds"),
        (
            TINY.replace("label = \"cornell\"", "label = \"furnace\""),
            "used twice",
        ),
        (
            TINY.replace("samples = 64", "samples = \"many\""),
            "samples",
        ),
        (
            TINY.replace(
                "label = \"cornell\"",
                "label = \"cornell\"\nreference_samples = 1",
            ),
            "reference_samples",
        ),
    ];
    for (body, needle) in cases {
        let cfg = write_config(tmp.path(), "bad.toml", &body);
        let o = radlab_with_env(tmp.path(), &["run", cfg.to_str().expect("utf8")], &[]);
        assert!(!o.status.success(), "accepted a bad config ({needle})");
        let t = text(&o);
        assert!(
            t.contains(needle) && t.contains("bad.toml"),
            "error for {needle} was: {t}"
        );
        assert!(!t.contains("panicked"), "{t}");
    }
    let o = radlab_with_env(tmp.path(), &["run", "missing.toml"], &[]);
    assert!(!o.status.success() && text(&o).contains("missing.toml"));
}

/// A CSV file's rows, and the index of each named column.
fn table<const N: usize>(path: &Path, names: [&str; N]) -> (Vec<csv::StringRecord>, [usize; N]) {
    let mut r = csv::Reader::from_path(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let h = r.headers().expect("header").clone();
    let cols = names.map(|n| h.iter().position(|x| x == n).expect(n));
    (r.records().map(|x| x.expect("row")).collect(), cols)
}

/// Rows of a scene's trace as (step, l1) pairs.
fn trace_l1(out: &Path, scene: &str) -> Vec<(u64, f64)> {
    let (rows, [sc, step, l1]) = table(&out.join("trace.csv"), ["scene", "step", "l1"]);
    rows.iter()
        .filter(|x| &x[sc] == scene)
        .map(|x| (x[step].parse().expect("step"), x[l1].parse().expect("l1")))
        .collect()
}

#[test]
fn pathtrace_experiment_error_falls_as_one_over_root_paths() {
    // A furnace (exact answer B = E/(1 − ρ)): path tracing's error is pure noise, so its relative L1 over the
    // points falls as paths^(-1/2). Step k has 16 · 2^(k−1) paths per point; the least-squares slope of
    // ln L1 against ln paths over 7 doublings must be −0.5 ± 0.05 (the L1 over 256 points fluctuates by
    // about 0.75/√256 ≈ 5% relative, i.e. ±0.05 in ln L1, giving a slope uncertainty near 0.02 over a span of
    // ln 64 ≈ 4.2).
    let tmp = tempfile::tempdir().expect("tmp");
    let cfg = write_config(
        tmp.path(),
        "pt.toml",
        r#"
name = "pt"
seeds = [1]
[evaluation]
points = 256
growth = 1.0
[outputs]
plots = true
images = false
[[scenes]]
scene = "builtin:furnace-cube?reflectance=0.5&tessellation=2"
label = "furnace"
[[methods]]
method = "pathtrace"
params = { initial_samples = 16, samples = 1024 }
"#,
    );
    let out = tmp.path().join("out");
    run_ok(tmp.path(), &cfg, &out);
    let trace = trace_l1(&out, "furnace");
    assert_eq!(trace.len(), 7, "{trace:?}");
    let pts: Vec<(f64, f64)> = trace
        .iter()
        .map(|&(k, e)| ((16.0 * 2f64.powi(k as i32 - 1)).ln(), e.ln()))
        .collect();
    let n = pts.len() as f64;
    let (mx, my) = (
        pts.iter().map(|p| p.0).sum::<f64>() / n,
        pts.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let slope = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum::<f64>()
        / pts.iter().map(|p| (p.0 - mx).powi(2)).sum::<f64>();
    assert!((slope + 0.5).abs() <= 0.05, "slope {slope}: {trace:?}");
    let report = std::fs::read_to_string(out.join("report.md")).expect("report");
    assert!(report.contains("pathtrace"), "{report}");
}

#[test]
fn pathtrace_seed_changes_its_estimates_not_the_reference() {
    // Two experiments differing only in the method's seed share one path-traced reference (one cache file,
    // reused), while the method's estimates differ. A method seed equal to the reference's seed still gives
    // estimates different from the reference (its streams are its own).
    let tmp = tempfile::tempdir().expect("tmp");
    let body = |seed: u64| {
        format!(
            r#"
name = "ptseed"
seeds = [{seed}]
[evaluation]
points = 24
[reference]
samples = 64
seed = 12345
[outputs]
images = false
plots = false
[[scenes]]
scene = "builtin:cornell"
label = "cornell"
[[methods]]
method = "pathtrace"
params = {{ initial_samples = 64, samples = 64 }}
"#
        )
    };
    let mut l1 = Vec::new();
    for seed in [1u64, 2, 12345] {
        let cfg = write_config(tmp.path(), &format!("s{seed}.toml"), &body(seed));
        let out = tmp.path().join(format!("out{seed}"));
        run_ok(tmp.path(), &cfg, &out);
        let t = trace_l1(&out, "cornell");
        l1.push(t.last().expect("a trace row").1);
    }
    let refs: Vec<_> = std::fs::read_dir(tmp.path().join("references"))
        .expect("references dir")
        .map(|e| e.expect("entry").file_name())
        .collect();
    assert_eq!(refs.len(), 1, "one shared reference: {refs:?}");
    assert!(
        l1[0] != l1[1],
        "seeds 1 and 2 give the same estimates: {l1:?}"
    );
    assert!(l1.iter().all(|&e| e > 0.0), "{l1:?}");
}

#[test]
fn a_scene_s_reference_samples_override_the_experiment_s() {
    // The same scene twice, once at the experiment's 16 reference samples and once at its own 1,024: the
    // second reference's standard errors are about √64 = 8 times smaller at the same points.
    let tmp = tempfile::tempdir().expect("tmp");
    let cfg = write_config(
        tmp.path(),
        "refs.toml",
        r#"
name = "refs"
seeds = [1]
[evaluation]
points = 24
[reference]
samples = 16
[outputs]
images = false
plots = false
[[scenes]]
scene = "builtin:cornell"
label = "coarse"
[[scenes]]
scene = "builtin:cornell"
label = "fine"
reference_samples = 1024
[[methods]]
method = "matrix"
params = { visibility = "centre", quadrature = 1, reconstruction = "constant" }
"#,
    );
    let out = tmp.path().join("out");
    run_ok(tmp.path(), &cfg, &out);
    let se_sum = |scene: &str| -> f64 {
        let runs = std::fs::read_dir(out.join("runs")).expect("runs dir");
        let path = runs
            .map(|e| e.expect("entry").path())
            .find(|p| {
                let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
                name.contains(scene) && name.ends_with(".points.csv")
            })
            .expect("a points file");
        let (rows, cols) = table(&path, ["se_r", "se_g", "se_b"]);
        rows.iter()
            .map(|row| {
                cols.iter()
                    .map(|&c| row[c].parse::<f64>().expect("se"))
                    .sum::<f64>()
            })
            .sum()
    };
    let ratio = se_sum("coarse") / se_sum("fine");
    assert!(
        (5.0..12.0).contains(&ratio),
        "standard errors at 16 and 1,024 samples differ by {ratio}, not about 8"
    );
}

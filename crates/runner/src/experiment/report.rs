//! `report.md` (per scene: the reference and its noise floor, then per method the best time to reach 10%, 3% and
//! 1% relative L1 error at the experiment's points, the best final error with its max error and image error, the
//! run outcomes, where path tracing and the finite-element methods cross, and the figures) and `meta.json` (the
//! config as run, git commit, versions, threads, machine, start and end times).
//!
//! Time is time to answer: the solver's set-up (hierarchy builds, preprocesses), its steps and one answering
//! pass at the points (a final gather's rays and time; path tracing does all its work in its steps). The
//! crossover: at error level e, path tracing's cost is per point, t_pt(N) = a N with a = its time to e over the
//! experiment's N points; a finite-element method's is t_fe(N) = s + g N with s its set-up and solving time to
//! e and g its answering time per point. They are
//! equal at N* = s / (a − g) (when a > g; otherwise path tracing is cheaper at every N); below N* path tracing
//! is cheaper, above it the finite-element solution.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;

use super::execute::{RunResult, TraceRow};
use crate::output::atomic::write_bytes;

/// Error levels of the report's table.
pub const THRESHOLDS: [f64; 3] = [0.10, 0.03, 0.01];

/// The trace row at which a run of (scene, label) first answered with relative L1 ≤ `thr` at the least time to
/// answer (set-up, solving and one answering pass).
pub fn row_to<'a>(
    trace: &'a [TraceRow],
    scene: &str,
    label: &str,
    thr: f64,
) -> Option<&'a TraceRow> {
    trace
        .iter()
        .filter(|t| t.scene == scene && t.label == label && t.l1 <= thr)
        .min_by(|a, b| a.time_to_answer().total_cmp(&b.time_to_answer()))
}

/// Earliest time to answer (set-up, steps and one answering pass) at which any run of (scene, label) reached relative
/// L1 ≤ `thr`.
pub fn time_to(trace: &[TraceRow], scene: &str, label: &str, thr: f64) -> Option<f64> {
    row_to(trace, scene, label, thr).map(TraceRow::time_to_answer)
}

/// Where path tracing's cost, a per point, equals a finite-element method's, s + g per point: N* = s/(a − g).
/// `None` when a ≤ g (path tracing is cheaper at any number of points).
pub fn crossover(a: f64, s: f64, g: f64) -> Option<f64> {
    (a > g && s >= 0.0).then(|| s / (a - g))
}

/// One line of the crossover table: at error level `level`, path tracing's time per point, the best
/// finite-element method at the experiment's N points (label, solving time, answering time per point) and N*.
#[derive(Clone, Debug, PartialEq)]
pub struct Crossing {
    /// Error level.
    pub level: f64,
    /// Path tracing's time per point to reach it.
    pub per_point: f64,
    /// The finite-element method (label) answering fastest at the experiment's point count.
    pub best: String,
    /// Its set-up and solving time.
    pub solve: f64,
    /// Its answering time per point.
    pub answer_per_point: f64,
    /// The crossover point count (`None`: path tracing is cheaper at any count).
    pub points: Option<f64>,
}

/// The crossovers of a scene at each of [`THRESHOLDS`] reached by path tracing and by some other method.
/// Methods are path tracing if their label is `pathtrace_label`'s; `n` is the experiment's point count.
pub fn crossings(
    trace: &[TraceRow],
    scene: &str,
    pathtrace_labels: &[&str],
    other_labels: &[&str],
    n: f64,
) -> Vec<Crossing> {
    let mut out = Vec::new();
    if !(n > 0.0) {
        return out;
    }
    for &level in &THRESHOLDS {
        let Some(pt) = pathtrace_labels
            .iter()
            .filter_map(|l| time_to(trace, scene, l, level))
            .min_by(f64::total_cmp)
        else {
            continue;
        };
        let best = other_labels
            .iter()
            .filter_map(|l| row_to(trace, scene, l, level).map(|r| (l, r)))
            .min_by(|a, b| a.1.time_to_answer().total_cmp(&b.1.time_to_answer()));
        let Some((label, row)) = best else { continue };
        let a = pt / n;
        let g = row.answer_s / n;
        let solve = row.setup_s + row.wall_s;
        out.push(Crossing {
            level,
            per_point: a,
            best: label.to_string(),
            solve,
            answer_per_point: g,
            points: crossover(a, solve, g),
        });
    }
    out
}

fn fmt_time(t: Option<f64>) -> String {
    t.map_or_else(
        || "—".to_string(),
        |s| {
            if s < 1e-3 {
                format!("{:.1} µs", s * 1e6)
            } else if s < 1.0 {
                format!("{:.0} ms", s * 1e3)
            } else {
                format!("{s:.2} s")
            }
        },
    )
}

/// The report's markdown.
pub fn markdown(
    name: &str,
    description: &str,
    runs: &[RunResult],
    trace: &[TraceRow],
    figures: &BTreeMap<String, Vec<String>>,
    image_errors: &BTreeMap<(String, String), f64>,
) -> String {
    let mut s = format!("# {name}\n\n{description}\n\n");
    let mut scenes: Vec<&str> = Vec::new();
    for r in runs {
        if !scenes.contains(&r.scene.as_str()) {
            scenes.push(&r.scene);
        }
    }
    for scene in scenes {
        let rs: Vec<&RunResult> = runs.iter().filter(|r| r.scene == scene).collect();
        let floor = rs.iter().map(|r| r.floor_l1).fold(0.0, f64::max);
        let kind = rs.first().map_or("", |r| r.reference.as_str());
        let n = rs.iter().map(|r| r.points).max().unwrap_or(0);
        let _ = writeln!(
            s,
            "## {scene}\n\nReference: {kind}; noise floor (relative L1) {floor:.2e}. Times are to answer at the \
             {n} evaluation points: the solver's set-up, its steps and one answering pass (a final gather's cost). \
             The max \
             error is relative to max(|reference|, {:.0}% of the scene's area-mean reference radiosity) at each \
             point. The image error is the mean relative difference of the best run's image from the path-traced \
             reference image (path tracing's image is rendered at the paths per point it reached).\n",
            radlab_method::error_metric::MAX_ERROR_FLOOR * 100.0
        );
        let _ = writeln!(
            s,
            "| method | runs | time to 10% | time to 3% | time to 1% | best final L1 | its max | its image error | its time | outcomes |"
        );
        let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|");
        let mut labels: Vec<&str> = Vec::new();
        for r in &rs {
            if !labels.contains(&r.label.as_str()) {
                labels.push(&r.label);
            }
        }
        for &label in &labels {
            let mine: Vec<&&RunResult> = rs.iter().filter(|r| r.label == label).collect();
            let best = mine
                .iter()
                .filter(|r| r.l1.is_finite())
                .min_by(|a, b| a.l1.total_cmp(&b.l1));
            let mut outcomes: BTreeMap<&str, usize> = BTreeMap::new();
            for r in &mine {
                *outcomes.entry(r.outcome.as_str()).or_default() += 1;
            }
            let outcomes: Vec<String> = outcomes.iter().map(|(k, v)| format!("{k} {v}")).collect();
            let times: Vec<String> = THRESHOLDS
                .iter()
                .map(|&t| fmt_time(time_to(trace, scene, label, t)))
                .collect();
            let image = image_errors
                .get(&(scene.to_string(), label.to_string()))
                .map_or("—".into(), |e| format!("{:.1}%", e * 100.0));
            let _ = writeln!(
                s,
                "| {label} | {} | {} | {} | {} | {} | {} | {image} | {} | {} |",
                mine.len(),
                times[0],
                times[1],
                times[2],
                best.map_or("—".into(), |b| format!("{:.2e}", b.l1)),
                best.map_or("—".into(), |b| format!("{:.0}%", b.max * 100.0)),
                fmt_time(best.map(|b| b.time_to_answer())),
                outcomes.join(", ")
            );
        }
        let pt: Vec<&str> = labels
            .iter()
            .copied()
            .filter(|l| {
                rs.iter()
                    .any(|r| r.label == *l && r.method == crate::pathtraced::NAME)
            })
            .collect();
        let fe: Vec<&str> = labels.iter().copied().filter(|l| !pt.contains(l)).collect();
        let cross = crossings(trace, scene, &pt, &fe, n as f64);
        if !cross.is_empty() {
            let _ = writeln!(
                s,
                "\nWhere path tracing and the finite-element methods cross: path tracing pays per point, a \
                 finite-element solution (its set-up and solve) once for the scene, plus its answering per point. Below the crossover \
                 point count path tracing answers sooner; above it the finite-element method does.\n"
            );
            let _ = writeln!(
                s,
                "| error | path tracing per point | fastest other method at {n} points | its set-up and solve | its answer per point | crossover points |"
            );
            let _ = writeln!(s, "|---|---|---|---|---|---|");
            for c in &cross {
                let _ = writeln!(
                    s,
                    "| {:.0}% | {} | {} | {} | {} | {} |",
                    c.level * 100.0,
                    fmt_time(Some(c.per_point)),
                    c.best,
                    fmt_time(Some(c.solve)),
                    fmt_time(Some(c.answer_per_point)),
                    c.points
                        .map_or("none (path tracing cheaper at any count)".into(), |p| {
                            format!("{p:.0}")
                        })
                );
            }
        }
        let failed: Vec<&&RunResult> = rs.iter().filter(|r| !r.message.is_empty()).collect();
        if !failed.is_empty() {
            let _ = writeln!(s, "\nRuns that did not finish normally:\n");
            for r in failed {
                let _ = writeln!(
                    s,
                    "- `{}` ({}): {}",
                    r.id,
                    r.outcome,
                    r.message.replace('\n', " ")
                );
            }
        }
        s.push('\n');
        for f in figures.get(scene).into_iter().flatten() {
            let _ = writeln!(s, "![{f}]({f})\n");
        }
    }
    let series = super::plots::scaling_series(runs);
    if !series.is_empty() {
        let _ = writeln!(
            s,
            "## Scaling\n\nLeast-squares slopes of log(time) and log(peak memory) against log(input faces), \
            over the finished runs of each family (a slope of 1 is linear, 2 quadratic).\n"
        );
        let _ = writeln!(s, "| family | method | faces | time slope | memory slope |");
        let _ = writeln!(s, "|---|---|---|---|---|");
        for (fam, label, pts) in &series {
            let t: Vec<(f64, f64)> = pts.iter().map(|p| (p.0, p.1)).collect();
            let m: Vec<(f64, f64)> = pts.iter().map(|p| (p.0, p.2)).collect();
            let f = |x: Option<f64>| x.map_or("—".into(), |v| format!("{v:.2}"));
            let range = format!("{:.0e} … {:.0e}", pts[0].0, pts[pts.len() - 1].0);
            let _ = writeln!(
                s,
                "| {fam} | {label} | {range} | {} | {} |",
                f(super::plots::loglog_slope(&t)),
                f(super::plots::loglog_slope(&m))
            );
        }
        s.push('\n');
        for f in figures.get("").into_iter().flatten() {
            let _ = writeln!(s, "![{f}]({f})\n");
        }
    }
    s
}

/// Writes `report.md`.
pub fn write_report(dir: &Path, text: &str) -> Result<()> {
    write_bytes(
        &dir.join("report.md"),
        |w| Ok(w.write_all(text.as_bytes())?),
    )
}

fn read_first_line(path: &str, prefix: &str) -> Option<String> {
    std::fs::read_to_string(path)
        .ok()?
        .lines()
        .find(|l| l.starts_with(prefix))
        .map(|l| l.split_once(':').map_or(l, |(_, v)| v).trim().to_string())
}

/// The machine and build facts for `meta.json`.
pub fn environment() -> serde_json::Value {
    let git = std::process::Command::new("git")
        .args(["rev-parse", "HEAD"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string());
    let dirty = std::process::Command::new("git")
        .args(["status", "--porcelain", "--untracked-files=no"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| !o.stdout.is_empty());
    serde_json::json!({
        "radlab_version": env!("CARGO_PKG_VERSION"),
        "git_commit": git,
        "git_dirty": dirty,
        "threads": rayon::current_num_threads(),
        "hostname": std::fs::read_to_string("/proc/sys/kernel/hostname").ok().map(|s| s.trim().to_string()),
        "cpu": read_first_line("/proc/cpuinfo", "model name"),
        "cores": std::thread::available_parallelism().map(|n| n.get()).ok(),
        "memory": read_first_line("/proc/meminfo", "MemTotal"),
        "os": std::env::consts::OS,
        "arch": std::env::consts::ARCH,
        "profile": if cfg!(debug_assertions) { "debug" } else { "release" },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(label: &str, wall: f64, answer: f64, l1: f64) -> TraceRow {
        TraceRow {
            id: label.into(),
            scene: "s".into(),
            label: label.into(),
            wall_s: wall,
            answer_s: answer,
            l1,
            ..Default::default()
        }
    }

    #[test]
    fn crossover_on_a_synthetic_table() {
        // At 100 points: path tracing reaches 10% in 0.5 s and 3% in 4 s (5 and 40 ms per point). Matrix
        // solves to 10% in 0.9 s and answers in 0.1 s (1 ms per point), to 3% in 1.9 s; a constant-element
        // method reaches 10% only, in 3 s. Crossovers: 10%: N* = 0.9/(0.005 − 0.001) = 225; 3%:
        // 1.9/(0.04 − 0.001) = 48.7; 1%: nobody reaches it.
        let trace = vec![
            row("pathtrace", 0.2, 0.0, 0.2),
            row("pathtrace", 0.5, 0.0, 0.09),
            row("pathtrace", 4.0, 0.0, 0.029),
            row("matrix", 0.9, 0.1, 0.08),
            row("matrix", 1.9, 0.1, 0.02),
            row("constant", 3.0, 0.0, 0.1),
        ];
        let c = crossings(&trace, "s", &["pathtrace"], &["matrix", "constant"], 100.0);
        assert_eq!(c.len(), 2, "{c:?}");
        assert_eq!(c[0].best, "matrix");
        assert!((c[0].points.expect("10%") - 225.0).abs() < 1e-9, "{c:?}");
        assert!(
            (c[1].points.expect("3%") - 1.9 / (0.04 - 0.001)).abs() < 1e-9,
            "{c:?}"
        );
        // A set-up (a hierarchy build) counts in the time to answer and in the solve of the crossover: 2 s of
        // set-up puts the 3% crossover at (2 + 1.9)/(0.04 − 0.001) = 100 points and matrix to 3% at 4 s.
        let built: Vec<TraceRow> = trace
            .iter()
            .map(|t| TraceRow {
                setup_s: if t.label == "matrix" { 2.0 } else { 0.0 },
                ..t.clone()
            })
            .collect();
        assert_eq!(time_to(&built, "s", "matrix", 0.03), Some(4.0));
        let c = crossings(&built, "s", &["pathtrace"], &["matrix", "constant"], 100.0);
        assert_eq!(c[1].solve, 3.9);
        assert!((c[1].points.expect("3%") - 100.0).abs() < 1e-9, "{c:?}");
        // Path tracing no costlier per point than answering: no crossover.
        assert_eq!(crossover(0.001, 5.0, 0.002), None);
        assert_eq!(crossover(0.01, 0.0, 0.0), Some(0.0));
    }
}

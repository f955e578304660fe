//! `report.md` (per scene: the reference and its noise floor, then per method the best time to reach 10%, 3% and
//! 1% relative L1 error, the best final error and the run outcomes, with the figures embedded) and `meta.json`
//! (the config as run, git commit, versions, threads, machine, start and end times).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;

use super::execute::{RunResult, TraceRow};
use crate::output::atomic::write_bytes;

/// Error levels of the report's table.
pub const THRESHOLDS: [f64; 3] = [0.10, 0.03, 0.01];

/// Earliest wall time at which any run of (scene, label) reached relative L1 ≤ `thr`.
pub fn time_to(trace: &[TraceRow], scene: &str, label: &str, thr: f64) -> Option<f64> {
    trace
        .iter()
        .filter(|t| t.scene == scene && t.label == label && t.l1 <= thr)
        .map(|t| t.wall_s)
        .min_by(f64::total_cmp)
}

fn fmt_time(t: Option<f64>) -> String {
    t.map_or_else(
        || "—".to_string(),
        |s| {
            if s < 1.0 {
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
        let _ = writeln!(
            s,
            "## {scene}\n\nReference: {kind}; noise floor (relative L1) {floor:.2e}.\n"
        );
        let _ = writeln!(
            s,
            "| method | runs | time to 10% | time to 3% | time to 1% | best final L1 | its time | outcomes |"
        );
        let _ = writeln!(s, "|---|---|---|---|---|---|---|---|");
        let mut labels: Vec<&str> = Vec::new();
        for r in &rs {
            if !labels.contains(&r.label.as_str()) {
                labels.push(&r.label);
            }
        }
        for label in labels {
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
            let _ = writeln!(
                s,
                "| {label} | {} | {} | {} | {} | {} | {} | {} |",
                mine.len(),
                times[0],
                times[1],
                times[2],
                best.map_or("—".into(), |b| format!("{:.2e}", b.l1)),
                fmt_time(best.map(|b| b.wall_s)),
                outcomes.join(", ")
            );
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

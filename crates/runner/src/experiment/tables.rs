//! The experiment's tidy tables: `runs.csv` (one row per run, from `runs/<id>.json`) and `trace.csv` (one row
//! per evaluated step, from `runs/<id>.trace.csv`), rebuilt from the per-run files so re-runs, shards and merges
//! all end in the same tables. Columns read directly into pandas or R.

use std::path::Path;

use anyhow::{Context, Result};

use super::execute::{RunResult, TraceRow, read_result};
use crate::output::atomic::write_csv_rows;

/// Every completed run's result in `dir/runs`, by expansion index.
pub fn collect_results(dir: &Path) -> Result<Vec<RunResult>> {
    let mut out = Vec::new();
    let runs = dir.join("runs");
    if !runs.exists() {
        return Ok(out);
    }
    for entry in
        std::fs::read_dir(&runs).with_context(|| format!("{}: cannot list", runs.display()))?
    {
        let path = entry?.path();
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or_default();
        if name.ends_with(".json") && !name.ends_with(".job.json") && !name.starts_with('.') {
            out.push(read_result(&path)?);
        }
    }
    out.sort_by(|a, b| a.index.cmp(&b.index).then(a.id.cmp(&b.id)));
    Ok(out)
}

/// Writes `runs.csv` and `trace.csv` from the per-run files.
pub fn write_tables(dir: &Path, results: &[RunResult]) -> Result<()> {
    write_csv_rows(&dir.join("runs.csv"), results)?;
    let mut rows = Vec::new();
    for r in results {
        let p = super::execute::trace_path(dir, &r.id);
        if p.exists() {
            // The set-up is the run's (traces written before it was recorded per row read it as 0).
            rows.extend(read_trace(&p)?.into_iter().map(|t| TraceRow {
                setup_s: r.setup_s,
                ..t
            }));
        }
    }
    write_csv_rows(&dir.join("trace.csv"), &rows)
}

/// Reads a trace CSV.
pub fn read_trace(path: &Path) -> Result<Vec<TraceRow>> {
    let mut rdr =
        csv::Reader::from_path(path).with_context(|| format!("{}: cannot read", path.display()))?;
    rdr.deserialize()
        .map(|r| r.with_context(|| format!("{}: malformed trace row", path.display())))
        .collect()
}

/// Reads `runs.csv`.
pub fn read_runs(path: &Path) -> Result<Vec<RunResult>> {
    let mut rdr =
        csv::Reader::from_path(path).with_context(|| format!("{}: cannot read", path.display()))?;
    rdr.deserialize()
        .map(|r| r.with_context(|| format!("{}: malformed row", path.display())))
        .collect()
}

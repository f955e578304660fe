//! Atomic file output: everything radlab writes goes to a temporary file in the destination's directory and is
//! renamed into place only once complete, so an interrupted or failed run never leaves a half-written file.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

/// The temporary sibling a file is written to before the rename. The extension is kept last so writers that
/// choose a format by extension (EXR) still work.
pub fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.tmp.{}", std::process::id(), ext(path)))
}

fn ext(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into())
}

/// Creates the parent directory of `path` if needed.
pub fn ensure_parent(path: &Path) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        fs::create_dir_all(dir)
            .with_context(|| format!("cannot create directory {}", dir.display()))?;
    }
    Ok(())
}

/// Writes a file through `write` (given the temporary path), then renames it over `path`. On failure the
/// temporary file is removed and `path` is untouched.
pub fn write_via_temp(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    ensure_parent(path)?;
    let tmp = temp_path(path);
    let result = write(&tmp).and_then(|()| {
        fs::rename(&tmp, path).with_context(|| {
            format!(
                "cannot move {} into place as {}",
                tmp.display(),
                path.display()
            )
        })
    });
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// Writes bytes produced by `fill` atomically.
pub fn write_bytes(path: &Path, fill: impl FnOnce(&mut dyn Write) -> Result<()>) -> Result<()> {
    write_via_temp(path, |tmp| {
        let file =
            fs::File::create(tmp).with_context(|| format!("cannot create {}", tmp.display()))?;
        let mut w = std::io::BufWriter::new(file);
        fill(&mut w)?;
        w.flush()
            .with_context(|| format!("cannot write {}", tmp.display()))?;
        w.into_inner().map_err(|e| e.into_error())?.sync_all().ok();
        Ok(())
    })
}

/// Writes `rows` as CSV (a header from the first row's fields) atomically.
pub fn write_csv_rows<T: serde::Serialize>(path: &Path, rows: &[T]) -> Result<()> {
    write_bytes(path, |w| {
        let mut out = csv::Writer::from_writer(w);
        for r in rows {
            out.serialize(r)?;
        }
        out.flush()?;
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_write_leaves_nothing() {
        let dir = tempfile::tempdir().expect("tempdir");
        let p = dir.path().join("out.csv");
        let r = write_bytes(&p, |w| {
            w.write_all(b"partial")?;
            anyhow::bail!("boom")
        });
        assert!(r.is_err());
        assert!(!p.exists());
        assert_eq!(
            fs::read_dir(dir.path()).expect("dir").count(),
            0,
            "temporary file left behind"
        );
        write_bytes(&p, |w| Ok(w.write_all(b"ok")?)).expect("write");
        assert_eq!(fs::read_to_string(&p).expect("read"), "ok");
    }
}

//! What the end-to-end tests share: running the `radlab` binary in a directory and reading what it printed.

#![allow(dead_code)] // each test file uses its own subset

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// `radlab ARGS` run in `dir`, with `env` set; its output (whatever the exit status).
pub fn radlab_with_env(dir: &Path, args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_radlab"));
    c.current_dir(dir).args(args);
    for (k, v) in env {
        c.env(k, v);
    }
    c.output().expect("radlab runs")
}

/// `radlab ARGS` run in `dir`; its output (whatever the exit status).
pub fn radlab(dir: &Path, args: &[&str]) -> Output {
    radlab_with_env(dir, args, &[])
}

/// What a run printed, stdout then stderr.
pub fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// The repository's root.
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

//! The command line (README.md, "The command line"): parsed with clap, dispatched to
//! [`crate::commands`]. Errors print as `error: ...` with their causes and exit with status 1.

use anyhow::Result;
use clap::{Parser, Subcommand};

use std::path::PathBuf;

use crate::commands::{catalogue, compare, export, probe, render, solve};
use crate::experiment;

/// radlab: radiosity and Monte Carlo methods side by side on the same scenes, measured the same way.
#[derive(Debug, Parser)]
#[command(name = "radlab", version, about, long_about = None)]
pub struct Cli {
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(long, global = true)]
    pub threads: Option<usize>,
    /// The subcommand.
    #[command(subcommand)]
    pub command: Command,
}

/// Subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run an experiment (default experiments/quickstart.toml): tables, plots, images, report.
    Run(experiment::RunArgs),
    /// One solve: per-face CSV, PLY mesh with radiosity, EXR image if the scene has a camera.
    Solve(solve::SolveArgs),
    /// Radiosity at given points (CSV on stdout: x,y,z,r,g,b).
    Probe(probe::ProbeArgs),
    /// An EXR image of a method's solution through the scene's camera.
    Render(render::RenderArgs),
    /// List builtin scenes and file formats.
    Scenes,
    /// List methods with their parameters and defaults.
    Methods,
    /// Redraw an experiment's figures and report from its CSV tables.
    Plot {
        /// The experiment's results directory.
        dir: PathBuf,
    },
    /// Compare runs' answers at the evaluation points (`runs/<id>.points.csv`): L1, bias, and each pair's
    /// difference with a bootstrap interval.
    Compare(compare::CompareArgs),
    /// Write the scene for Radiance or Mitsuba 3, with the evaluation points and a script that asks that
    /// renderer for the radiosity at them (a CSV `radlab compare` reads).
    Export(export::ExportArgs),
    /// Merge the results of shards (directories of `radlab run --shard`) into one directory.
    Merge {
        /// The merged results directory.
        out: PathBuf,
        /// The shard directories.
        dirs: Vec<PathBuf>,
    },
    /// Internal: execute one run of an experiment in this process (used for run isolation).
    #[command(hide = true)]
    RunOne {
        /// The job file.
        job: PathBuf,
    },
}

/// Parses the arguments and runs the command.
pub fn main() -> Result<()> {
    let cli = Cli::parse();
    if let Some(n) = cli.threads {
        if n == 0 {
            anyhow::bail!("--threads must be at least 1");
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()?;
    }
    match &cli.command {
        Command::Run(a) => experiment::run(a, cli.threads),
        Command::Plot { dir } => experiment::plot(dir),
        Command::Merge { out, dirs } => experiment::merge(out, dirs),
        Command::RunOne { job } => experiment::execute::run_child(job),
        Command::Solve(a) => solve::run(a),
        Command::Probe(a) => probe::run(a),
        Command::Compare(a) => compare::run(a),
        Command::Export(a) => export::run(a),
        Command::Render(a) => render::run(a),
        Command::Scenes => {
            catalogue::scenes();
            Ok(())
        }
        Command::Methods => {
            catalogue::methods();
            Ok(())
        }
    }
}

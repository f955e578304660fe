//! # radlab-runner
//!
//! The `radlab` command: runs methods on scenes, measures them against references, and writes what people read
//! (CSV tables, PLY meshes, EXR images, plots). It is the only part of radlab that prints, writes files or reads
//! the clock for reports.

pub mod cli;
pub mod commands;
pub mod experiment;
pub mod face_cache;
pub mod methods;
pub mod output;
pub mod pathtraced;
pub mod points_csv;
pub mod progress;
pub mod scene_spec;
pub mod solve_loop;

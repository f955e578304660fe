//! `radlab probe SCENE --method M --points POINTS.csv`: radiosity at given points, CSV on stdout with header
//! `x,y,z,r,g,b`, one row per input point, in input order.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Result;

use super::solve::{MethodArgs, load, solve};
use crate::points_csv;

/// Options of `radlab probe`.
#[derive(Clone, Debug, clap::Args)]
pub struct ProbeArgs {
    #[command(flatten)]
    /// Scene, method and parameters.
    pub common: MethodArgs,
    /// CSV of points: columns x,y,z and optionally nx,ny,nz.
    #[arg(long)]
    pub points: PathBuf,
}

/// Runs `radlab probe`.
pub fn run(args: &ProbeArgs) -> Result<()> {
    let raw = points_csv::read_points(&args.points)?;
    let loaded = load(&args.common.scene)?;
    let points = points_csv::match_points(&loaded.scene, &raw, &args.points.display().to_string())?;
    let values = match solve(&loaded, &args.common)? {
        super::solve::Solved::PathTraced(pt) => {
            pt.estimate(&points.iter().map(|p| (p.face, p.point)).collect::<Vec<_>>())
        }
        solved => {
            let s = solved.solution();
            points
                .iter()
                .map(|p| s.radiosity_at(p.face, p.point))
                .collect()
        }
    };
    let stdout = std::io::stdout();
    let mut w = csv::Writer::from_writer(stdout.lock());
    w.write_record(["x", "y", "z", "r", "g", "b"])?;
    for (p, b) in points.iter().zip(&values) {
        w.write_record([p.input.x, p.input.y, p.input.z, b.x, b.y, b.z].map(|v| v.to_string()))?;
    }
    w.flush()?;
    std::io::stdout().flush()?;
    Ok(())
}

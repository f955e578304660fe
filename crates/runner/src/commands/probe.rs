//! `radlab probe SCENE --method M --points POINTS.csv`: radiosity at given points, CSV on stdout with header
//! `x,y,z,r,g,b`, one row per input point, in input order. Methods with a standard error per point (`pathtrace`)
//! add the columns `se_r,se_g,se_b`. Answers come through the method's own reconstruction, as in `render` and
//! experiments.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Result;
use radlab_method::{EvalPoint, MethodParams};
use radlab_pathtrace::{PathTraceParams, PathTraceSolver, surface_points};
use radlab_scene::Rgb;

use super::solve::{MethodArgs, load, solve};
use crate::{pathtraced, points_csv, progress, solve_loop};

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
    let points = points_csv::match_points(
        &loaded.scene,
        &loaded.accel,
        &raw,
        &args.points.display().to_string(),
    )?;
    let eval: Vec<EvalPoint> = points
        .iter()
        .map(|p| EvalPoint {
            face: p.face,
            point: p.point,
            normal: loaded.scene.faces[p.face].normal,
            weight: 1.0,
        })
        .collect();
    let a = &args.common;
    let (values, std_errors): (Vec<Rgb>, Option<Vec<Rgb>>) = if a.method == pathtraced::NAME {
        let params = PathTraceParams::from_table(a.table()?)?;
        let mut solver = PathTraceSolver::new(
            &loaded.scene,
            &loaded.accel,
            params,
            a.seed,
            surface_points(&eval),
        )?;
        let bar = progress::spinner("pathtrace points");
        solve_loop::run(&mut solver, a.limits()?, |_, rec| {
            bar.set_message(format!("step {} | {} rays", rec.step, rec.stats.rays));
            bar.tick();
            Ok(())
        })?;
        bar.finish_and_clear();
        let est = solver.estimates();
        (
            est.iter().map(|e| e.mean).collect(),
            Some(est.iter().map(|e| e.std_error).collect()),
        )
    } else {
        let solved = solve(&loaded, a, &eval)?;
        let s = solved.solution();
        (
            points
                .iter()
                .map(|p| s.radiosity_at(p.face, p.point))
                .collect(),
            None,
        )
    };
    let stdout = std::io::stdout();
    let mut w = csv::Writer::from_writer(stdout.lock());
    let mut header = vec!["x", "y", "z", "r", "g", "b"];
    if std_errors.is_some() {
        header.extend(["se_r", "se_g", "se_b"]);
    }
    w.write_record(&header)?;
    for (i, (p, b)) in points.iter().zip(&values).enumerate() {
        let mut row: Vec<String> = [p.input.x, p.input.y, p.input.z, b.x, b.y, b.z]
            .iter()
            .map(|v| v.to_string())
            .collect();
        if let Some(se) = &std_errors {
            row.extend([se[i].x, se[i].y, se[i].z].iter().map(|v| v.to_string()));
        }
        w.write_record(&row)?;
    }
    w.flush()?;
    std::io::stdout().flush()?;
    Ok(())
}

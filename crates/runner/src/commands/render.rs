//! `radlab render SCENE --method M --out IMAGE.exr`: an image through the scene's camera. Finite-element and
//! mesh Monte Carlo methods are solved, then rendered by primary rays (radiance B/π); `pathtrace` renders by
//! camera path tracing and also writes a per-pixel standard-error image `IMAGE-stderr.exr` beside it.

use std::path::PathBuf;

use anyhow::{Result, bail};

use super::solve::{MethodArgs, load, render_image, solve};
use crate::output::exr_image::write_exr;
use crate::pathtraced;

/// Options of `radlab render`.
#[derive(Clone, Debug, clap::Args)]
pub struct RenderArgs {
    #[command(flatten)]
    /// Scene, method and parameters.
    pub common: MethodArgs,
    /// The EXR file to write.
    #[arg(long)]
    pub out: PathBuf,
    /// Jittered samples per pixel for finite-element methods (path tracing takes `--set samples_per_pixel=N`).
    #[arg(long, default_value_t = 4)]
    pub spp: u32,
}

/// The standard-error image's path beside `out`.
pub fn stderr_path(out: &std::path::Path) -> PathBuf {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "image".into());
    out.with_file_name(format!("{stem}-stderr.exr"))
}

/// Runs `radlab render`.
pub fn run(args: &RenderArgs) -> Result<()> {
    let a = &args.common;
    let loaded = load(&a.scene)?;
    let Some(camera) = loaded.scene.camera.clone() else {
        bail!(
            "scene '{}' has no camera; add a [camera] table (see scenes/README.md)",
            loaded.scene.name
        );
    };
    if a.method == pathtraced::NAME {
        let (mean, err) =
            pathtraced::render(&loaded.scene, &loaded.accel, &camera, a.table()?, a.seed)?;
        write_exr(&args.out, &mean)?;
        let side = stderr_path(&args.out);
        write_exr(&side, &err)?;
        println!("wrote {} and {}", args.out.display(), side.display());
        return Ok(());
    }
    let solved = solve(&loaded, a, &[])?;
    let image = render_image(&loaded, &camera, solved.solution(), args.spp, a.seed);
    write_exr(&args.out, &image)?;
    println!("wrote {}", args.out.display());
    Ok(())
}

//! The `pathtrace` method's runner side: its name, summary and parameters for `radlab methods`, and camera
//! path tracing for `render` with a progress bar. The stepped method itself (path tracing at given points,
//! doubling the paths per step) is [`radlab_pathtrace::PathTraceSolver`].

use anyhow::Result;
use radlab_answer::Image;
use radlab_method::MethodParams;
use radlab_pathtrace::{PathTraceParams, RenderParams};
use radlab_scene::{Camera, Scene};
use radlab_visibility::Accel;

use crate::methods::{ParamLine, param_lines};
use crate::progress;

/// The method's name.
pub const NAME: &str = "pathtrace";

/// One paragraph for `radlab methods`.
pub const SUMMARY: &str = "Path tracing at the points asked about (next-event estimation with MIS, Russian \
    roulette): unbiased, mesh-free, with a standard error; each step doubles the paths per point, so its cost \
    grows with the number of points answered (a finite-element solution pays once for the scene). The same \
    estimator with many paths is the reference. `render` path-traces the camera (parameter samples_per_pixel).";

/// Its parameters (per-point, then render), each name once: a key both read with the same default
/// (`max_depth`, `direct`) is listed with the per-point help and, where render reads it differently, render's
/// after it.
pub fn params() -> Vec<ParamLine> {
    let mut p = param_lines::<PathTraceParams>();
    for r in param_lines::<RenderParams>() {
        match p
            .iter_mut()
            .find(|l| l.name == r.name && l.default == r.default)
        {
            Some(l) if l.help != r.help => l.help = format!("{} For render: {}", l.help, r.help),
            Some(_) => {}
            None => p.push(r),
        }
    }
    p
}

/// Path-traces the camera: (mean radiance, standard error) images.
pub fn render(
    scene: &Scene,
    accel: &Accel,
    camera: &Camera,
    table: toml::Table,
    seed: u64,
) -> Result<(Image, Image)> {
    let params = RenderParams::from_table(table)?;
    let bar = progress::bar((camera.width * camera.height) as u64, "pathtrace render");
    let out = radlab_pathtrace::render(scene, accel, camera, &params, seed, &|done, _| {
        bar.set_position(done as u64)
    });
    bar.finish_and_clear();
    Ok(out)
}

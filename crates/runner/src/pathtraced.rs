//! The `pathtrace` method: radlab-pathtrace's per-point radiosity estimator used as a method. For probes it
//! estimates B at the points directly; as a [`Solution`] (for `solve`'s tables and meshes) each query runs the
//! estimator at that point with a stream derived from the seed and the point's coordinates, so answers are
//! reproducible; `render` path-traces the camera's pixels with a progress bar.

use anyhow::Result;
use glam::DVec3;
use radlab_pathtrace::{PointParams, RenderParams, SurfacePoint};
use radlab_scene::{
    Accel, Camera, FaceId, Image, MethodParams, Rgb, Scene, Solution, sampling::mix64,
};

use crate::methods::{ParamLine, param_lines};
use crate::progress;

/// The method's name.
pub const NAME: &str = "pathtrace";

/// One paragraph for `radlab methods`.
pub const SUMMARY: &str = "Per-point Monte Carlo estimator (next-event estimation with MIS, Russian roulette): \
    unbiased, mesh-free, with a standard error; the reference every method is measured against. \
    `render` path-traces the camera (parameter samples_per_pixel).";

/// Its parameters (per-point, then render).
pub fn params() -> Vec<ParamLine> {
    let mut p = param_lines::<PointParams>();
    p.extend(param_lines::<RenderParams>());
    p
}

/// The estimator as a solution.
pub struct PathTracedSolution<'a> {
    scene: &'a Scene,
    accel: &'a Accel,
    params: PointParams,
    seed: u64,
}

impl<'a> PathTracedSolution<'a> {
    /// Validates the parameters.
    pub fn new(scene: &'a Scene, accel: &'a Accel, table: toml::Table, seed: u64) -> Result<Self> {
        Ok(Self {
            scene,
            accel,
            params: PointParams::from_table(table)?,
            seed,
        })
    }

    fn surface_point(&self, face: FaceId, point: DVec3) -> SurfacePoint {
        SurfacePoint {
            face,
            point,
            normal: self.scene.faces[face].normal,
        }
    }

    /// Estimates at many points at once (parallel, with a progress bar on a terminal).
    pub fn estimate(&self, points: &[(FaceId, DVec3)]) -> Vec<Rgb> {
        let pts: Vec<SurfacePoint> = points
            .iter()
            .map(|&(f, p)| self.surface_point(f, p))
            .collect();
        let bar = progress::bar(pts.len() as u64, "pathtrace points");
        let est = radlab_pathtrace::estimate_points_with_progress(
            self.scene,
            self.accel,
            &pts,
            &self.params,
            self.seed,
            &|done, _| bar.set_position(done as u64),
        );
        bar.finish_and_clear();
        est.into_iter().map(|e| e.mean).collect()
    }
}

impl Solution for PathTracedSolution<'_> {
    fn radiosity_at(&self, face: FaceId, point: DVec3) -> Rgb {
        let key = mix64(
            point.x.to_bits() ^ mix64(point.y.to_bits() ^ mix64(point.z.to_bits() ^ face as u64)),
        );
        let pts = [self.surface_point(face, point)];
        radlab_pathtrace::estimate_points(
            self.scene,
            self.accel,
            &pts,
            &self.params,
            mix64(self.seed ^ key),
        )[0]
        .mean
    }
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

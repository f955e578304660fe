//! Per-face CSV of a solution: one row per input face with its material, area, centroid and the radiosity
//! averaged over the face (midpoint rule on a 4 × 4 grid of the face's parameter domain, exact for methods that
//! are constant over the face, and within the element resolution otherwise).

use std::path::Path;

use anyhow::Result;
use indicatif::ProgressBar;
use radlab_method::Solution;
use radlab_scene::{Rgb, Scene};
use rayon::prelude::*;

use super::atomic::write_bytes;

/// Area-mean radiosity of every face (4 × 4 midpoint samples), counting the faces answered on `bar`.
pub fn face_means(scene: &Scene, solution: &dyn Solution, bar: &ProgressBar) -> Vec<Rgb> {
    bar.set_length(scene.faces.len() as u64);
    (0..scene.faces.len())
        .into_par_iter()
        .map(|f| {
            let p = scene.polygon(f);
            let mut s = Rgb::ZERO;
            for j in 0..4 {
                for i in 0..4 {
                    s += solution.radiosity_at(
                        f,
                        p.point_at((i as f64 + 0.5) / 4.0, (j as f64 + 0.5) / 4.0),
                    );
                }
            }
            bar.inc(1);
            s / 16.0
        })
        .collect()
}

/// Writes `faces.csv`: face,material,area,cx,cy,cz,nx,ny,nz,r,g,b.
pub fn write_faces_csv(path: &Path, scene: &Scene, means: &[Rgb]) -> Result<()> {
    write_bytes(path, |w| {
        let mut out = csv::Writer::from_writer(w);
        out.write_record([
            "face", "material", "area", "cx", "cy", "cz", "nx", "ny", "nz", "r", "g", "b",
        ])?;
        for (f, b) in means.iter().enumerate() {
            let face = &scene.faces[f];
            let (c, n) = (face.centroid, face.normal);
            out.write_record([
                f.to_string(),
                scene.material(f).name.clone(),
                face.area.to_string(),
                c.x.to_string(),
                c.y.to_string(),
                c.z.to_string(),
                n.x.to_string(),
                n.y.to_string(),
                n.z.to_string(),
                b.x.to_string(),
                b.y.to_string(),
                b.z.to_string(),
            ])?;
        }
        out.flush()?;
        Ok(())
    })
}

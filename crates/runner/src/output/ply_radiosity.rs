//! PLY output of a solution: a binary little-endian mesh whose vertices carry the radiosity there (float
//! `radiosity_r/g/b`, W/m²) and a display colour (uchar `red/green/blue`: radiance B/π scaled so the brightest
//! non-emitting vertex maps to 255, then sRGB-encoded). Each face is subdivided to `piece_size` and written with
//! its own (unshared) vertices, so discontinuities between faces and elements stay sharp; each vertex's value
//! is the solution at a point nudged 1e-6 of the piece's size toward the piece's centroid (so it is read from
//! the piece itself, not a neighbour).

use std::path::Path;

use anyhow::Result;
use indicatif::ProgressBar;
use radlab_method::Solution;
use radlab_scene::{Polygon, Rgb, Scene};
use rayon::prelude::*;

use super::atomic::write_bytes;

/// Linear → sRGB-encoded byte.
pub fn srgb_byte(v: f64) -> u8 {
    let v = v.clamp(0.0, 1.0);
    let s = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

/// Writes the solution over the scene's faces, subdivided to `piece_size` (∞ for whole faces), counting the
/// pieces answered on `bar`.
pub fn write_ply(
    path: &Path,
    scene: &Scene,
    solution: &dyn Solution,
    piece_size: f64,
    bar: &ProgressBar,
) -> Result<()> {
    let pieces: Vec<(usize, Polygon)> = (0..scene.faces.len())
        .into_par_iter()
        .flat_map_iter(|f| {
            scene
                .polygon(f)
                .subdivide(piece_size)
                .into_iter()
                .map(move |p| (f, p))
        })
        .collect();
    bar.set_length(pieces.len() as u64);
    let verts: Vec<Vec<(glam::DVec3, Rgb)>> = pieces
        .par_iter()
        .map(|(f, p)| {
            let c = p.centroid();
            let answers = p
                .vertices()
                .iter()
                .map(|&v| (v, solution.radiosity_at(*f, v + (c - v) * 1e-6)))
                .collect();
            bar.inc(1);
            answers
        })
        .collect();
    let peak = pieces
        .iter()
        .zip(&verts)
        .filter(|((f, _), _)| !scene.material(*f).is_emitter())
        .flat_map(|(_, vs)| vs.iter().map(|(_, b)| b.max_element()))
        .fold(0.0f64, f64::max);
    let scale = if peak > 0.0 { 1.0 / peak } else { 1.0 };
    let nv: usize = verts.iter().map(|v| v.len()).sum();
    write_bytes(path, |w| {
        write!(
            w,
            "ply\nformat binary_little_endian 1.0\ncomment radlab radiosity of scene '{}' (W/m^2 per vertex)\n\
             element vertex {nv}\nproperty float x\nproperty float y\nproperty float z\n\
             property float radiosity_r\nproperty float radiosity_g\nproperty float radiosity_b\n\
             property uchar red\nproperty uchar green\nproperty uchar blue\n\
             element face {}\nproperty list uchar int vertex_indices\nend_header\n",
            scene.name,
            pieces.len()
        )?;
        for vs in &verts {
            for (p, b) in vs {
                for x in [p.x, p.y, p.z, b.x, b.y, b.z] {
                    w.write_all(&(x as f32).to_le_bytes())?;
                }
                w.write_all(&[
                    srgb_byte(b.x * scale),
                    srgb_byte(b.y * scale),
                    srgb_byte(b.z * scale),
                ])?;
            }
        }
        let mut next = 0i32;
        for vs in &verts {
            w.write_all(&[vs.len() as u8])?;
            for _ in vs {
                w.write_all(&next.to_le_bytes())?;
                next += 1;
            }
        }
        Ok(())
    })
}

//! Probe points: a CSV with columns `x,y,z` and optional `nx,ny,nz`. Each point is matched to the nearest
//! surface; among faces within a small tolerance of the nearest distance, the one whose normal best agrees
//! with the given normal wins (so a point on a wall's corner or between touching surfaces picks the side the
//! user meant). A point farther than [`MAX_DISTANCE_REL`] × the scene's diagonal from every face is an error
//! naming its row.

use std::path::Path;

use anyhow::{Context, Result, bail};
use glam::DVec3;
use radlab_scene::{FaceId, Scene};
use radlab_visibility::Accel;
use rayon::prelude::*;

/// How far (relative to the scene's bounding diagonal) a probe point may lie from the surface it is matched to.
pub const MAX_DISTANCE_REL: f64 = 1e-3;

/// A probe point matched to a face.
#[derive(Clone, Copy, Debug)]
pub struct ProbePoint {
    /// The point as given.
    pub input: DVec3,
    /// The face it was matched to.
    pub face: FaceId,
    /// The point projected onto that face's plane.
    pub point: DVec3,
}

/// Reads `x,y,z[,nx,ny,nz]` rows. Errors name the file and the row (1-based data row, header excluded).
pub fn read_points(path: &Path) -> Result<Vec<(DVec3, Option<DVec3>)>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{}: cannot read", path.display()))?;
    let mut rdr = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let headers = rdr
        .headers()
        .with_context(|| format!("{}: cannot read the header", path.display()))?
        .clone();
    let col = |name: &str| headers.iter().position(|h| h.eq_ignore_ascii_case(name));
    let (Some(x), Some(y), Some(z)) = (col("x"), col("y"), col("z")) else {
        bail!(
            "{}: the header must name columns x,y,z (and optionally nx,ny,nz); found: {}",
            path.display(),
            headers.iter().collect::<Vec<_>>().join(",")
        );
    };
    let normal_cols = match (col("nx"), col("ny"), col("nz")) {
        (Some(a), Some(b), Some(c)) => Some((a, b, c)),
        (None, None, None) => None,
        _ => bail!("{}: give all of nx,ny,nz or none of them", path.display()),
    };
    let mut out = Vec::new();
    for (i, rec) in rdr.records().enumerate() {
        let row = i + 1;
        let rec = rec.with_context(|| format!("{}: row {row}: malformed CSV", path.display()))?;
        let num = |c: usize, name: &str| -> Result<f64> {
            let s = rec.get(c).unwrap_or("");
            let v: f64 = s.parse().map_err(|_| {
                anyhow::anyhow!(
                    "{}: row {row}: column {name}: '{s}' is not a number",
                    path.display()
                )
            })?;
            if !v.is_finite() {
                bail!(
                    "{}: row {row}: column {name}: {v} is not finite",
                    path.display()
                );
            }
            Ok(v)
        };
        let p = DVec3::new(num(x, "x")?, num(y, "y")?, num(z, "z")?);
        let n = match normal_cols {
            Some((a, b, c)) => {
                let n = DVec3::new(num(a, "nx")?, num(b, "ny")?, num(c, "nz")?);
                if n.length_squared() == 0.0 {
                    bail!(
                        "{}: row {row}: the normal (nx,ny,nz) is zero",
                        path.display()
                    );
                }
                Some(n.normalize())
            }
            None => None,
        };
        out.push((p, n));
    }
    Ok(out)
}

/// Matches each point to its face through the scene's BVH ([`Accel::nearest_faces`]: O(log n) per point).
/// `file` names the input for errors.
pub fn match_points(
    scene: &Scene,
    accel: &Accel,
    points: &[(DVec3, Option<DVec3>)],
    file: &str,
) -> Result<Vec<ProbePoint>> {
    let max_d = MAX_DISTANCE_REL * scene.diagonal();
    points
        .par_iter()
        .enumerate()
        .map(|(i, &(p, n))| {
            let near = accel.nearest_faces(p, 1e-9 * scene.diagonal());
            let best = near.as_ref().map_or(f64::INFINITY, |n| n.0);
            let Some((_, candidates)) = near.filter(|_| best <= max_d) else {
                bail!(
                    "{file}: row {}: point ({}, {}, {}) is {best:.3e} from the nearest surface (limit {max_d:.3e}, \
                     {MAX_DISTANCE_REL} of the scene's diagonal); probe points must lie on surfaces",
                    i + 1,
                    p.x,
                    p.y,
                    p.z
                );
            };
            let face = candidates
                .iter()
                .copied()
                .max_by(|&a, &b| {
                    let score = |f: usize| n.map_or(0.0, |n| scene.faces[f].normal.dot(n));
                    score(a).total_cmp(&score(b)).then(b.cmp(&a))
                })
                .unwrap_or(0);
            let nf = scene.faces[face].normal;
            let point = p - (p - scene.faces[face].centroid).dot(nf) * nf;
            Ok(ProbePoint { input: p, face, point })
        })
        .collect()
}

//! Evaluation points: deterministic, area-stratified points over every non-emitting face (over every face when
//! all of them emit, as in a furnace), the same for every method and the reference (README.md,
//! "Conventions that make comparisons fair"). Emitters are left out otherwise because their radiosity is
//! dominated by their own emission, which every method gets exactly right.
//!
//! Faces are laid end to end by area into [0, A_total); point i is placed at (i + ξ_i)/N · A_total in that
//! line (stratified sampling of the area measure), which picks its face, and the remainder of the position
//! within the face's share picks the first coordinate of a uniform sample on the face (the second is ξ'_i).
//! Each point represents area A_total / N, so area-weighted means over the points are plain means.

use glam::DVec3;

use radlab_scene::{FaceId, Scene, sampling};

/// A point at which solutions and the reference are compared.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EvalPoint {
    /// The face it lies on.
    pub face: FaceId,
    /// Position.
    pub point: DVec3,
    /// The face's unit normal.
    pub normal: DVec3,
    /// Area it represents (A_total / N).
    pub weight: f64,
}

/// `count` evaluation points over the non-emitting faces (all faces if every face emits), from `seed`.
pub fn evaluation_points(scene: &Scene, count: usize, seed: u64) -> Vec<EvalPoint> {
    let mut faces: Vec<FaceId> = (0..scene.faces.len())
        .filter(|&f| !scene.material(f).is_emitter())
        .collect();
    if faces.is_empty() {
        faces = (0..scene.faces.len()).collect();
    }
    let mut cum = Vec::with_capacity(faces.len() + 1);
    let mut total = 0.0;
    cum.push(0.0);
    for &f in &faces {
        total += scene.faces[f].area;
        cum.push(total);
    }
    if faces.is_empty() || count == 0 || !(total > 0.0) {
        return Vec::new();
    }
    let weight = total / count as f64;
    (0..count)
        .map(|i| {
            let mut r = sampling::rng(seed, i as u64);
            let a = (i as f64 + sampling::uniform(&mut r)) * weight;
            let k = cum.partition_point(|&c| c <= a).clamp(1, faces.len()) - 1;
            let f = faces[k];
            let u1 = ((a - cum[k]) / (cum[k + 1] - cum[k])).clamp(0.0, 1.0 - f64::EPSILON);
            let u2 = sampling::uniform(&mut r);
            EvalPoint {
                face: f,
                point: scene.polygon(f).sample_uniform(u1, u2),
                normal: scene.faces[f].normal,
                weight,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_cover_non_emitters_by_area_and_furnaces_entirely() {
        let s = radlab_scene::builtin("parallel-squares?tessellation=3").expect("scene");
        let pts = evaluation_points(&s, 900, 5);
        assert_eq!(pts.len(), 900);
        assert!(pts.iter().all(|p| !s.material(p.face).is_emitter()));
        // Stratified by area: each of the 9 equal receiver faces gets 100 points exactly.
        for f in 0..s.faces.len() {
            let n = pts.iter().filter(|p| p.face == f).count();
            assert!(n == 0 || n == 100, "face {f}: {n}");
        }
        assert!((pts.iter().map(|p| p.weight).sum::<f64>() - 1.0).abs() < 1e-12);
        let furnace = radlab_scene::builtin("furnace-cube?tessellation=2").expect("furnace");
        let pts = evaluation_points(&furnace, 240, 5);
        assert_eq!(pts.len(), 240);
        assert!(
            pts.iter()
                .all(|p| furnace.polygon(p.face).contains(p.point, 1e-9))
        );
        assert_eq!(evaluation_points(&furnace, 240, 5), pts, "deterministic");
    }
}

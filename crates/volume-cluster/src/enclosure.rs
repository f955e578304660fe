//! Which input faces light can reach at all. Light moves between two faces only along a segment between them,
//! so a face can receive light only if it lies in the same connected region of free space (an "enclosure") as
//! some emitter: a closed box's inner faces, sealed from every emitter, stay exactly dark (B = 0) at every
//! order of reflection. A cluster link cannot express this by itself: its one visibility fraction V and its
//! source flux J are means over the two ends, so V · J is non-zero whenever a source cluster holds both faces
//! the receiver sees (a sealed interior's own dark faces) and lit faces it cannot see (the walls behind the
//! box), and the product carries light through the wall (Sillion & Drettakis 1995 discuss the same product
//! error for shadows inside clusters).
//!
//! The regions are found as the connected components of the graph "face f's ray hits face g": from each face,
//! [`RAYS_PER_FACE`] cosine-distributed rays from area-uniform points; a ray that leaves the scene joins the
//! face to the outside. Faces whose component holds no emitter are unreachable, and the transport gives them
//! no irradiance. A ray only ever joins faces that see each other (hits on a face's back included, which errs
//! towards reachability), so a sealed interior is never joined to a lit region; the error it can make is to
//! split a region whose parts happen to exchange no ray, which needs a pocket of faces whose 16 rays each
//! all stay inside it — a cavity that is nearly closed, whose light the links would carry only through its
//! opening. Cost: 16 k rays once, O(k log k).
//!
//! The same rays say whether the scene is closed: if every ray from every face hits the front of a face,
//! the exact form factors from every point sum to one (the summation relation of an enclosure; Goral,
//! Torrance, Greenberg & Battaile 1984), and the solver may rescale its discrete rows to that sum
//! ([`crate::RowNormalisation`]). An opening of cosine-weighted solid-angle fraction p seen by the faces
//! escapes detection with probability about (1 − p)^(16 k); an undetected one is so small that rescaling
//! its rows to one errs by about p.

use radlab_scene::{FaceId, Scene, sampling};
use radlab_visibility::Accel;
use rayon::prelude::*;

/// Rays cast from each face to find its region.
pub const RAYS_PER_FACE: usize = 16;

/// What the enclosure rays found.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Enclosures {
    /// Per face (by id): whether it shares a region of free space with an emitter.
    pub reachable: Vec<bool>,
    /// Whether every ray from every face hit the front of a face: the scene is closed.
    pub closed: bool,
}

/// Whether each face (by id) shares a region of free space with an emitter; rays from `seed`.
pub fn reachable_faces(scene: &Scene, accel: &Accel, seed: u64) -> Vec<bool> {
    enclosures(scene, accel, seed).reachable
}

/// Which faces light can reach, and whether the scene is closed; rays from `seed`.
pub fn enclosures(scene: &Scene, accel: &Accel, seed: u64) -> Enclosures {
    let k = scene.face_count();
    let outside = k as u32;
    let hits: Vec<([u32; RAYS_PER_FACE], bool)> = (0..k)
        .into_par_iter()
        .map(|f| {
            let mut rng = sampling::rng(seed, sampling::mix64(0xE7C1_0005_0000_0000 ^ f as u64));
            let poly = scene.polygon(f);
            let n = scene.faces[f].normal;
            let mut out = [outside; RAYS_PER_FACE];
            let mut all_front = true;
            for o in &mut out {
                let (u1, u2) = (sampling::uniform(&mut rng), sampling::uniform(&mut rng));
                let (u3, u4) = (sampling::uniform(&mut rng), sampling::uniform(&mut rng));
                let p = poly.sample_uniform(u1, u2);
                let d = sampling::cosine_hemisphere(n, u3, u4);
                match accel.intersect_from(f, p, d) {
                    Some(h) => {
                        *o = h.face as u32;
                        all_front &= scene.faces[h.face].normal.dot(d) < 0.0;
                    }
                    None => all_front = false,
                }
            }
            (out, all_front)
        })
        .collect();
    // Union-find over faces and the outside, joined in face order (deterministic).
    let mut parent: Vec<u32> = (0..=outside).collect();
    fn find(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            let up = parent[parent[x as usize] as usize];
            parent[x as usize] = up;
            x = up;
        }
        x
    }
    let closed = hits.iter().all(|h| h.1);
    for (f, (hs, _)) in hits.iter().enumerate() {
        for &g in hs {
            let (a, b) = (find(&mut parent, f as u32), find(&mut parent, g));
            if a != b {
                parent[a.max(b) as usize] = a.min(b);
            }
        }
    }
    let mut lit = vec![false; k + 1];
    for f in 0..k {
        if scene.emission(f).max_element() > 0.0 {
            let r = find(&mut parent, f as u32);
            lit[r as usize] = true;
        }
    }
    let reachable = (0..k)
        .map(|f: FaceId| {
            let r = find(&mut parent, f as u32);
            lit[r as usize]
        })
        .collect();
    Enclosures { reachable, closed }
}

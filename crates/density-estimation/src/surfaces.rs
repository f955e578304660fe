//! The surfaces density estimation works on (Shirley, Wade, Hubbard, Zareski, Walter & Greenberg 1995, §3:
//! one hit-point list and one density estimate per surface): groups of faces, each with its own 2-D
//! coordinates, in which the kernel estimate is taken.
//!
//! A surface is grown from the lowest-numbered face not yet taken over its edge neighbours (edges matched by
//! position, vertices within 1e-9 of the scene diagonal being one) of the same material whose normal lies
//! within `group_angle` of the seed face's normal n_s. A flat scene polygon cut into quads or a fan (the
//! builtins' grids, a floor and a sliver beside it) is one surface; faces at a crease of more than the angle,
//! or of another material, or touching only at a vertex, are not joined (so a box standing on a floor keeps
//! its own surfaces, and a closed interior never reads particles from outside). On a detailed mesh (a scanned
//! surface, each triangle too small to hold particles) a surface is a patch of faces within the normal cone:
//! the simple region grouping, chosen over the face-cluster hierarchy because it needs no hierarchy build,
//! gives planar surfaces back exactly, and bounds the tilt that projection to the seed's plane distorts.
//!
//! Coordinates: points are projected to the plane through the seed's centroid with normal n_s, along n_s.
//! A face with normal n_f shrinks by c_f = n_f·n_s ≥ cos(group_angle) > 0 under the projection (no face is
//! flipped), so power Φ landing on it with irradiance H per true area is a density H per projected area once
//! each particle is weighted by c_f: E Σ Φ_i c_i g(P X_i) = ∫ g(P x) H(x) c(x) dA = ∫ g(y) H dA_P. The
//! estimate in the plane is H itself, continuous across the creases inside the surface. (Faces that overlap
//! in projection, a mesh folding back within the cone, are not detected.)

use std::collections::HashMap;

use glam::{DVec2, DVec3};
use radlab_scene::{FaceId, Scene, sampling};

use crate::local_linear::Domain;

/// One surface: its faces, projection frame and domain.
#[derive(Clone, Debug)]
pub struct Surface {
    /// Its faces, in increasing order.
    pub faces: Vec<FaceId>,
    /// The seed face's normal n_s (the projection direction).
    pub normal: DVec3,
    origin: DVec3,
    axes: (DVec3, DVec3),
    /// The faces projected to the surface's plane, and its boundary.
    pub domain: Domain,
}

impl Surface {
    /// `p` in the surface's 2-D coordinates.
    pub fn project(&self, p: DVec3) -> DVec2 {
        let d = p - self.origin;
        DVec2::new(d.dot(self.axes.0), d.dot(self.axes.1))
    }
}

/// The scene's faces grouped into surfaces.
#[derive(Clone, Debug)]
pub struct Surfaces {
    /// Every surface.
    pub surfaces: Vec<Surface>,
    /// The surface of each face.
    pub of_face: Vec<u32>,
}

type Key = (i64, i64, i64);

impl Surfaces {
    /// Groups `scene`'s faces: edge-connected, same material, normals within the angle whose cosine is
    /// `cos_angle` of the seed's.
    pub fn new(scene: &Scene, cos_angle: f64) -> Self {
        let q = 1e-9 * scene.diagonal();
        let key = |p: DVec3| -> Key {
            (
                (p.x / q).round() as i64,
                (p.y / q).round() as i64,
                (p.z / q).round() as i64,
            )
        };
        let edge_key = |a: Key, b: Key| if a < b { (a, b) } else { (b, a) };
        let n = scene.face_count();
        let mut edges: HashMap<(Key, Key), Vec<u32>> = HashMap::new();
        for f in 0..n {
            let poly = scene.polygon(f);
            let v = poly.vertices();
            for k in 0..v.len() {
                let e = edge_key(key(v[k]), key(v[(k + 1) % v.len()]));
                edges.entry(e).or_default().push(f as u32);
            }
        }
        // Neighbours of each face over shared edges, sorted (deterministic order).
        let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); n];
        for faces in edges.values() {
            for &a in faces {
                for &b in faces {
                    if a != b {
                        neighbours[a as usize].push(b);
                    }
                }
            }
        }
        for l in &mut neighbours {
            l.sort_unstable();
            l.dedup();
        }
        let mut of_face = vec![u32::MAX; n];
        let mut surfaces = Vec::new();
        for seed in 0..n {
            if of_face[seed] != u32::MAX {
                continue;
            }
            let id = surfaces.len() as u32;
            let ns = scene.faces[seed].normal;
            let material = scene.faces[seed].material;
            let mut faces = vec![seed];
            of_face[seed] = id;
            let mut next = 0;
            while next < faces.len() {
                let f = faces[next];
                next += 1;
                for &g in &neighbours[f] {
                    let g = g as usize;
                    if of_face[g] == u32::MAX
                        && scene.faces[g].material == material
                        && scene.faces[g].normal.dot(ns) >= cos_angle
                    {
                        of_face[g] = id;
                        faces.push(g);
                    }
                }
            }
            faces.sort_unstable();
            surfaces.push(Self::surface(scene, faces, ns, seed, &key));
        }
        Self { surfaces, of_face }
    }

    fn surface(
        scene: &Scene,
        faces: Vec<FaceId>,
        normal: DVec3,
        seed: FaceId,
        key: &impl Fn(DVec3) -> Key,
    ) -> Surface {
        let origin = scene.faces[seed].centroid;
        let axes = sampling::basis(normal);
        let project = |p: DVec3| {
            let d = p - origin;
            DVec2::new(d.dot(axes.0), d.dot(axes.1))
        };
        let mut polygons = Vec::with_capacity(faces.len());
        let mut uses: HashMap<(Key, Key), (u32, [DVec2; 2])> = HashMap::new();
        let mut order = Vec::new();
        for &f in &faces {
            let poly = scene.polygon(f);
            let v = poly.vertices();
            polygons.push(v.iter().map(|&p| project(p)).collect());
            for k in 0..v.len() {
                let (a, b) = (v[k], v[(k + 1) % v.len()]);
                let (ka, kb) = (key(a), key(b));
                let e = if ka < kb { (ka, kb) } else { (kb, ka) };
                let entry = uses.entry(e).or_insert_with(|| {
                    order.push(e);
                    (0, [project(a), project(b)])
                });
                entry.0 += 1;
            }
        }
        let boundary = order
            .iter()
            .filter_map(|e| {
                let (count, seg) = uses[e];
                (count == 1).then_some(seg)
            })
            .collect();
        Surface {
            faces,
            normal,
            origin,
            axes,
            domain: Domain::new(polygons, boundary),
        }
    }

    /// Approximate heap bytes held.
    pub fn bytes(&self) -> usize {
        self.of_face.capacity() * 4
            + self
                .surfaces
                .iter()
                .map(|s| size_of::<Surface>() + s.faces.capacity() * 8 + s.domain.bytes())
                .sum::<usize>()
    }
}

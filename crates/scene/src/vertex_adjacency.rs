//! Vertex adjacency of a scene's faces: for every vertex index, the faces that have it as a corner (its
//! one-ring of faces), in increasing face order. Connectivity is by vertex index, as for
//! [`crate::EdgeAdjacency`]. Built by counting then filling (a compressed sparse row layout): O(k) for k
//! faces, deterministic.

use crate::{FaceId, Scene};

/// The faces around every vertex of a scene.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct VertexAdjacency {
    /// Faces around vertex v are `faces[starts[v]..starts[v + 1]]`.
    starts: Vec<u32>,
    faces: Vec<u32>,
}

impl VertexAdjacency {
    /// The adjacency of `scene`'s faces.
    pub fn new(scene: &Scene) -> Self {
        let mut starts = vec![0u32; scene.vertices.len() + 1];
        for face in &scene.faces {
            for &v in face.vertex_indices() {
                starts[v as usize + 1] += 1;
            }
        }
        for v in 0..scene.vertices.len() {
            starts[v + 1] += starts[v];
        }
        let mut next = starts.clone();
        let mut faces = vec![0u32; starts[scene.vertices.len()] as usize];
        for (f, face) in scene.faces.iter().enumerate() {
            for &v in face.vertex_indices() {
                let slot = &mut next[v as usize];
                faces[*slot as usize] = f as u32;
                *slot += 1;
            }
        }
        Self { starts, faces }
    }

    /// The faces having vertex `v` as a corner, in increasing order (empty for an unused vertex).
    pub fn faces_around(&self, v: u32) -> impl Iterator<Item = FaceId> + '_ {
        let (a, b) = (self.starts[v as usize], self.starts[v as usize + 1]);
        self.faces[a as usize..b as usize]
            .iter()
            .map(|&f| f as FaceId)
    }

    /// Approximate heap bytes held.
    pub fn bytes(&self) -> usize {
        (self.starts.len() + self.faces.len()) * 4
    }
}

#[cfg(test)]
mod tests {
    use glam::dvec3;

    use crate::{Material, Rgb, SceneBuilder};

    use super::VertexAdjacency;

    /// Two triangles sharing an edge and a third face elsewhere: the shared vertices have both triangles,
    /// the others one face each, and an unused vertex none.
    #[test]
    fn faces_around_each_vertex() {
        let mut b = SceneBuilder::new("fan");
        let m = b
            .add_material(Material::new("m", Rgb::splat(0.5), Rgb::ZERO).expect("valid"))
            .expect("valid");
        for p in [
            dvec3(0.0, 0.0, 0.0),
            dvec3(1.0, 0.0, 0.0),
            dvec3(1.0, 1.0, 0.0),
            dvec3(0.0, 1.0, 0.0),
            dvec3(5.0, 5.0, 5.0),
            dvec3(3.0, 0.0, 0.0),
            dvec3(4.0, 0.0, 0.0),
            dvec3(3.0, 1.0, 0.0),
        ] {
            b.add_vertex(p, "fan").expect("finite");
        }
        b.add_polygon(&[0, 1, 2], m, "fan").expect("valid");
        b.add_polygon(&[0, 2, 3], m, "fan").expect("valid");
        b.add_polygon(&[5, 6, 7], m, "fan").expect("valid");
        let scene = b.build().expect("scene");
        let a = VertexAdjacency::new(&scene);
        let around = |v| a.faces_around(v).collect::<Vec<_>>();
        assert_eq!(around(0), vec![0, 1]);
        assert_eq!(around(2), vec![0, 1]);
        assert_eq!(around(1), vec![0]);
        assert_eq!(around(3), vec![1]);
        assert_eq!(around(4), Vec::<usize>::new());
        assert_eq!(around(6), vec![2]);
    }
}

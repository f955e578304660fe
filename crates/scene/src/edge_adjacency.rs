//! Edge adjacency of a scene's faces: every mesh edge (an unordered pair of vertex indices that some face
//! walks between consecutively) with the faces that use it.
//!
//! Connectivity is by vertex index, so it is exactly what the input shares: the OBJ reader welds equal
//! positions (see [`crate::io::obj_mtl`]) and the builtin generators share their lattice vertices. An edge
//! used by one face is a boundary edge, by two a manifold edge, by three or more a non-manifold edge; the
//! manifold edges are the edges of the dual graph that face clustering contracts (Garland, Willmott &
//! Heckbert 2001, section 3). Built by sorting the 3k–4k half-edges of k faces: O(k log k), deterministic
//! for any thread count (the sort keys are distinct).

use rayon::prelude::*;

use crate::{FaceId, Scene};

/// One mesh edge and the faces that use it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MeshEdge<'a> {
    /// The two vertex indices, smaller first.
    pub vertices: [u32; 2],
    /// The faces that walk along this edge, in increasing order (each once).
    pub faces: &'a [u32],
}

impl MeshEdge<'_> {
    /// Whether exactly two faces share the edge (an edge of the dual graph).
    pub fn is_manifold(&self) -> bool {
        self.faces.len() == 2
    }
}

/// Every edge of a scene's faces with its faces, in increasing order of (smaller vertex, larger vertex).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct EdgeAdjacency {
    vertices: Vec<[u32; 2]>,
    /// Faces of edge e are `faces[starts[e]..starts[e + 1]]`.
    starts: Vec<u32>,
    faces: Vec<u32>,
}

impl EdgeAdjacency {
    /// The edge adjacency of the scene's faces.
    pub fn new(scene: &Scene) -> Self {
        let mut half: Vec<(u64, u32)> = Vec::with_capacity(4 * scene.faces.len());
        for (f, face) in scene.faces.iter().enumerate() {
            let idx = face.vertex_indices();
            for k in 0..idx.len() {
                let (a, b) = (idx[k], idx[(k + 1) % idx.len()]);
                if a != b {
                    let (lo, hi) = (a.min(b), a.max(b));
                    half.push((((lo as u64) << 32) | hi as u64, f as u32));
                }
            }
        }
        half.par_sort_unstable();
        half.dedup();
        let mut adj = Self {
            vertices: Vec::new(),
            starts: Vec::new(),
            faces: Vec::with_capacity(half.len()),
        };
        let mut last = u64::MAX;
        for &(key, f) in &half {
            if key != last {
                adj.vertices.push([(key >> 32) as u32, key as u32]);
                adj.starts.push(adj.faces.len() as u32);
                last = key;
            }
            adj.faces.push(f);
        }
        adj.starts.push(adj.faces.len() as u32);
        adj
    }

    /// Number of distinct edges.
    pub fn edge_count(&self) -> usize {
        self.vertices.len()
    }

    /// Edge `e` (0 ≤ e < [`EdgeAdjacency::edge_count`]).
    pub fn edge(&self, e: usize) -> MeshEdge<'_> {
        MeshEdge {
            vertices: self.vertices[e],
            faces: &self.faces[self.starts[e] as usize..self.starts[e + 1] as usize],
        }
    }

    /// All edges, in order.
    pub fn edges(&self) -> impl Iterator<Item = MeshEdge<'_>> + '_ {
        (0..self.edge_count()).map(|e| self.edge(e))
    }

    /// The edges shared by exactly two faces, as (edge, first face, second face): the dual graph's edges.
    pub fn manifold_pairs(&self) -> impl Iterator<Item = (usize, FaceId, FaceId)> + '_ {
        self.edges()
            .enumerate()
            .filter_map(|(e, m)| match *m.faces {
                [a, b] => Some((e, a as FaceId, b as FaceId)),
                _ => None,
            })
    }

    /// Number of edges used by one face only.
    pub fn boundary_edge_count(&self) -> usize {
        self.edges().filter(|m| m.faces.len() == 1).count()
    }

    /// Number of edges used by three or more faces.
    pub fn non_manifold_edge_count(&self) -> usize {
        self.edges().filter(|m| m.faces.len() > 2).count()
    }

    /// Approximate heap bytes held.
    pub fn bytes(&self) -> usize {
        self.vertices.len() * size_of::<[u32; 2]>() + (self.starts.len() + self.faces.len()) * 4
    }
}

impl Scene {
    /// The edge adjacency of the scene's faces (see [`EdgeAdjacency`]); O(k log k) for k faces.
    pub fn edge_adjacency(&self) -> EdgeAdjacency {
        EdgeAdjacency::new(self)
    }
}

#[cfg(test)]
mod tests {
    use glam::dvec3;

    use crate::{Material, SceneBuilder};

    #[test]
    fn two_triangles_of_a_quad_share_one_edge() {
        let mut b = SceneBuilder::new("quad");
        let m = Material::new("m", glam::DVec3::splat(0.5), glam::DVec3::ZERO).expect("valid");
        let m = b.add_material(m).expect("valid");
        for p in [
            dvec3(0.0, 0.0, 0.0),
            dvec3(1.0, 0.0, 0.0),
            dvec3(1.0, 1.0, 0.0),
            dvec3(0.0, 1.0, 0.0),
        ] {
            b.add_vertex(p, "t").expect("finite");
        }
        b.add_polygon(&[0, 1, 2], m, "t").expect("valid");
        b.add_polygon(&[0, 2, 3], m, "t").expect("valid");
        let adj = b.build().expect("faces").edge_adjacency();
        assert_eq!(adj.edge_count(), 5);
        assert_eq!(adj.boundary_edge_count(), 4);
        assert_eq!(adj.non_manifold_edge_count(), 0);
        let pairs: Vec<_> = adj.manifold_pairs().collect();
        assert_eq!(pairs.len(), 1);
        let (e, f, g) = pairs[0];
        assert_eq!((f, g), (0, 1));
        assert_eq!(adj.edge(e).vertices, [0, 2]);
    }
}

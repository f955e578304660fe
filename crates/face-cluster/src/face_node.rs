//! The node kind of face cluster radiosity (Willmott, Heckbert & Garland 1999): a node of the face-cluster
//! tree ([`crate::tree`]) or, below a tree leaf (one input face), a quadtree patch of that face (Hanrahan,
//! Salzman & Aupperle 1991), so the hierarchical engine's patch links, quadtree and output work below the
//! faces. A cluster splits into its tree children; a tree leaf splits into the patch of its face, the only
//! place the solve reads an input face (counted by [`FaceContext::face_reads`]).
//!
//! What a cluster shows the refinement comes from the tree's per-node data and from sums made once when the
//! solver is built (O(k), like the tree): the area-weighted centroid c = Σ A_i c_i / A (where the point
//! approximation places the node), Σ ρ_i A_i n_i and Σ ρ_i A_i, Σ E_i A_i per channel, so that a node's
//! area-mean radiosity under irradiance vector e, B̄ = (Σ A_i E_i + (Σ ρ_i A_i n_i)·e)/A, needs no face.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use glam::DVec3;
use radlab_hierarchical::{Bound, NodeKind, Patch};
use radlab_scene::{FaceId, Rgb, Scene, sampling};

use crate::FaceClusterTree;
use crate::bounds::NormalCone;

/// Per-node sums the vector solve needs besides the tree's own data, and the face-read counter.
#[derive(Debug)]
pub struct FaceContext<'a> {
    /// The hierarchy.
    pub tree: FaceClusterTree,
    /// The scene its faces come from.
    pub scene: &'a Scene,
    /// Per tree node: area-weighted centroid Σ A_i c_i / A.
    pub centroid: Vec<DVec3>,
    /// Per tree node and channel: Σ ρ_i A_i n_i.
    pub rho_vector: Vec<[DVec3; 3]>,
    /// Per tree node: Σ ρ_i A_i (per channel).
    pub rho_area: Vec<Rgb>,
    /// Per tree node: Σ E_i A_i (per channel).
    pub emitted: Vec<Rgb>,
    face_reads: AtomicU64,
}

impl<'a> FaceContext<'a> {
    /// The sums of every node of `tree` over `scene`'s faces: one pass over the faces (at the leaves) and one
    /// over the nodes, children before parents.
    pub fn new(tree: FaceClusterTree, scene: &'a Scene) -> Self {
        let n = tree.nodes().len();
        let mut centroid = vec![DVec3::ZERO; n];
        let mut rho_vector = vec![[DVec3::ZERO; 3]; n];
        let mut rho_area = vec![Rgb::ZERO; n];
        let mut emitted = vec![Rgb::ZERO; n];
        // Children follow parents (breadth-first), so a reverse walk sums children first.
        for i in (0..n).rev() {
            let node = tree.node(i);
            if node.is_leaf() {
                let f = tree.faces_of(i)[0] as usize;
                let face = &scene.faces[f];
                let (rho, e) = (scene.reflectance(f), scene.emission(f));
                centroid[i] = face.centroid * face.area;
                rho_vector[i] = std::array::from_fn(|c| face.normal * (rho[c] * face.area));
                rho_area[i] = rho * face.area;
                emitted[i] = e * face.area;
            } else {
                for c in node.children() {
                    let (ci, rv, ra, em) = (centroid[c], rho_vector[c], rho_area[c], emitted[c]);
                    centroid[i] += ci;
                    for k in 0..3 {
                        rho_vector[i][k] += rv[k];
                    }
                    rho_area[i] += ra;
                    emitted[i] += em;
                }
            }
        }
        // Sums of A_i c_i to centroids, after every parent has read its children's sums.
        for (c, node) in centroid.iter_mut().zip(tree.nodes()) {
            if node.area > 0.0 {
                *c /= node.area;
            } else {
                *c = node.sphere.centre;
            }
        }
        Self {
            tree,
            scene,
            centroid,
            rho_vector,
            rho_area,
            emitted,
            face_reads: AtomicU64::new(0),
        }
    }

    /// How many input faces the solve has read since the context was made (each tree leaf the refinement
    /// splits into its face's patch reads that face once).
    pub fn face_reads(&self) -> u64 {
        self.face_reads.load(Ordering::Relaxed)
    }

    /// Approximate heap bytes held (the tree included).
    pub fn bytes(&self) -> usize {
        self.tree.bytes()
            + self.centroid.len()
                * (size_of::<DVec3>() + size_of::<[DVec3; 3]>() + 2 * size_of::<Rgb>())
    }
}

/// A node of the simulation hierarchy: a face cluster, or a patch of one input face.
#[derive(Clone, Debug)]
#[allow(clippy::large_enum_variant)]
pub enum FaceNode<'a> {
    /// A node of the face-cluster tree.
    Cluster(ClusterRef<'a>),
    /// An input face (below its tree leaf) or a piece of one.
    Patch(Patch),
}

/// A node of a shared face-cluster tree.
#[derive(Clone, Debug)]
pub struct ClusterRef<'a> {
    /// The tree and its sums.
    pub ctx: Arc<FaceContext<'a>>,
    /// Node index in the tree.
    pub id: u32,
}

impl ClusterRef<'_> {
    /// The tree node.
    pub fn node(&self) -> &crate::Node {
        self.ctx.tree.node(self.id as usize)
    }
}

impl FaceNode<'_> {
    /// Where the point approximation places the node: its area-weighted centroid.
    pub fn centroid(&self) -> DVec3 {
        match self {
            Self::Cluster(c) => c.ctx.centroid[c.id as usize],
            Self::Patch(p) => p.centroid,
        }
    }

    /// A cone holding every face normal.
    pub fn cone(&self) -> NormalCone {
        match self {
            Self::Cluster(c) => c.node().cone,
            Self::Patch(p) => NormalCone::of_normal(p.normal),
        }
    }

    /// Whether part of the node can see another part: a cluster whose two children each have the other's
    /// centroid strictly in front of their vector area's plane (concave). Single faces and patches cannot.
    pub fn sees_itself(&self) -> bool {
        let Self::Cluster(c) = self else {
            return false;
        };
        let kids = c.node().children();
        if kids.len() != 2 {
            return false;
        }
        let (a, b) = (kids.start, kids.start + 1);
        let tree = &c.ctx.tree;
        let (ca, cb) = (c.ctx.centroid[a], c.ctx.centroid[b]);
        let (na, nb) = (tree.node(a).vector_area, tree.node(b).vector_area);
        let tol = 1e-9 * (ca - cb).length() * (na.length() + nb.length());
        na.dot(cb - ca) > tol && nb.dot(ca - cb) > tol
    }

    /// The patch, if it is one.
    pub fn as_patch(&self) -> Option<&Patch> {
        match self {
            Self::Patch(p) => Some(p),
            Self::Cluster(_) => None,
        }
    }

    /// Points on the node's surfaces for visibility rays: the tree's sample points of a cluster, four
    /// stratified points of a patch.
    pub fn sample_points(&self) -> Vec<DVec3> {
        match self {
            Self::Cluster(c) => c.ctx.tree.samples(c.id as usize).to_vec(),
            Self::Patch(p) => [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)]
                .iter()
                .map(|&(s, t)| p.polygon.point_at(s, t))
                .collect(),
        }
    }
}

impl NodeKind for FaceNode<'_> {
    fn area(&self) -> f64 {
        match self {
            Self::Cluster(c) => c.node().area,
            Self::Patch(p) => p.area,
        }
    }

    fn bound(&self) -> Bound {
        match self {
            Self::Cluster(c) => {
                let s = c.node().sphere;
                Bound {
                    centre: s.centre,
                    radius: s.radius,
                }
            }
            Self::Patch(p) => p.bound(),
        }
    }

    fn normal(&self) -> Option<DVec3> {
        self.as_patch().map(|p| p.normal)
    }

    fn projected_area(&self, dir: DVec3) -> f64 {
        match self {
            Self::Cluster(c) => {
                let n = c.node();
                n.obb.projected_area(dir).min(n.area)
            }
            Self::Patch(p) => p.projected_area(dir),
        }
    }

    fn reflectance(&self) -> Rgb {
        match self {
            Self::Cluster(c) => {
                let a = c.node().area;
                if a > 0.0 {
                    c.ctx.rho_area[c.id as usize] / a
                } else {
                    Rgb::ZERO
                }
            }
            Self::Patch(p) => p.reflectance,
        }
    }

    fn emission(&self) -> Rgb {
        match self {
            Self::Cluster(c) => {
                let a = c.node().area;
                if a > 0.0 {
                    c.ctx.emitted[c.id as usize] / a
                } else {
                    Rgb::ZERO
                }
            }
            Self::Patch(p) => p.emission,
        }
    }

    fn can_split(&self, min_size: f64) -> bool {
        match self {
            Self::Cluster(_) => true,
            Self::Patch(p) => p.can_split(min_size),
        }
    }

    fn split(&self) -> Vec<Self> {
        match self {
            Self::Cluster(c) => {
                let node = c.node();
                if node.is_leaf() {
                    c.ctx.face_reads.fetch_add(1, Ordering::Relaxed);
                    let f = c.ctx.tree.faces_of(c.id as usize)[0] as FaceId;
                    vec![Self::Patch(Patch::root(c.ctx.scene, f))]
                } else {
                    node.children()
                        .map(|id| {
                            Self::Cluster(ClusterRef {
                                ctx: Arc::clone(&c.ctx),
                                id: id as u32,
                            })
                        })
                        .collect()
                }
            }
            Self::Patch(p) => p.split().into_iter().map(Self::Patch).collect(),
        }
    }

    fn face(&self) -> Option<FaceId> {
        self.as_patch().map(|p| p.face)
    }

    fn key(&self) -> u64 {
        match self {
            Self::Cluster(c) => sampling::mix64(0xFACE_C1A5_0000_0000 ^ u64::from(c.id)),
            Self::Patch(p) => p.key(),
        }
    }

    fn patch(&self) -> Option<&Patch> {
        self.as_patch()
    }

    fn sends_own_emission(&self) -> bool {
        // A power vector p = p_E + M e carries its faces' emission.
        true
    }
}

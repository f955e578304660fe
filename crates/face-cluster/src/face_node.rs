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
//!
//! Above the tree's roots (one per dual-connected part) sits a volume hierarchy, Christensen et al.'s (1997)
//! loose octree over the roots' boxes ([`FaceNode::Volume`]): a volume splits into its child volumes and its
//! direct roots, so a scene of many separate parts starts from one self-link instead of (roots)² links. A
//! volume is a closed group of surfaces (Σ A_i n_i ≈ 0), so it is not a vector node: it shows the refinement
//! and its links the isotropic cluster of Sillion (1995), projected area A/4 toward every direction.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use glam::DVec3;
use radlab_hierarchical::{Bound, NodeKind, Patch};
use radlab_scene::{FaceId, Rgb, Scene, sampling};
use radlab_volume_cluster::{ClusterTree, OctreeItem};

use crate::FaceClusterTree;
use crate::bounds::NormalCone;

/// Sample points per volume for visibility rays (one on each of as many roots, chosen in proportion to area).
const VOLUME_SAMPLES: usize = 4;

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
    /// Per tree node: the light it sends onto itself and between its children, traced before the solve
    /// (empty until [`crate::SelfExchange::trace`] fills it: then every factor reads 0).
    pub exchange: crate::SelfExchange,
    /// The loose octree over the tree's roots (its "faces" are root indices).
    pub volumes: ClusterTree,
    /// Per volume: visibility sample points (on the roots below it).
    pub volume_samples: Vec<Vec<DVec3>>,
    /// (first position in the tree's face order, root), sorted: which root holds a face.
    root_starts: Vec<(u32, u32)>,
    /// Per root: its position in the volumes' order (a volume holds the roots at its range of positions).
    root_slot: Vec<u32>,
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
        let items: Vec<OctreeItem> = tree
            .roots()
            .map(|r| {
                let node = tree.node(r);
                let (lo, hi) = node
                    .obb
                    .corners()
                    .iter()
                    .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), c| {
                        (lo.min(*c), hi.max(*c))
                    });
                let a = node.area;
                let (reflectance, emission) = if a > 0.0 {
                    (rho_area[r] / a, emitted[r] / a)
                } else {
                    (Rgb::ZERO, Rgb::ZERO)
                };
                OctreeItem {
                    lo,
                    hi,
                    area: a,
                    centroid: centroid[r],
                    reflectance,
                    emission,
                }
            })
            .collect();
        let volumes = ClusterTree::build_over_items(&items, (0..items.len()).collect());
        let volume_samples = (0..volumes.clusters.len() as u32)
            .map(|v| {
                (0..VOLUME_SAMPLES)
                    .map(|j| {
                        let u = (j as f64 + 0.5) / VOLUME_SAMPLES as f64;
                        let r = volumes.face_at(v, u);
                        let s = tree.samples(r);
                        s[j % s.len()]
                    })
                    .collect()
            })
            .collect();
        let mut root_starts: Vec<(u32, u32)> = tree
            .roots()
            .map(|r| (tree.node(r).faces().start as u32, r as u32))
            .collect();
        root_starts.sort_unstable();
        let mut root_slot = vec![0; items.len()];
        for (slot, &r) in volumes.face_order.iter().enumerate() {
            root_slot[r] = slot as u32;
        }
        Self {
            tree,
            scene,
            centroid,
            rho_vector,
            rho_area,
            emitted,
            exchange: crate::SelfExchange::default(),
            volumes,
            volume_samples,
            root_starts,
            root_slot,
            face_reads: AtomicU64::new(0),
        }
    }

    /// How many input faces the solve has read since the context was made (each tree leaf the refinement
    /// splits into its face's patch reads that face once).
    pub fn face_reads(&self) -> u64 {
        self.face_reads.load(Ordering::Relaxed)
    }

    /// Counts one input face read by the solve.
    pub(crate) fn count_face_read(&self) {
        self.face_reads.fetch_add(1, Ordering::Relaxed);
    }

    /// Approximate heap bytes held (the tree and the volumes included).
    pub fn bytes(&self) -> usize {
        self.tree.bytes()
            + self.centroid.len()
                * (size_of::<DVec3>() + size_of::<[DVec3; 3]>() + 2 * size_of::<Rgb>())
            + self.volumes.bytes() as usize
            + self.volume_samples.len() * (24 + VOLUME_SAMPLES * size_of::<DVec3>())
            + self.exchange.bytes()
    }

    /// Position of scene face `f` in the tree's face order.
    fn position(&self, f: FaceId) -> usize {
        self.tree.node(self.tree.leaf_of_face(f)).faces().start
    }

    /// Whether scene face `f` belongs to tree node `n`.
    pub fn node_holds(&self, n: usize, f: FaceId) -> bool {
        self.tree.node(n).faces().contains(&self.position(f))
    }

    /// Whether scene face `f` belongs to a root below volume `v`.
    pub fn volume_holds(&self, v: u32, f: FaceId) -> bool {
        let pos = self.position(f) as u32;
        let i = self.root_starts.partition_point(|&(start, _)| start <= pos);
        let Some(&(_, root)) = i.checked_sub(1).and_then(|i| self.root_starts.get(i)) else {
            return false;
        };
        let slot = self.root_slot[root as usize];
        let c = &self.volumes.clusters[v as usize];
        (c.start..c.end).contains(&slot)
    }

    /// Whether tree node `n`'s two children each have the other's centroid strictly in front of their vector
    /// area's plane (a concave node).
    pub fn concave(&self, n: usize) -> bool {
        let kids = self.tree.node(n).children();
        if kids.len() != 2 {
            return false;
        }
        let (a, b) = (kids.start, kids.start + 1);
        let (ca, cb) = (self.centroid[a], self.centroid[b]);
        let (na, nb) = (self.tree.node(a).vector_area, self.tree.node(b).vector_area);
        let tol = 1e-9 * (ca - cb).length() * (na.length() + nb.length());
        na.dot(cb - ca) > tol && nb.dot(ca - cb) > tol
    }

    /// The root volume: the engine's one root.
    pub fn root_volume(self: &Arc<Self>) -> FaceNode<'a> {
        FaceNode::Volume(VolumeRef {
            ctx: Arc::clone(self),
            id: 0,
        })
    }
}

/// A node of the simulation hierarchy: a face cluster, or a patch of one input face.
#[derive(Clone, Debug)]
#[allow(clippy::large_enum_variant)]
pub enum FaceNode<'a> {
    /// A volume cluster above the tree's roots.
    Volume(VolumeRef<'a>),
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

/// A volume of the loose octree over the roots.
#[derive(Clone, Debug)]
pub struct VolumeRef<'a> {
    /// The tree, its sums and the volumes.
    pub ctx: Arc<FaceContext<'a>>,
    /// Volume index in [`FaceContext::volumes`].
    pub id: u32,
}

impl VolumeRef<'_> {
    /// The volume's data.
    pub fn data(&self) -> &radlab_volume_cluster::Cluster {
        &self.ctx.volumes.clusters[self.id as usize]
    }
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
            Self::Volume(v) => v.data().centroid,
            Self::Cluster(c) => c.ctx.centroid[c.id as usize],
            Self::Patch(p) => p.centroid,
        }
    }

    /// A cone holding every face normal (every direction for a volume).
    pub fn cone(&self) -> NormalCone {
        match self {
            Self::Volume(_) => NormalCone {
                axis: DVec3::Z,
                half_angle: std::f64::consts::PI,
            },
            Self::Cluster(c) => c.node().cone,
            Self::Patch(p) => NormalCone::of_normal(p.normal),
        }
    }

    /// Whether part of the node can see another part: a cluster whose two children each have the other's
    /// centroid strictly in front of their vector area's plane (concave). Single faces and patches cannot.
    pub fn sees_itself(&self) -> bool {
        let c = match self {
            Self::Volume(v) => {
                let d = v.data();
                return d.end - d.start > 1;
            }
            Self::Cluster(c) => c,
            Self::Patch(_) => return false,
        };
        c.ctx.concave(c.id as usize)
    }

    /// Whether the node is a cluster whose children are all single faces (tree leaves).
    pub fn children_are_faces(&self) -> bool {
        match self {
            Self::Cluster(c) => {
                let node = c.node();
                !node.is_leaf() && node.children().all(|k| c.ctx.tree.node(k).is_leaf())
            }
            Self::Volume(_) | Self::Patch(_) => false,
        }
    }

    /// The patch, if it is one.
    pub fn as_patch(&self) -> Option<&Patch> {
        match self {
            Self::Patch(p) => Some(p),
            Self::Volume(_) | Self::Cluster(_) => None,
        }
    }

    /// Corners of a box around the node (its box for a volume, its oriented box for a cluster, its vertices
    /// for a patch).
    pub fn hull(&self) -> Vec<DVec3> {
        match self {
            Self::Volume(v) => {
                let d = v.data();
                (0..8)
                    .map(|i| {
                        DVec3::new(
                            if i & 1 == 0 { d.lo.x } else { d.hi.x },
                            if i & 2 == 0 { d.lo.y } else { d.hi.y },
                            if i & 4 == 0 { d.lo.z } else { d.hi.z },
                        )
                    })
                    .collect()
            }
            Self::Cluster(c) => c.node().obb.corners().to_vec(),
            Self::Patch(p) => p.polygon.vertices().to_vec(),
        }
    }

    /// Whether scene face `f` is part of the node.
    pub fn holds(&self, f: FaceId) -> bool {
        match self {
            Self::Volume(v) => v.ctx.volume_holds(v.id, f),
            Self::Cluster(c) => c.ctx.node_holds(c.id as usize, f),
            Self::Patch(p) => p.face == f,
        }
    }

    /// Whether it is a volume above the roots.
    pub fn is_volume(&self) -> bool {
        matches!(self, Self::Volume(_))
    }

    /// Points on the node's surfaces for visibility rays: the tree's sample points of a cluster, four
    /// stratified points of a patch.
    pub fn sample_points(&self) -> Vec<DVec3> {
        match self {
            Self::Volume(v) => v.ctx.volume_samples[v.id as usize].clone(),
            Self::Cluster(c) => c.ctx.tree.samples(c.id as usize).to_vec(),
            Self::Patch(p) => [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)]
                .iter()
                .map(|&(s, t)| p.polygon.point_at(s, t))
                .collect(),
        }
    }

    /// The sample points facing `target` (in front of their face's plane), or all of them where none does or
    /// the node is a volume (its points lie on surfaces of every orientation): where a link's visibility is
    /// sampled, since the faces turned away from the other end take no light from it whatever lies between.
    pub fn sample_points_facing(&self, target: DVec3) -> Vec<DVec3> {
        let Self::Cluster(c) = self else {
            // A patch's samples share its normal: all face the target or none does.
            return self.sample_points();
        };
        let tree = &c.ctx.tree;
        let facing: Vec<DVec3> = tree.samples_facing(c.id as usize, target).collect();
        if facing.is_empty() {
            tree.samples(c.id as usize).to_vec()
        } else {
            facing
        }
    }
}

impl NodeKind for FaceNode<'_> {
    fn area(&self) -> f64 {
        match self {
            Self::Volume(v) => v.data().area,
            Self::Cluster(c) => c.node().area,
            Self::Patch(p) => p.area,
        }
    }

    fn bound(&self) -> Bound {
        match self {
            Self::Volume(v) => {
                let d = v.data();
                Bound {
                    centre: 0.5 * (d.lo + d.hi),
                    radius: 0.5 * (d.hi - d.lo).length(),
                }
            }
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
            // The direction-averaged projected area of any set of one-sided surfaces (Sillion 1995).
            Self::Volume(v) => v.data().area / 4.0,
            Self::Cluster(c) => {
                let n = c.node();
                n.obb.projected_area(dir).min(n.area)
            }
            Self::Patch(p) => p.projected_area(dir),
        }
    }

    fn reflectance(&self) -> Rgb {
        match self {
            Self::Volume(v) => v.data().reflectance,
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
            Self::Volume(v) => v.data().emission,
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
            Self::Volume(_) | Self::Cluster(_) => true,
            Self::Patch(p) => p.can_split(min_size),
        }
    }

    fn split(&self) -> Vec<Self> {
        match self {
            Self::Volume(v) => {
                let d = v.data();
                let mut kids: Vec<Self> = d
                    .children
                    .iter()
                    .map(|&id| {
                        Self::Volume(VolumeRef {
                            ctx: Arc::clone(&v.ctx),
                            id,
                        })
                    })
                    .collect();
                let roots =
                    &v.ctx.volumes.face_order[d.start as usize..(d.start + d.direct) as usize];
                kids.extend(roots.iter().map(|&r| {
                    Self::Cluster(ClusterRef {
                        ctx: Arc::clone(&v.ctx),
                        id: r as u32,
                    })
                }));
                kids
            }
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
            Self::Volume(v) => sampling::mix64(0x7017_C1A5_0000_0000 ^ u64::from(v.id)),
            Self::Cluster(c) => sampling::mix64(0xFACE_C1A5_0000_0000 ^ u64::from(c.id)),
            Self::Patch(p) => p.key(),
        }
    }

    fn patch(&self) -> Option<&Patch> {
        self.as_patch()
    }

    fn sends_own_emission(&self) -> bool {
        // A power vector p = p_E + M e carries its faces' emission; a volume sends isotropically, so an
        // emitting volume is split first.
        !self.is_volume()
    }
}

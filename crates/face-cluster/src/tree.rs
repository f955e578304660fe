//! The face-cluster hierarchy: the binary tree of the greedy contraction (see [`crate::contraction`]) laid out
//! for a solver that never reads input faces (Willmott, Heckbert & Garland 1999, section 3).
//!
//! Layout: nodes in breadth-first order from the roots, so the children of a node are a contiguous range of
//! node indices and every parent comes before its children; faces permuted (depth-first, first child first)
//! so the faces of every node are a contiguous range of [`FaceClusterTree::face_order`], nested inside their
//! parent's. Each node carries, pulled up from its children in O(1):
//! - area A = Σ A_i and vector area Σ A_i n_i;
//! - a normal cone, an oriented box in the node's fitted frame and a bounding sphere (see [`crate::bounds`]);
//! - per channel, M = Σ ρ_i A_i n_i n_iᵀ and p_E = Σ E_i A_i n_i, so that wherever every face of the node
//!   has n_i·e ≥ 0, its power vector under irradiance vector e is Σ (E_i + ρ_i n_i·e) A_i n_i = p_E + M e
//!   (Willmott et al. 1999, section 4: the leaf rule B_i = E_i + ρ_i n_i·e summed without visiting leaves);
//! - `samples_per_node` points on its faces for visibility rays: stratified over each face (a rotated
//!   Hammersley set through [`radlab_scene::Polygon::point_at`]), and at a parent drawn from the children's
//!   points in proportion to the children's areas (stratified), so they stay area-uniform at every level;
//!   each with its face's normal, so that a visibility estimate can keep to the samples facing the other end.

use std::ops::Range;

use glam::DVec3;
use radlab_scene::{Scene, sampling};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::bounds::{NormalCone, OrientedBox, Sphere};
use crate::contraction::{ContractionStats, contract};
use crate::moments::SymMat3;
use crate::{FaceClusterError, FaceClusterParams};

/// "No such node" in [`Node::parent`].
pub const NO_PARENT: u32 = u32::MAX;

/// One cluster of faces.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Node {
    first_face: u32,
    face_count: u32,
    first_child: u32,
    child_count: u32,
    parent: u32,
    /// Total area Σ A_i.
    pub area: f64,
    /// Vector area Σ A_i n_i (its length is at most `area`; near zero for a closed surface).
    pub vector_area: DVec3,
    /// Root-mean-square distance of the node's face corners to its least-squares plane (0 for one face). The
    /// square root of an eigenvalue known to about ε times the scatter's norm, so planar nodes read up to
    /// about √ε × their size, not 0.
    pub plane_rms: f64,
    /// Cone holding every face normal of the node.
    pub cone: NormalCone,
    /// Oriented box in the node's fitted frame (last axis: the plane normal, on the side of `vector_area`).
    pub obb: OrientedBox,
    /// Bounding sphere.
    pub sphere: Sphere,
    /// Per channel (r, g, b): M = Σ ρ_i A_i n_i n_iᵀ.
    pub m: [SymMat3; 3],
    /// N = Σ A_i n_i n_iᵀ: with `vector_area` and `area`, the mean and second moment of the cosines n_i·u
    /// toward any direction u (area-weighted), from which a cluster's clamped cosine is fitted
    /// ([`crate::clamped_irradiance::CosineFit::of_node`]).
    pub normal_moment: SymMat3,
    /// Per channel (r, g, b): p_E = Σ E_i A_i n_i.
    pub p_e: [DVec3; 3],
}

impl Node {
    /// Positions in [`FaceClusterTree::face_order`] of this node's faces.
    pub fn faces(&self) -> Range<usize> {
        self.first_face as usize..(self.first_face + self.face_count) as usize
    }

    /// Indices of the children (empty for a leaf).
    pub fn children(&self) -> Range<usize> {
        self.first_child as usize..(self.first_child + self.child_count) as usize
    }

    /// Whether the node is one input face.
    pub fn is_leaf(&self) -> bool {
        self.child_count == 0
    }

    /// The parent, `None` for a root.
    pub fn parent(&self) -> Option<usize> {
        (self.parent != NO_PARENT).then_some(self.parent as usize)
    }

    /// The power vector per channel under irradiance vectors `e` (one per channel): p_E + M e, exact where
    /// every face of the node has n_i·e ≥ 0.
    pub fn power_vector(&self, e: [DVec3; 3]) -> [DVec3; 3] {
        std::array::from_fn(|c| self.p_e[c] + self.m[c].mul_vec(e[c]))
    }

    /// Ends of the child and face ranges without overflow (for checking a decoded cache).
    pub(crate) fn raw_ends(&self) -> (u64, u64) {
        (
            u64::from(self.first_child) + u64::from(self.child_count),
            u64::from(self.first_face) + u64::from(self.face_count),
        )
    }

    /// The fitted plane's unit normal (the box's last axis).
    pub fn normal(&self) -> DVec3 {
        self.obb.axes[2]
    }
}

/// A face-cluster hierarchy over every face of a scene (see the module doc).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FaceClusterTree {
    pub(crate) digest: crate::Digest,
    pub(crate) params: FaceClusterParams,
    pub(crate) nodes: Vec<Node>,
    pub(crate) root_count: u32,
    pub(crate) face_order: Vec<u32>,
    pub(crate) leaf_of_face: Vec<u32>,
    pub(crate) samples: Vec<DVec3>,
    pub(crate) sample_normals: Vec<DVec3>,
    pub(crate) stats: ContractionStats,
}

/// Base-2 radical inverse of `i` (van der Corput), in [0, 1).
fn radical_inverse_2(i: u32) -> f64 {
    f64::from(i.reverse_bits()) / 4_294_967_296.0
}

/// Random stream of the samples of internal node `node` (leaves use their face index).
const INTERNAL_STREAM: u64 = 1 << 63;

impl FaceClusterTree {
    /// Builds the hierarchy of every face of `scene`: O(k log k) for k faces. Deterministic; the face-level
    /// work runs on rayon's threads and gives the same bits on any number of them.
    pub fn build(scene: &Scene, params: &FaceClusterParams) -> Result<Self, FaceClusterError> {
        params.validate()?;
        let digest = crate::cache::digest(scene, params);
        let k = scene.face_count();
        let con = contract(scene, params);
        let nreg = con.regions.len();
        let region_children = |r: usize| (r >= k).then(|| con.merges[r - k]);

        // Roots in order of their smallest face.
        let mut min_face: Vec<u32> = (0..k as u32).collect();
        let mut has_parent = vec![false; nreg];
        for (i, [a, b]) in con.merges.iter().enumerate() {
            min_face.push(min_face[*a as usize].min(min_face[*b as usize]));
            has_parent[*a as usize] = true;
            has_parent[*b as usize] = true;
            debug_assert_eq!(min_face.len(), k + i + 1);
        }
        let mut roots: Vec<u32> = (0..nreg as u32)
            .filter(|&r| !has_parent[r as usize])
            .collect();
        roots.sort_by_key(|&r| min_face[r as usize]);

        // Breadth-first layout: region of each node, children contiguous.
        let mut region_of: Vec<u32> = Vec::with_capacity(nreg);
        region_of.extend_from_slice(&roots);
        let mut first_child = vec![0u32; nreg];
        let mut parent = vec![NO_PARENT; nreg];
        let mut i = 0;
        while i < region_of.len() {
            if let Some([a, b]) = region_children(region_of[i] as usize) {
                first_child[i] = region_of.len() as u32;
                parent[region_of.len()] = i as u32;
                parent[region_of.len() + 1] = i as u32;
                region_of.push(a);
                region_of.push(b);
            }
            i += 1;
        }
        debug_assert_eq!(region_of.len(), nreg);

        // Face counts bottom-up (region ids grow from children to parents), then ranges top-down.
        let mut count_of_region = vec![1u32; nreg];
        for (i, [a, b]) in con.merges.iter().enumerate() {
            count_of_region[k + i] = count_of_region[*a as usize] + count_of_region[*b as usize];
        }
        let mut first_face = vec![0u32; nreg];
        let mut next = 0u32;
        for n in 0..roots.len() {
            first_face[n] = next;
            next += count_of_region[region_of[n] as usize];
        }
        let mut face_order = vec![0u32; k];
        let mut leaf_of_face = vec![0u32; k];
        for n in 0..nreg {
            let r = region_of[n] as usize;
            if r < k {
                face_order[first_face[n] as usize] = r as u32;
                leaf_of_face[r] = n as u32;
            } else {
                let c = first_child[n] as usize;
                first_face[c] = first_face[n];
                first_face[c + 1] = first_face[n] + count_of_region[region_of[c] as usize];
            }
        }

        // Leaves from their faces (in parallel), then internal nodes from their children, last to first.
        let s = params.samples_per_node;
        let mut samples = vec![DVec3::ZERO; nreg * s];
        let mut sample_normals = vec![DVec3::ZERO; nreg * s];
        let mut nodes: Vec<Node> = samples
            .par_chunks_mut(s)
            .zip(sample_normals.par_chunks_mut(s))
            .enumerate()
            .map(|(n, (pts, normals))| {
                let r = region_of[n] as usize;
                let mut node = if r < k {
                    normals.fill(scene.faces[r].normal);
                    leaf_node(scene, r, params, pts)
                } else {
                    placeholder()
                };
                node.first_face = first_face[n];
                node.face_count = count_of_region[r];
                node.first_child = if r < k { 0 } else { first_child[n] };
                node.child_count = if r < k { 0 } else { 2 };
                node.parent = parent[n];
                node
            })
            .collect();
        for n in (0..nreg).rev() {
            if nodes[n].is_leaf() {
                continue;
            }
            let c = nodes[n].first_child as usize;
            let (head, tail) = nodes.split_at_mut(c);
            let node = &mut head[n];
            pull_up(
                node,
                &tail[0],
                &tail[1],
                &con.regions[region_of[n] as usize],
            );
            // The same picks for the points and their normals (one stream).
            let rng = sampling::rng(params.seed, INTERNAL_STREAM | n as u64);
            let areas = (nodes[c].area, nodes[c + 1].area);
            for list in [&mut samples, &mut sample_normals] {
                let (head, tail) = list.split_at_mut(c * s);
                pick_samples(
                    &mut head[n * s..(n + 1) * s],
                    &tail[..s],
                    &tail[s..2 * s],
                    areas,
                    rng.clone(),
                );
            }
        }
        Ok(Self {
            digest,
            params: params.clone(),
            nodes,
            root_count: roots.len() as u32,
            face_order,
            leaf_of_face,
            samples,
            sample_normals,
            stats: con.stats,
        })
    }

    /// Every node; roots first, then breadth-first (a parent always comes before its children).
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// Node `n`.
    pub fn node(&self, n: usize) -> &Node {
        &self.nodes[n]
    }

    /// The roots: one per dual-connected part of the scene's meshes (nodes `0..roots().end`).
    pub fn roots(&self) -> Range<usize> {
        0..self.root_count as usize
    }

    /// The face permutation: the faces of node n are `face_order()[node(n).faces()]`.
    pub fn face_order(&self) -> &[u32] {
        &self.face_order
    }

    /// The scene faces of node `n`.
    pub fn faces_of(&self, n: usize) -> &[u32] {
        &self.face_order[self.nodes[n].faces()]
    }

    /// The leaf node of scene face `f`.
    pub fn leaf_of_face(&self, f: usize) -> usize {
        self.leaf_of_face[f] as usize
    }

    /// The sample points of node `n` (on its faces; `params().samples_per_node` of them).
    pub fn samples(&self, n: usize) -> &[DVec3] {
        let s = self.params.samples_per_node;
        &self.samples[n * s..(n + 1) * s]
    }

    /// The unit normals of the faces the sample points of node `n` lie on, in the order of
    /// [`Self::samples`].
    pub fn sample_normals(&self, n: usize) -> &[DVec3] {
        let s = self.params.samples_per_node;
        &self.sample_normals[n * s..(n + 1) * s]
    }

    /// The sample points of node `n` in front of their face's plane as seen from `toward`, in the order of
    /// [`Self::samples`]: where a visibility ray toward `toward` may leave from, since a face turned away
    /// takes no light from there whatever lies between.
    pub fn samples_facing(
        &self,
        n: usize,
        toward: DVec3,
    ) -> impl Iterator<Item = DVec3> + Clone + '_ {
        self.samples(n)
            .iter()
            .zip(self.sample_normals(n))
            .filter(move |(p, normal)| normal.dot(toward - **p) > 0.0)
            .map(|(p, _)| *p)
    }

    /// One sample point of node `n` for a visibility ray from `x` (on a surface of normal `normal`), chosen
    /// by `u` in [0, 1) with probability proportional to the point kernel between them,
    /// w_s = max(0, n_s·(x − y_s)) max(0, normal·(y_s − x)) / |x − y_s|⁴, so that one ray's expected visibility
    /// is the kernel-weighted mean over the samples; evenly among all samples where every weight is 0.
    pub fn sample_toward(&self, n: usize, x: DVec3, normal: DVec3, u: f64) -> DVec3 {
        let samples = self.samples(n);
        // Each sample's kernel once (at most MAX_SAMPLES_PER_NODE of them), then the draw over them.
        let mut weights = [0.0; FaceClusterParams::MAX_SAMPLES_PER_NODE];
        let weights = &mut weights[..samples.len()];
        for ((w, y), ns) in weights.iter_mut().zip(samples).zip(self.sample_normals(n)) {
            let v = x - *y;
            let d2 = v.length_squared();
            let k = ns.dot(v).max(0.0) * normal.dot(-v).max(0.0) / (d2 * d2);
            *w = if k.is_finite() { k } else { 0.0 };
        }
        let total: f64 = weights.iter().sum();
        if !(total > 0.0) {
            return samples[((u * samples.len() as f64) as usize).min(samples.len() - 1)];
        }
        let mut left = u * total;
        for (y, &w) in samples.iter().zip(weights.iter()) {
            if left < w {
                return *y;
            }
            left -= w;
        }
        // Rounding left `u · total` at or above the sum: the last sample of positive weight.
        let last = weights.iter().rposition(|&w| w > 0.0).unwrap_or(0);
        samples[last]
    }

    /// The build parameters.
    pub fn params(&self) -> &FaceClusterParams {
        &self.params
    }

    /// The digest of the scene's mesh and the build parameters this hierarchy was built from.
    pub fn digest(&self) -> &crate::Digest {
        &self.digest
    }

    /// Counts from the contraction (dual, boundary and non-manifold edges, merges, queue work).
    pub fn stats(&self) -> &ContractionStats {
        &self.stats
    }

    /// The number of edges on the longest path from a root to a leaf (0 when every root is a leaf).
    pub fn depth(&self) -> usize {
        let mut depth = vec![0usize; self.nodes.len()];
        for (i, n) in self.nodes.iter().enumerate() {
            for c in n.children() {
                depth[c] = depth[i] + 1;
            }
        }
        depth.into_iter().max().unwrap_or(0)
    }

    /// Approximate heap bytes held.
    pub fn bytes(&self) -> usize {
        self.nodes.len() * size_of::<Node>()
            + (self.face_order.len() + self.leaf_of_face.len()) * 4
            + (self.samples.len() + self.sample_normals.len()) * size_of::<DVec3>()
    }
}

fn placeholder() -> Node {
    Node {
        first_face: 0,
        face_count: 0,
        first_child: 0,
        child_count: 0,
        parent: NO_PARENT,
        area: 0.0,
        vector_area: DVec3::ZERO,
        plane_rms: 0.0,
        cone: NormalCone::of_normal(DVec3::Z),
        obb: OrientedBox {
            centre: DVec3::ZERO,
            axes: [DVec3::X, DVec3::Y, DVec3::Z],
            half_extents: DVec3::ZERO,
        },
        sphere: Sphere {
            centre: DVec3::ZERO,
            radius: 0.0,
        },
        m: [SymMat3::ZERO; 3],
        normal_moment: SymMat3::ZERO,
        p_e: [DVec3::ZERO; 3],
    }
}

/// A leaf's data from its face, and its sample points.
fn leaf_node(scene: &Scene, f: usize, params: &FaceClusterParams, pts: &mut [DVec3]) -> Node {
    let face = &scene.faces[f];
    let poly = scene.polygon(f);
    let v = poly.vertices();
    let n = face.normal;
    let a0 = (v[1] - v[0]).reject_from_normalized(n).normalize();
    let axes = [a0, n.cross(a0), n];
    let (rho, e) = (scene.reflectance(f), scene.emission(f));
    let mut r = sampling::rng(params.seed, f as u64);
    let (xi, eta) = (sampling::uniform(&mut r), sampling::uniform(&mut r));
    let s = pts.len();
    for (j, p) in pts.iter_mut().enumerate() {
        let u = (j as f64 + xi) / s as f64;
        let t = (radical_inverse_2(j as u32) + eta).fract();
        *p = poly.point_at(u, t);
    }
    Node {
        area: face.area,
        vector_area: n * face.area,
        cone: NormalCone::of_normal(n),
        obb: OrientedBox::fit(axes, v.iter().copied()),
        sphere: Sphere::about(face.centroid, v),
        m: std::array::from_fn(|c| SymMat3::outer(n, rho[c] * face.area)),
        normal_moment: SymMat3::outer(n, face.area),
        p_e: std::array::from_fn(|c| n * (e[c] * face.area)),
        ..placeholder()
    }
}

/// An internal node's data from its two children and its region's moments.
fn pull_up(node: &mut Node, a: &Node, b: &Node, region: &crate::contraction::Region) {
    node.area = a.area + b.area;
    node.vector_area = a.vector_area + b.vector_area;
    node.plane_rms = region.moments.plane_fit_error().sqrt();
    node.cone = a.cone.union(&b.cone);
    let mut axes = region
        .moments
        .scatter
        .eigen_frame()
        .unwrap_or(if a.area >= b.area {
            a.obb.axes
        } else {
            b.obb.axes
        });
    if axes[2].dot(node.vector_area) < 0.0 {
        axes[1] = -axes[1];
        axes[2] = -axes[2];
    }
    node.obb = OrientedBox::fit(axes, a.obb.corners().into_iter().chain(b.obb.corners()));
    node.sphere = a.sphere.union(&b.sphere);
    node.m = std::array::from_fn(|c| a.m[c] + b.m[c]);
    node.normal_moment = a.normal_moment + b.normal_moment;
    node.p_e = std::array::from_fn(|c| a.p_e[c] + b.p_e[c]);
}

/// A parent's samples from its children's: child 0 gives those of the stratified positions
/// (j + ξ)/S that fall below its area fraction, child 1 the rest, each from a random offset in its list.
fn pick_samples(
    out: &mut [DVec3],
    c0: &[DVec3],
    c1: &[DVec3],
    areas: (f64, f64),
    mut r: sampling::Rng,
) {
    let s = out.len();
    let xi = sampling::uniform(&mut r);
    let frac0 = areas.0 / (areas.0 + areas.1);
    let n0 = (0..s)
        .filter(|&j| (j as f64 + xi) / (s as f64) < frac0)
        .count();
    let off0 = (sampling::uniform(&mut r) * s as f64) as usize;
    let off1 = (sampling::uniform(&mut r) * s as f64) as usize;
    for (i, p) in out.iter_mut().enumerate() {
        *p = if i < n0 {
            c0[(off0 + i) % s]
        } else {
            c1[(off1 + i - n0) % s]
        };
    }
}

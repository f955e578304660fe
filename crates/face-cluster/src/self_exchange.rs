//! The light a face-cluster node sends onto itself, traced once before the solve: its self form factor
//!
//!   F_NN = (1/A_N) Σ_{i ∈ N} A_i F_{i→N},
//!
//! the share of what the node's faces send that lands on the node's own faces (visibility included), and for
//! a node P with children a and b the exchange between them, A_a F_ab = A_b F_ba (reciprocity). By the
//! Nusselt analogy (Cohen & Wallace 1993, §4.9) a cosine-distributed ray from a uniform point of face i lands
//! on face j with probability F_ij, so one pass of `rays` such rays per input face estimates every node's
//! self form factor at once: a ray from face i that reaches the front of face j of the same tree adds A_i/rays
//! to H(P) at the deepest node P holding both, and
//!
//!   A_N F_NN = Σ_{P ∈ subtree(N)} H(P),     A_a F_ab = A_b F_ba = H(P)/2.
//!
//! The same rays say where that light lands: L_N, what the node's mesh sends onto N's faces, and for a
//! node a with sibling b what b sends onto a and onto each of a's children (the rays whose deepest common
//! node is a's parent), and what lands on N from beyond it, L_N − A_N F_NN. Push hands a node's traced light
//! down by these (per unit area, the totals kept), so a valley gets more than a ridge, and a sibling's light,
//! at every level below the link that brought it, lands near the boundary it crossed; and the answers hand
//! it on down to the faces below the deepest node the solve made. Each ratio is shrunk toward one by its
//! noise (n rays landed: relative deviation about 1/√n; Wiener's gain d²/(d² + r²/n) on its departure d),
//! so a valley keeps its share while the inside of a sphere, where every true ratio is one, is not made as
//! noisy as its faces' few landings.
//!
//! A convex node sends nothing onto itself (no ray returns), a spherical cap of half-angle θ seen from
//! inside sends (1 − cos θ)/2 of its light (inside a sphere of radius R, F_ij = A_j/(4πR²) for any two
//! parts), and a rough, nearly flat patch of ground something in between; the self-links of
//! [`crate::VectorTransport`] carry these factors where the node's children do not face each other as a whole (a ridge, a rough patch of terrain), so that light a heightfield sends onto
//! itself is not lost. Like the hierarchy, this pass reads every input face (O(k · rays) rays); the solve
//! does not. Each face draws from its own stream (seed, face), and the sums are made in face order, so the
//! factors do not depend on the number of threads.

use radlab_scene::{AreaSampler, Rgb, Scene, sampling};
use radlab_visibility::Accel;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::FaceClusterTree;

/// What a curved face-cluster node sends onto itself (parameter `self_exchange`).
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum SelfExchangeMode {
    /// Only a concave node (each child's centroid in front of the other's mean plane) has a self-link, with
    /// its spherical cap's share (1 − cos θ)/2 of its light along its cone's axis, refined into its children's
    /// pairs while it could carry more than ε. Exact inside a sphere; a ridge or a rough patch of ground has
    /// none, so its parts exchange no light.
    Cap,
    /// A one-sided curved node (|Σ A_i n_i| ≥ A/2, for a spherical cap a cone of at most 90°) of at least
    /// [`crate::vector_transport::TRACED_MIN_FACES`] (32) faces has a self-link carrying its traced F_NN, and its
    /// two children, if one-sided, a link carrying the traced exchange between them, never refined; both
    /// handed down the receiver by where the trace's rays landed ([`SelfExchange::landing_ratio`]; by default
    /// at least [`SELF_RAYS`] rays per input face before the solve). Other nodes keep the cap's rule if they
    /// are concave; otherwise their self-link carries nothing and is refined while their traced F_NN could
    /// carry more than ε. The default.
    #[default]
    Traced,
}

impl SelfExchangeMode {
    /// The name used in parameters.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Cap => "cap",
            Self::Traced => "traced",
        }
    }
}

/// Rays per input face, at least, by default (parameter `self_rays`): at 1e6 faces, 3.2e7 rays.
pub const SELF_RAYS: u32 = 32;

/// Faces traced per block (their landings are held until the block is summed).
const TRACE_BLOCK: usize = 1 << 16;

/// Rays in all, at least (default 65,536), shared among the faces in proportion to their areas, so that a
/// coarse mesh (a room of a dozen triangles) is not estimated from a few dozen rays.
pub const SELF_RAYS_TOTAL: f64 = 65_536.0;

/// The traced self-exchange of every node of a tree.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SelfExchange {
    /// Per node: A_N F_NN, the flux per unit radiosity the node sends onto itself.
    pub onto_itself: Vec<f64>,
    /// Per node: H(N)/2, the flux per unit radiosity each of its two children sends onto the other
    /// (0 for a leaf).
    pub between_children: Vec<f64>,
    /// Per node: the flux per unit radiosity its mesh's faces send onto it, Σ_{j ∈ N} A_j F_{j→mesh} (the
    /// rays of the trace that land on its faces; by reciprocity also what its faces send onto their mesh).
    pub landed: Vec<f64>,
    /// Per node a: the flux its sibling's faces send onto it (the rays whose deepest common node is a's
    /// parent), Σ_{j ∈ a} A_j F_{j→sibling}.
    pub from_sibling: Vec<f64>,
    /// Per node C: the flux its parent's sibling's faces send onto it (rays whose deepest common node is C's
    /// grandparent).
    pub from_uncle: Vec<f64>,
    /// Per node: how many of the trace's rays landed on its faces (the count behind [`Self::landed`]).
    pub landed_rays: Vec<u32>,
    /// Per node: the ratios push hands light down to it by, per [`Landing`] (mesh, sibling, outside): the
    /// landing ratios shrunk by their noise ([`Self::shrunk_ratios`]), computed once after the trace.
    handed: Vec<[f64; 3]>,
}

/// Which of the trace's landings hands a node's traced light down to its children.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Landing {
    /// Where the node's whole mesh sent light ([`SelfExchange::landed`]): for its self-exchange and what its
    /// ancestors passed down.
    Mesh,
    /// Where the node's sibling sent light ([`SelfExchange::from_sibling`], [`SelfExchange::from_uncle`]):
    /// for what the sibling link delivered to the node itself.
    Sibling,
    /// Where light from beyond the node's grandparent landed (rays whose deepest common node with it lies
    /// above its grandparent: L − A F_NN, less what its sibling and its uncle sent): for what the siblings of
    /// its parent's ancestors sent, which lands near the boundaries it crossed rather than in the node's own
    /// valleys.
    Outside,
}

impl SelfExchange {
    /// Traces at least `rays` rays from each face of `tree` (and [`SELF_RAYS_TOTAL`] in all) through `accel`
    /// (its scene's faces), streams from `seed`.
    pub fn trace(
        tree: &FaceClusterTree,
        scene: &Scene,
        accel: &Accel,
        seed: u64,
        rays: u32,
    ) -> Self {
        let nodes = tree.nodes();
        let k = tree.face_order().len();
        let total: f64 = tree.roots().map(|n| nodes[n].area).sum();
        // One face's landings: (deepest node holding both faces, leaf of the face hit, weight).
        let land = |f: usize| -> Vec<(u32, u32, u32, f64)> {
            let face = &scene.faces[f];
            if !(face.area > 0.0) || rays == 0 {
                return Vec::new();
            }
            let rays = rays.max((SELF_RAYS_TOTAL * face.area / total).ceil() as u32);
            let start = AreaSampler::new(scene.polygon(f));
            let mut r = sampling::rng(seed, f as u64 ^ 0x7365_6c66_6578_6368);
            let w = face.area / rays as f64;
            let mut out = Vec::new();
            for _ in 0..rays {
                let (u, v) = (sampling::uniform(&mut r), sampling::uniform(&mut r));
                let (u1, u2) = (sampling::uniform(&mut r), sampling::uniform(&mut r));
                let d = sampling::cosine_hemisphere(face.normal, u1, u2);
                let Some(hit) = accel.intersect_from(f, start.sample(u, v), d) else {
                    continue;
                };
                if scene.faces[hit.face].normal.dot(d) >= 0.0 {
                    continue; // the back of a one-sided face absorbs
                }
                // Node N holds the face hit iff its range of the face order holds the hit face's leaf's.
                let to = nodes[tree.leaf_of_face(hit.face)].faces().start;
                let mut n = tree.leaf_of_face(f);
                while !nodes[n].faces().contains(&to) {
                    match nodes[n].parent() {
                        Some(p) => n = p,
                        None => break,
                    }
                }
                if nodes[n].faces().contains(&to) {
                    out.push((n as u32, to as u32, tree.leaf_of_face(hit.face) as u32, w));
                }
            }
            out
        };
        // Blocks of faces traced in parallel and summed in face order: the same sums on any number of
        // threads, and at most one block's landings held at once.
        let (mut h, mut landed) = (vec![0.0; nodes.len()], vec![0.0; nodes.len()]);
        let mut landed_rays = vec![0u32; nodes.len()];
        let (mut from_sibling, mut from_uncle) = (vec![0.0; nodes.len()], vec![0.0; nodes.len()]);
        for start in (0..k).step_by(TRACE_BLOCK) {
            let block: Vec<Vec<(u32, u32, u32, f64)>> = (start..(start + TRACE_BLOCK).min(k))
                .into_par_iter()
                .map(land)
                .collect();
            for &(n, to, leaf, w) in block.iter().flatten() {
                h[n as usize] += w;
                landed[leaf as usize] += w;
                landed_rays[leaf as usize] += 1;
                // The child of n the ray landed in, and that child's child on the way to the face hit.
                let below = |m: usize| {
                    nodes[m]
                        .children()
                        .find(|&c| nodes[c].faces().contains(&(to as usize)))
                };
                if let Some(a) = below(n as usize) {
                    from_sibling[a] += w;
                    if let Some(c) = below(a) {
                        from_uncle[c] += w;
                    }
                }
            }
        }
        let between_children = h.iter().map(|x| 0.5 * x).collect();
        // Children follow parents (breadth-first): a reverse walk sums each subtree before its parent reads it.
        let mut onto_itself = h;
        for i in (0..nodes.len()).rev() {
            let below: f64 = nodes[i].children().map(|c| onto_itself[c]).sum();
            onto_itself[i] += below;
        }
        for i in (0..nodes.len()).rev() {
            let below: f64 = nodes[i].children().map(|c| landed[c]).sum();
            landed[i] += below;
            let below: u32 = nodes[i].children().map(|c| landed_rays[c]).sum();
            landed_rays[i] += below;
        }
        let mut x = Self {
            onto_itself,
            between_children,
            landed,
            from_sibling,
            from_uncle,
            landed_rays,
            handed: Vec::new(),
        };
        let mut handed = vec![[1.0; 3]; nodes.len()];
        for p in 0..nodes.len() {
            for (slot, which) in [Landing::Mesh, Landing::Sibling, Landing::Outside]
                .into_iter()
                .enumerate()
            {
                for (c, r) in x.shrunk_ratios(tree, which, p) {
                    handed[c][slot] = r;
                }
            }
        }
        x.handed = handed;
        x
    }

    /// Approximate heap bytes held.
    pub fn bytes(&self) -> usize {
        (self.onto_itself.len()
            + self.between_children.len()
            + self.landed.len()
            + self.from_sibling.len()
            + self.from_uncle.len())
            * size_of::<f64>()
            + self.landed_rays.len() * size_of::<u32>()
            + self.handed.len() * size_of::<[f64; 3]>()
    }

    /// The traced light a node received, handed to its child `child` as push hands it (the ratios of
    /// [`Self::landing_ratio`], shrunk by their noise): its own and its ancestors' self-exchange (`traced`) by
    /// where the mesh's rays landed, what its sibling sent (`from_sibling`) by where the sibling's rays landed,
    /// and what its ancestors' siblings sent (`outside`) by where the rays from beyond its parent landed.
    /// Returns the child's `(traced, outside)`: what the sibling sent the parent comes from beyond the child's
    /// parent too.
    pub fn hand_down(&self, child: usize, [traced, from_sibling, outside]: [Rgb; 3]) -> (Rgb, Rgb) {
        let [mesh, sibling, beyond] = self.handed(child);
        (traced * mesh, from_sibling * sibling + outside * beyond)
    }

    /// The traced light `[traced, from_sibling, outside]` node `from` received, handed down the tree to its
    /// descendant `to` by the path's [`Self::hand_down`] steps, in all: where the solve stopped above the
    /// faces, each face below still takes its share by where the trace's rays landed, not the node's mean.
    /// The steps' ratios multiply, so the path is walked upward: the self-exchange takes every step's mesh
    /// ratio, the sibling's light the first step's sibling ratio, the rest every later step's outside ratio.
    pub fn hand_down_to(
        &self,
        tree: &FaceClusterTree,
        from: usize,
        to: usize,
        [traced, from_sibling, outside]: [Rgb; 3],
    ) -> Rgb {
        let (mut mesh, mut beyond_below_first, mut first) = (1.0, 1.0, [1.0; 3]);
        let mut n = to;
        while n != from {
            let Some(p) = tree.node(n).parent() else {
                return traced + from_sibling + outside; // `to` is not below `from`
            };
            let r = self.handed(n);
            mesh *= r[0];
            if p == from {
                first = r;
            } else {
                beyond_below_first *= r[2];
            }
            n = p;
        }
        traced * mesh + (from_sibling * first[1] + outside * first[2]) * beyond_below_first
    }

    /// The ratios (mesh, sibling, outside) by which light reaches `child` from its parent; one where nothing
    /// was traced.
    fn handed(&self, child: usize) -> [f64; 3] {
        self.handed.get(child).copied().unwrap_or([1.0; 3])
    }

    /// [`Self::landing_ratio`] of each child of `parent`, shrunk toward one by its noise: a ratio r from n
    /// landed rays has a relative standard deviation of about 1/√n, so its departure d = r − 1 is kept with
    /// weight d²/(d² + r²/n) (the Wiener filter's gain), and the children's shrunk ratios are rescaled so their
    /// area-weighted mean stays one (the parent's total kept). Pairs (child, ratio); none for a leaf.
    fn shrunk_ratios(
        &self,
        tree: &FaceClusterTree,
        which: Landing,
        parent: usize,
    ) -> Vec<(usize, f64)> {
        let parent_area = tree.node(parent).area;
        let shrunk: Vec<(usize, f64, f64)> = tree
            .node(parent)
            .children()
            .map(|c| {
                let ac = tree.node(c).area;
                let r = self.landing_ratio(which, parent, c, parent_area, ac);
                let n = self.landed_rays.get(c).copied().unwrap_or(0).max(1) as f64;
                let d = r - 1.0;
                let noise = r * r / n;
                let gain = if d * d + noise > 0.0 {
                    d * d / (d * d + noise)
                } else {
                    1.0
                };
                (c, 1.0 + gain * d, ac)
            })
            .collect();
        let total: f64 = shrunk.iter().map(|&(_, r, a)| r * a).sum();
        shrunk
            .into_iter()
            .map(|(c, r, _)| {
                (
                    c,
                    if total > 0.0 {
                        r * parent_area / total
                    } else {
                        r
                    },
                )
            })
            .collect()
    }

    /// The share of a traced exchange delivered evenly to `parent` that its child `child` takes per unit
    /// area, relative to the parent's: (L_C/A_C)/(L_P/A_P), with L the flux `which` says landed. Light a rough
    /// surface sends onto itself lands where more of the view is the surface itself, in its valleys rather
    /// than on its ridges ([`Landing::Mesh`]); what a sibling sends lands mostly near it, along their shared
    /// boundary ([`Landing::Sibling`]). The area-weighted mean of the children's ratios is one, so pushing by
    /// it keeps the node's total. One where nothing was traced.
    pub fn landing_ratio(
        &self,
        which: Landing,
        parent: usize,
        child: usize,
        parent_area: f64,
        child_area: f64,
    ) -> f64 {
        let at = |x: &[f64], n: usize| x.get(n).copied();
        let (p, c) = match which {
            Landing::Mesh => (at(&self.landed, parent), at(&self.landed, child)),
            Landing::Sibling => (at(&self.from_sibling, parent), at(&self.from_uncle, child)),
            Landing::Outside => {
                // Landed from beyond the node: all its landings less those from within.
                let beyond = |n: usize| Some(at(&self.landed, n)? - at(&self.onto_itself, n)?);
                (
                    beyond(parent)
                        .zip(at(&self.from_sibling, parent))
                        .map(|(b, s)| b - s),
                    beyond(child)
                        .zip(at(&self.from_sibling, child))
                        .zip(at(&self.from_uncle, child))
                        .map(|((b, s), u)| (b - s - u).max(0.0)),
                )
            }
        };
        match (p, c) {
            // Sums of many rays less sums of most of them: below 1e-9 of the node's landings (rounding),
            // nothing was traced from there.
            (Some(p), Some(c))
                if p > 1e-9 * at(&self.landed, parent).unwrap_or(0.0)
                    && p > 0.0
                    && child_area > 0.0 =>
            {
                (c / child_area) / (p / parent_area)
            }
            _ => 1.0,
        }
    }
}

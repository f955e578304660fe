//! Conversion of a binary BVH into a compressed 8-wide BVH (CwBvh; Ylitie, Karras & Laine 2017, "Efficient
//! incoherent ray traversal on GPUs through compressed wide BVHs", §3.1–3.2), on rayon threads.
//!
//! The same computation as obvhs 0.4's `bvh2_to_cwbvh`, whose two recursions run on one thread and took half
//! of the build of 10⁶ triangles. First the dynamic programme of Ylitie et al. (their Eq. 1–3): for every
//! binary node n and every number i + 1 ≤ 7 of subtrees it may hand to its wide parent, the SAH cost
//!
//! C(n, 1) = min(leaf: A(n) · p · P(n) if p(n) ≤ 3, internal: A(n) + min_k C(l, k) + C(r, 7 − k)),
//! C(n, i) = min(C(n, i − 1), min_k C(l, k) + C(r, i − k))   (distribute: the children split the slots),
//!
//! A the half area of the box, p(n) the primitives under n, P = 0.3 the primitive cost relative to a node;
//! a node's costs depend on its children's only, so the two subtrees of a node are costed on two threads
//! (`rayon::join`). Then the wide nodes are emitted top-down: each wide node takes the ≤ 8 subtrees the
//! decisions give it, orders them by ray octant (greedy assignment of Ylitie et al. §3.2) and quantises their
//! boxes to 8 bits. Where obvhs appends to growing arrays in depth-first order, here a counting pass first finds
//! how many wide nodes every subtree produces, so that each subtree's nodes and primitive slots are a known
//! range and subtrees are emitted on separate threads into disjoint slices (`split_at_mut`). Every number is
//! computed by the same operations in the same order as obvhs's serial code, so the result is the same CwBvh,
//! bit for bit, on any number of threads (tested against obvhs's).

use std::sync::atomic::{AtomicU16, AtomicU32, Ordering};

use glam::{UVec3, Vec3A, vec3a};
use obvhs::{
    PerComponent,
    bvh2::Bvh2,
    cwbvh::{CwBvh, node::CwBvhNode},
};
use rayon::prelude::*;

/// Primitive cost relative to a node visit (obvhs's value).
const PRIM_COST: f32 = 0.3;

/// 1 / 255: child boxes are quantised to 8 bits.
const DENOM: f32 = 1.0 / 255.0;

/// Binary subtrees are costed, counted and emitted on separate rayon tasks down to this depth (about 2¹⁴ tasks
/// for a balanced tree; deeper work stays on its task).
const PARALLEL_DEPTH: u32 = 14;

/// Wide levels emitted on separate rayon tasks (8⁵ ≈ 3·10⁴ tasks at most).
const PARALLEL_WIDE_DEPTH: u32 = 5;

/// What a binary node does with i + 1 slots of its wide parent.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    /// One wide leaf holding all its primitives.
    Leaf,
    /// One wide internal node.
    Internal,
    /// Its two children take `left + 1` and `right + 1` slots.
    Distribute,
}

/// One entry of the dynamic programme.
#[derive(Clone, Copy, Debug)]
struct Decision {
    cost: f32,
    kind: Kind,
    left: u8,
    right: u8,
}

const INVALID: u8 = u8::MAX;

impl Decision {
    /// Kind and slot split in 10 bits (a slot count 0..7, or [`INVALID`] as 15).
    fn meta(self) -> u16 {
        let kind = match self.kind {
            Kind::Leaf => 0u16,
            Kind::Internal => 1,
            Kind::Distribute => 2,
        };
        kind | u16::from(self.left.min(15)) << 2 | u16::from(self.right.min(15)) << 6
    }

    fn from_parts(cost: f32, meta: u16) -> Self {
        let slots = |x: u16| if x == 15 { INVALID } else { x as u8 };
        Self {
            cost,
            kind: match meta & 3 {
                0 => Kind::Leaf,
                1 => Kind::Internal,
                _ => Kind::Distribute,
            },
            left: slots((meta >> 2) & 15),
            right: slots((meta >> 6) & 15),
        }
    }
}

/// The decisions of every binary node (7 per node), written once each by the task that costs the node and
/// read after the costing has joined (relaxed atomics: the join orders them). Costs and the rest apart: the
/// costing reads only costs, the emission only the rest.
struct Decisions {
    cost: Vec<AtomicU32>,
    meta: Vec<AtomicU16>,
}

impl Decisions {
    fn new(nodes: usize) -> Self {
        Self {
            cost: (0..nodes * 7)
                .into_par_iter()
                .map(|_| AtomicU32::new(0))
                .collect(),
            meta: (0..nodes * 7)
                .into_par_iter()
                .map(|_| AtomicU16::new(0))
                .collect(),
        }
    }

    #[inline(always)]
    fn cost(&self, node: u32, i: usize) -> f32 {
        f32::from_bits(self.cost[node as usize * 7 + i].load(Ordering::Relaxed))
    }

    /// How many slots the node's children take when it has i + 1 (meaningful for a split).
    #[inline(always)]
    fn split(&self, node: u32, i: usize) -> (u8, u8) {
        let d = Decision::from_parts(
            0.0,
            self.meta[node as usize * 7 + i].load(Ordering::Relaxed),
        );
        (d.left, d.right)
    }

    #[inline(always)]
    fn kind(&self, node: u32, i: usize) -> Kind {
        Decision::from_parts(
            0.0,
            self.meta[node as usize * 7 + i].load(Ordering::Relaxed),
        )
        .kind
    }

    #[inline(always)]
    fn set(&self, node: u32, i: usize, d: Decision) {
        let k = node as usize * 7 + i;
        self.cost[k].store(d.cost.to_bits(), Ordering::Relaxed);
        self.meta[k].store(d.meta(), Ordering::Relaxed);
    }
}

struct Converter<'a> {
    bvh2: &'a Bvh2,
    max_prims_per_leaf: u32,
    decisions: Decisions,
    /// Per binary node: primitives under it.
    prims: Vec<AtomicU32>,
    /// Per binary node that becomes a wide internal node: wide nodes below it (not counting itself).
    below: Vec<AtomicU32>,
}

/// The ≤ 8 subtrees of a wide node (binary node indices) and their number.
type Children = ([u32; 8], usize);

impl Converter<'_> {
    /// The dynamic programme over the subtree of `n` (obvhs `calculate_cost_impl`); returns its primitive count.
    fn cost(&self, n: u32, depth: u32) -> u32 {
        let node = &self.bvh2.nodes[n as usize];
        let half_area = node.aabb().half_area();
        let num = if node.prim_count != 0 {
            assert!(
                node.prim_count == 1,
                "the wide BVH conversion expects binary leaves of one primitive"
            );
            let d = Decision {
                cost: half_area * (node.prim_count as f32) * PRIM_COST,
                kind: Kind::Leaf,
                left: 0,
                right: 0,
            };
            for i in 0..7 {
                self.decisions.set(n, i, d);
            }
            node.prim_count
        } else {
            let (l, r) = (node.first_index, node.first_index + 1);
            let (nl, nr) = if depth < PARALLEL_DEPTH {
                rayon::join(|| self.cost(l, depth + 1), || self.cost(r, depth + 1))
            } else {
                (self.cost(l, depth + 1), self.cost(r, depth + 1))
            };
            let num = nl + nr;
            let lc: [f32; 7] = std::array::from_fn(|k| self.decisions.cost(l, k));
            let rc: [f32; 7] = std::array::from_fn(|k| self.decisions.cost(r, k));
            let cost_leaf = if num <= self.max_prims_per_leaf {
                (num as f32) * half_area * PRIM_COST
            } else {
                f32::INFINITY
            };
            let (mut cost_distribute, mut dl, mut dr) = (f32::INFINITY, INVALID, INVALID);
            for k in 0..7 {
                let c = lc[k] + rc[6 - k];
                if c < cost_distribute {
                    (cost_distribute, dl, dr) = (c, k as u8, 6 - k as u8);
                }
            }
            let cost_internal = cost_distribute + half_area;
            let mut prev = if cost_leaf < cost_internal {
                Decision {
                    cost: cost_leaf,
                    kind: Kind::Leaf,
                    left: dl,
                    right: dr,
                }
            } else {
                Decision {
                    cost: cost_internal,
                    kind: Kind::Internal,
                    left: dl,
                    right: dr,
                }
            };
            self.decisions.set(n, 0, prev);
            for i in 1..7 {
                let (mut cost, mut dl, mut dr) = (prev.cost, INVALID, INVALID);
                for k in 0..i {
                    let c = lc[k] + rc[i - k - 1];
                    if c < cost {
                        (cost, dl, dr) = (c, k as u8, (i - k - 1) as u8);
                    }
                }
                if dl != INVALID {
                    prev = Decision {
                        cost,
                        kind: Kind::Distribute,
                        left: dl,
                        right: dr,
                    };
                }
                self.decisions.set(n, i, prev);
            }
            num
        };
        self.prims[n as usize].store(num, Ordering::Relaxed);
        num
    }

    /// The subtrees the wide node made from binary node `n` takes (obvhs `get_children`, slot order before
    /// ordering by octant).
    fn children(&self, n: u32) -> Children {
        let mut out = ([u32::MAX; 8], 0);
        self.collect(n, 0, &mut out);
        out
    }

    fn collect(&self, n: u32, i: usize, out: &mut Children) {
        let node = &self.bvh2.nodes[n as usize];
        if node.is_leaf() {
            out.0[out.1] = n;
            out.1 += 1;
            return;
        }
        let (left, right) = self.decisions.split(n, i);
        for (child, slots) in [(node.first_index, left), (node.first_index + 1, right)] {
            if self.decisions.kind(child, slots as usize) == Kind::Distribute {
                self.collect(child, slots as usize, out);
            } else {
                out.0[out.1] = child;
                out.1 += 1;
            }
        }
    }

    fn is_internal(&self, child: u32) -> bool {
        self.decisions.kind(child, 0) == Kind::Internal
    }

    /// Counts the wide nodes below the wide node made from `n`, storing the count for every wide internal node.
    fn count(&self, n: u32, depth: u32) -> u32 {
        let (children, count) = self.children(n);
        let internal = children[..count]
            .iter()
            .copied()
            .filter(|&c| self.is_internal(c));
        let below = if depth < PARALLEL_WIDE_DEPTH {
            internal
                .collect::<Vec<u32>>()
                .par_iter()
                .map(|&c| 1 + self.count(c, depth + 1))
                .sum()
        } else {
            internal.map(|c| 1 + self.count(c, depth + 1)).sum()
        };
        self.below[n as usize].store(below, Ordering::Relaxed);
        below
    }

    /// Orders the children by ray octant (obvhs `order_children`: greedy assignment of children to the octant
    /// slots of largest centroid offset along the octant's diagonal).
    fn order(&self, n: u32, children: &mut [u32; 8], count: usize) {
        let p = self.bvh2.nodes[n as usize].aabb().center();
        let mut cost = [[f32::MAX; 8]; 8];
        for (row, &child) in cost.iter_mut().zip(children.iter()).take(count) {
            let v = self.bvh2.nodes[child as usize].aabb().center() - p;
            for (s, c) in row.iter_mut().enumerate() {
                let d = vec3a(
                    if (s & 0b100) != 0 { -1.0 } else { 1.0 },
                    if (s & 0b010) != 0 { -1.0 } else { 1.0 },
                    if (s & 0b001) != 0 { -1.0 } else { 1.0 },
                );
                *c = d.dot(v);
            }
        }
        let mut assignment = [usize::MAX; 8];
        let mut filled = [false; 8];
        loop {
            let (mut min_cost, mut min_slot, mut min_index) = (f32::MAX, usize::MAX, usize::MAX);
            for c in 0..count {
                if assignment[c] == usize::MAX {
                    for (s, &f) in filled.iter().enumerate() {
                        if !f && cost[c][s] < min_cost {
                            (min_cost, min_slot, min_index) = (cost[c][s], s, c);
                        }
                    }
                }
            }
            if min_slot == usize::MAX {
                break;
            }
            filled[min_slot] = true;
            assignment[min_index] = min_slot;
        }
        let original = std::mem::replace(children, [u32::MAX; 8]);
        for c in 0..count {
            children[assignment[c]] = original[c];
        }
    }

    /// Writes the primitives under binary node `n`, depth first, left before right, into `out`.
    fn leaf_primitives(&self, n: u32, out: &mut [u32]) -> usize {
        let node = &self.bvh2.nodes[n as usize];
        if node.is_leaf() {
            out[0] = self.bvh2.primitive_indices[node.first_index as usize];
            return 1;
        }
        let k = self.leaf_primitives(node.first_index, out);
        k + self.leaf_primitives(node.first_index + 1, &mut out[k..])
    }

    /// Emits the wide node made from binary node `n` into `slot`, its descendants into `below` (which starts
    /// at wide index `below_start`) and its primitives into `prims` (starting at `prim_start`) (obvhs
    /// `convert_to_cwbvh_impl`).
    #[allow(clippy::too_many_arguments)]
    fn emit(
        &self,
        n: u32,
        slot: &mut CwBvhNode,
        below: &mut [CwBvhNode],
        below_start: u32,
        prims: &mut [u32],
        prim_start: u32,
        depth: u32,
    ) {
        let aabb = self.bvh2.nodes[n as usize].aabb();
        let mut node = CwBvhNode {
            p: aabb.min.into(),
            ..Default::default()
        };
        let e = ((aabb.max - aabb.min).max(Vec3A::splat(1e-20)) * DENOM)
            .log2()
            .ceil()
            .exp2();
        let rcp_e = 1.0 / e;
        let e: UVec3 = e.per_comp(|c: f32| c.to_bits() >> 23);
        node.e = [e.x as u8, e.y as u8, e.z as u8];
        let (mut children, count) = self.children(n);
        self.order(n, &mut children, count);
        node.imask = 0;
        node.primitive_base_idx = prim_start;
        node.child_base_idx = below_start;
        let mut num_internal = 0usize;
        let mut num_prims = 0u32;
        for (i, &c) in children.iter().enumerate() {
            if c == u32::MAX {
                continue;
            }
            let child_aabb = self.bvh2.nodes[c as usize].aabb();
            let lo = ((child_aabb.min - aabb.min) * rcp_e)
                .floor()
                .clamp(Vec3A::ZERO, Vec3A::splat(255.0));
            let hi = ((child_aabb.max - aabb.min) * rcp_e)
                .ceil()
                .clamp(Vec3A::ZERO, Vec3A::splat(255.0));
            node.child_min_x[i] = lo.x as u8;
            node.child_min_y[i] = lo.y as u8;
            node.child_min_z[i] = lo.z as u8;
            node.child_max_x[i] = hi.x as u8;
            node.child_max_y[i] = hi.y as u8;
            node.child_max_z[i] = hi.z as u8;
            if self.is_internal(c) {
                node.imask |= 1u8 << i;
                node.child_meta[i] = (24 + i as u8) | 0b0010_0000;
                num_internal += 1;
            } else {
                let k = self.leaf_primitives(c, &mut prims[num_prims as usize..]) as u32;
                assert!((1..=3).contains(&k), "a wide leaf holds 1 to 3 primitives");
                node.child_meta[i] = num_prims as u8
                    | match k {
                        1 => 0b0010_0000,
                        2 => 0b0110_0000,
                        _ => 0b1110_0000,
                    };
                num_prims += k;
            }
        }
        *slot = node;
        // The wide children's slots, then each one's descendants and primitives, in slot order.
        let (block, mut rest) = below.split_at_mut(num_internal);
        let mut prims_rest = &mut prims[num_prims as usize..];
        let mut next_below = below_start + num_internal as u32;
        let mut next_prim = prim_start + num_prims;
        let mut tasks = Vec::with_capacity(num_internal);
        let internal = children
            .iter()
            .copied()
            .filter(|&c| c != u32::MAX && self.is_internal(c));
        for (c, child_slot) in internal.zip(block.iter_mut()) {
            let nb = self.below[c as usize].load(Ordering::Relaxed);
            let np = self.prims[c as usize].load(Ordering::Relaxed);
            let (b, r) = std::mem::take(&mut rest).split_at_mut(nb as usize);
            rest = r;
            let (p, pr) = std::mem::take(&mut prims_rest).split_at_mut(np as usize);
            prims_rest = pr;
            tasks.push((c, child_slot, b, next_below, p, next_prim));
            next_below += nb;
            next_prim += np;
        }
        let run = |(c, child_slot, b, bs, p, ps): (
            u32,
            &mut CwBvhNode,
            &mut [CwBvhNode],
            u32,
            &mut [u32],
            u32,
        )| { self.emit(c, child_slot, b, bs, p, ps, depth + 1) };
        if depth < PARALLEL_WIDE_DEPTH {
            tasks.into_par_iter().for_each(run);
        } else {
            tasks.into_iter().for_each(run);
        }
    }
}

/// The CwBvh of `bvh2` (binary leaves of one primitive each), with wide leaves of at most `max_prims_per_leaf`
/// (1 to 3) primitives and children ordered by octant: obvhs 0.4's `bvh2_to_cwbvh(bvh2, max_prims_per_leaf,
/// true, false)`, bit for bit, on the calling rayon pool.
pub(crate) fn bvh2_to_cwbvh(bvh2: &Bvh2, max_prims_per_leaf: u32) -> CwBvh {
    if bvh2.nodes.is_empty() {
        return CwBvh::default();
    }
    let len = bvh2.nodes.len();
    let conv = Converter {
        bvh2,
        max_prims_per_leaf: max_prims_per_leaf.clamp(1, 3),
        decisions: Decisions::new(len),
        prims: (0..len)
            .into_par_iter()
            .map(|_| AtomicU32::new(0))
            .collect(),
        below: (0..len)
            .into_par_iter()
            .map(|_| AtomicU32::new(0))
            .collect(),
    };
    let total_prims = conv.cost(0, 0);
    let below = conv.count(0, 0);
    let mut nodes = vec![CwBvhNode::default(); 1 + below as usize];
    let mut primitive_indices = vec![0u32; total_prims as usize];
    let (root, rest) = nodes.split_at_mut(1);
    conv.emit(0, &mut root[0], rest, 1, &mut primitive_indices, 0, 0);
    CwBvh {
        nodes,
        primitive_indices,
        total_aabb: *bvh2.nodes[0].aabb(),
        exact_node_aabbs: None,
        uses_spatial_splits: bvh2.uses_spatial_splits,
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use obvhs::{BvhBuildParams, aabb::Aabb, ploc::PlocBuilder, triangle::Triangle};
    use radlab_scene::sampling;

    /// At least `count` random triangles of unit size in a cube of side `spread` (stream `seed`), every
    /// `repeat_every`-th one repeated exactly, so that boxes and Morton codes tie.
    pub(crate) fn random_triangles(
        seed: u64,
        count: usize,
        spread: f32,
        repeat_every: usize,
    ) -> Vec<Triangle> {
        let mut r = sampling::rng(seed, 0);
        let mut tris: Vec<Triangle> = Vec::new();
        while tris.len() < count {
            let mut p = || {
                Vec3A::new(
                    sampling::uniform(&mut r) as f32,
                    sampling::uniform(&mut r) as f32,
                    sampling::uniform(&mut r) as f32,
                )
            };
            let c = spread * p();
            let t = Triangle {
                v0: c,
                v1: c + p(),
                v2: c + p(),
            };
            tris.push(t);
            if tris.len().is_multiple_of(repeat_every) {
                tris.push(t);
            }
        }
        tris
    }

    /// The same CwBvh as obvhs's serial conversion, node for node and primitive for primitive, on 1 and 2
    /// threads, for every leaf size, on random triangles (some repeated, so that boxes tie) after PLOC and
    /// reinsertion.
    #[test]
    fn same_wide_bvh_as_obvhs_on_any_number_of_threads() {
        let tris = random_triangles(7, 30_000, 40.0, 9);
        let params = BvhBuildParams::fast_build();
        let boxes: Vec<Aabb> = tris.iter().map(Triangle::aabb).collect();
        let mut bvh2 = PlocBuilder::with_capacity(boxes.len()).build(
            params.ploc_search_distance,
            &boxes,
            (0..tris.len() as u32).collect(),
            params.sort_precision,
            params.search_depth_threshold,
        );
        obvhs::bvh2::reinsertion::ReinsertionOptimizer::default().run(
            &mut bvh2,
            params.reinsertion_batch_ratio,
            None,
        );
        for max_prims in 1..=3 {
            let expected =
                obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh(&bvh2, max_prims, true, false);
            for threads in [1, 2] {
                let got = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .expect("pool")
                    .install(|| bvh2_to_cwbvh(&bvh2, max_prims));
                assert_eq!(got.nodes.len(), expected.nodes.len());
                assert!(
                    got == expected,
                    "max_prims {max_prims}, {threads} threads: differs from obvhs"
                );
            }
        }
    }
}

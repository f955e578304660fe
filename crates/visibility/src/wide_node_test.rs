//! The ray–box test of a compressed 8-wide BVH node (Ylitie, Karras & Laine 2017, "Efficient incoherent
//! ray traversal on GPUs through compressed wide BVHs", §3.3) for all eight children at once in AVX2 lanes.
//!
//! A child's box is stored as 8-bit planes q on the node's grid (origin p, per-axis scale e = 2^k), and the
//! slab test (Kay & Kajiya 1986) runs in the grid's units: per axis, t(q) = q · (e / d) + (p − o) / d, with
//! the near and far planes swapped on the axes where the ray's direction is negative; the child is hit
//! when max(t_near,x, t_near,y, t_near,z, ε) ≤ min(t_far,x, t_far,y, t_far,z, t_max), ε the 1e-4 of obvhs's
//! node test. Each hit child sets its bits in the traversal's hit mask (its unary primitive count shifted to
//! its primitive offset for a leaf, one bit at its octant-ordered slot for an inner node).
//!
//! obvhs 0.4's own test (`CwBvhNode::intersect_ray_simd`) does the same arithmetic four children at a time in
//! SSE, converting the 8-bit planes one scalar at a time; this one widens them with one instruction per
//! plane set. Every lane computes the same IEEE operations in the same order (a multiply and an add, never
//! fused; max and min with the same operand order, so NaNs fall the same way), so the two tests return the
//! same mask bit for bit, and a traversal visits the same nodes in the same order with either. `Accel`
//! chooses this one at run time where the processor has AVX2, through pulp's safe intrinsics
//! and its `V3::vectorize`, which compiles the traversal with AVX2 enabled.

use obvhs::{cwbvh::node::CwBvhNode, ray::Ray};

#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::{__m256, __m256i, _CMP_LE_OQ};

/// obvhs's lower bound on a child's entry distance (its `cwbvh::node::EPSILON`, which is private).
#[cfg(target_arch = "x86_64")]
const NODE_EPSILON: f32 = 0.0001;

/// Which node test a traversal uses; the traversals are generic over it, so each is compiled for its test.
pub(crate) trait NodeTest: Copy {
    /// The hit mask of `node`'s children for `ray` (as `CwBvhNode::intersect_ray`).
    fn hits(self, node: &CwBvhNode, ray: &Ray, oct_inv4: u32) -> u32;

    /// The children `ray` hits as slots: bit i set when child slot i is occupied and its box is hit (the
    /// same children as [`NodeTest::hits`], in storage order rather than the traversal's bit layout).
    fn slot_hits(self, node: &CwBvhNode, ray: &Ray, oct_inv4: u32) -> u32;
}

/// The occupied child slots of `node` (an empty slot's meta byte is 0).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn occupied(node: &CwBvhNode) -> u32 {
    node.child_meta
        .iter()
        .enumerate()
        .fold(0, |m, (i, &meta)| m | (u32::from(meta != 0) << i))
}

/// obvhs's own test (SSE on x86-64, scalar elsewhere).
#[derive(Clone, Copy)]
pub(crate) struct Portable;

impl NodeTest for Portable {
    #[inline(always)]
    fn hits(self, node: &CwBvhNode, ray: &Ray, oct_inv4: u32) -> u32 {
        node.intersect_ray(ray, oct_inv4)
    }

    #[inline(always)]
    fn slot_hits(self, node: &CwBvhNode, ray: &Ray, oct_inv4: u32) -> u32 {
        // Each occupied slot owns distinct bits of the mask: its unary primitive count at its primitive
        // offset (a leaf), or one bit at its octant-ordered index (an inner node).
        let mask = node.intersect_ray(ray, oct_inv4);
        let (child_bits8, bit_index8) = node.get_child_and_index_bits(oct_inv4);
        (0..8).fold(0, |m, i| {
            let bits = ((child_bits8 >> (8 * i)) & 0xff) << ((bit_index8 >> (8 * i)) & 0xff);
            m | (u32::from(mask as u64 & bits != 0) << i)
        })
    }
}

/// The eight-lane AVX2 test, holding pulp's proof that the processor has AVX2 (`V3`, obtained only where it
/// does). Its intrinsics compile to AVX2 instructions inside `V3::vectorize`, where traversals run it.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
pub(crate) struct Avx2(pub(crate) pulp::x86::V3);

#[cfg(target_arch = "x86_64")]
impl NodeTest for Avx2 {
    #[inline(always)]
    fn hits(self, node: &CwBvhNode, ray: &Ray, oct_inv4: u32) -> u32 {
        let pulp::x86::V3 {
            sse2, avx, avx2, ..
        } = self.0;
        let hit = self.hit_lanes(node, ray);
        // Each hit child's bits shifted to its index, OR-ed over the lanes.
        let (child_bits8, bit_index8) = node.get_child_and_index_bits(oct_inv4);
        let bytes = |x: u64| avx2._mm256_cvtepu8_epi32(sse2._mm_set_epi64x(0, x as i64));
        let lanes = avx2._mm256_and_si256(
            avx2._mm256_sllv_epi32(bytes(child_bits8), bytes(bit_index8)),
            hit,
        );
        let x = sse2._mm_or_si128(
            avx._mm256_castsi256_si128(lanes),
            avx2._mm256_extracti128_si256::<1>(lanes),
        );
        let x = sse2._mm_or_si128(x, sse2._mm_shuffle_epi32::<0b01_00_11_10>(x));
        let x = sse2._mm_or_si128(x, sse2._mm_shuffle_epi32::<0b10_11_00_01>(x));
        sse2._mm_cvtsi128_si32(x) as u32
    }

    #[inline(always)]
    fn slot_hits(self, node: &CwBvhNode, ray: &Ray, _oct_inv4: u32) -> u32 {
        let hit = self.hit_lanes(node, ray);
        self.0
            .avx
            ._mm256_movemask_ps(self.0.avx._mm256_castsi256_ps(hit)) as u32
            & occupied(node)
    }
}

#[cfg(target_arch = "x86_64")]
impl Avx2 {
    /// The slab test of the eight children: all ones in lane i where child slot i's box is hit.
    #[inline(always)]
    fn hit_lanes(self, node: &CwBvhNode, ray: &Ray) -> __m256i {
        let pulp::x86::V3 {
            sse2, avx, avx2, ..
        } = self.0;
        let inv = node.compute_extent() * ray.inv_direction;
        let org = (glam::Vec3A::from(node.p) - ray.origin) * ray.inv_direction;
        // The eight 8-bit planes of one kind as f32 lanes (exact: integers below 256), and eight bytes as
        // 32-bit lanes.
        let bytes = |x: u64| avx2._mm256_cvtepu8_epi32(sse2._mm_set_epi64x(0, x as i64));
        let widen = |q: [u8; 8]| -> __m256 { avx._mm256_cvtepi32_ps(bytes(u64::from_le_bytes(q))) };
        // Per axis: the entry and exit distances of the planes the ray meets first and last.
        let axis = |lo: [u8; 8], hi: [u8; 8], negative: bool, inv: f32, org: f32| {
            let (near, far) = if negative { (hi, lo) } else { (lo, hi) };
            let (inv, org) = (avx._mm256_set1_ps(inv), avx._mm256_set1_ps(org));
            (
                avx._mm256_add_ps(avx._mm256_mul_ps(widen(near), inv), org),
                avx._mm256_add_ps(avx._mm256_mul_ps(widen(far), inv), org),
            )
        };
        let d = ray.direction;
        let (nx, fx) = axis(node.child_min_x, node.child_max_x, d.x < 0.0, inv.x, org.x);
        let (ny, fy) = axis(node.child_min_y, node.child_max_y, d.y < 0.0, inv.y, org.y);
        let (nz, fz) = axis(node.child_min_z, node.child_max_z, d.z < 0.0, inv.z, org.z);
        let tmin = avx._mm256_max_ps(nx, avx._mm256_max_ps(ny, nz));
        let tmax = avx._mm256_min_ps(fx, avx._mm256_min_ps(fy, fz));
        let tmin = avx._mm256_max_ps(tmin, avx._mm256_set1_ps(NODE_EPSILON));
        let tmax = avx._mm256_min_ps(tmax, avx._mm256_set1_ps(ray.tmax));
        avx._mm256_castps_si256(avx._mm256_cmp_ps::<_CMP_LE_OQ>(tmin, tmax))
    }
}

/// The AVX2 test where the processor has AVX2 (pulp's `V3` set: AVX2, FMA, BMI1/2, LZCNT).
pub(crate) fn avx2_test() -> Option<Avx2Test> {
    #[cfg(target_arch = "x86_64")]
    {
        pulp::x86::V3::try_new().map(Avx2)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        None
    }
}

/// The AVX2 test's type, or `()` where there is none.
#[cfg(target_arch = "x86_64")]
pub(crate) type Avx2Test = Avx2;
#[cfg(not(target_arch = "x86_64"))]
pub(crate) type Avx2Test = ();

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;
    use glam::Vec3A;
    use radlab_scene::sampling;

    /// The AVX2 test returns obvhs's mask for every node of a BVH over random triangles and random rays,
    /// including rays along axes (infinite inverse directions), rays starting inside boxes, and short rays; and
    /// both tests give the same hit children as slots.
    #[test]
    fn avx2_masks_equal_obvhs() {
        let Some(avx2) = avx2_test() else {
            eprintln!("no AVX2 on this processor: nothing to compare");
            return;
        };
        let tris = crate::cwbvh_convert::tests::random_triangles(3, 4000, 10.0, 0);
        let bvh = obvhs::cwbvh::builder::build_cwbvh_from_tris(
            &tris,
            obvhs::BvhBuildParams::fast_build(),
            &mut std::time::Duration::default(),
        );
        let mut rng = sampling::rng(11, 0);
        let mut range = |lo: f32, hi: f32| lo + (hi - lo) * sampling::uniform(&mut rng) as f32;
        let mut compared = 0usize;
        let mut nonzero = 0usize;
        for r in 0..3000 {
            let o = Vec3A::new(range(-2.0, 14.0), range(-2.0, 14.0), range(-2.0, 14.0));
            let mut d = Vec3A::new(range(-1.0, 1.0), range(-1.0, 1.0), range(-1.0, 1.0));
            // Some rays along an axis or in a coordinate plane.
            match r % 7 {
                0 => d = Vec3A::new(d.x, 0.0, 0.0),
                1 => d.y = 0.0,
                2 => d.z = -0.0,
                _ => {}
            }
            if d.length() == 0.0 {
                continue;
            }
            let tmax = if r % 3 == 0 {
                f32::INFINITY
            } else {
                range(0.0, 20.0)
            };
            let ray = Ray::new(o, d.normalize(), 0.0, tmax);
            let oct = bvh.new_traversal(ray.direction).oct_inv4;
            for node in &bvh.nodes {
                let want = node.intersect_ray(&ray, oct);
                let got = avx2.0.vectorize(|| avx2.hits(node, &ray, oct));
                assert_eq!(got, want, "ray {r}: node masks differ");
                // The same children as slots, from either test (packets use these).
                let slots = Portable.slot_hits(node, &ray, oct);
                let got = avx2.0.vectorize(|| avx2.slot_hits(node, &ray, oct));
                assert_eq!(got, slots, "ray {r}: slot masks differ");
                assert_eq!(
                    slots == 0,
                    want == 0,
                    "ray {r}: slots {slots:b}, mask {want:b}"
                );
                compared += 1;
                nonzero += (want != 0) as usize;
            }
        }
        // The comparison is not vacuous: thousands of nodes are hit (about 1% of the pairs).
        assert!(
            compared > 1_000_000 && nonzero > 5_000,
            "{compared} {nonzero}"
        );
    }
}

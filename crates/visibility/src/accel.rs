//! Ray casting over the scene's faces: closest hit and point-to-point visibility, on an obvhs compressed
//! wide BVH (CwBvh, Ylitie et al. 2017) built with PLOC and reinsertion (obvhs's parallel build) and converted
//! to the wide BVH on rayon tasks (`cwbvh_convert`): the same BVH on any number of rayon threads.
//!
//! Two stages per candidate triangle. The BVH and a first triangle test run in f32 on coordinates normalised
//! to the scene's bounds (centre at 0, diagonal [`NORMALISED_DIAGONAL`]), so their precision is relative to the
//! scene's size and independent of its scale and position. The f32 test is a loose filter (barycentric
//! tolerance [`F32_FILTER_BARY`]; ray origin moved back by [`F32_FILTER_SHIFT`], because obvhs's node test
//! skips boxes the ray leaves within 1e-4 units of its origin, which would drop touching surfaces; primitive
//! boxes padded by [`BOX_PAD_REL`]). The answer is then decided in f64 against the triangle's exact plane,
//! as below; but wherever conservative bounds on the f32 test's rounding errors prove that the ray's line
//! crosses the triangle's interior, or passes it farther than 2τ outside, the f64 edge test (and the vertex
//! fetch it needs) is skipped, since its answer is then known (`f32_filter`). Only lines within the f32
//! error bound of an edge, a small fraction of the candidates, reach the f64 edge test, so answers are those
//! of the f64 test, bit for bit, at mostly f32 cost. The f32 triangles (with their faces) and the f64 planes
//! are stored in the BVH's leaf order, so a leaf's candidates are side by side in memory.
//!
//! - s = signed distance of the ray origin from the plane (positive in front), τ = [`PLANE_TOL_REL`] × diagonal.
//!   A surface the origin lies on (|s| ≤ τ, origin in the closed polygon) is hit at t = 0 only if the ray
//!   enters its back: a ray leaving a floor under a box resting on it meets the box's bottom, and a ray from a
//!   point exactly on an edge or corner of an enclosure that heads through a neighbouring wall hits that wall
//!   instead of leaking (the price: a ray from exactly the foot line of a box, leaving it upwards, meets the
//!   box's bottom edge at t = 0). Otherwise that surface is ignored, so a point on a surface never hits
//!   itself or its coplanar neighbours. Elsewhere the hit is at t = −s/(n·d) when the ray approaches the plane.
//! - A segment between `p` and `q` is occluded only by a surface whose plane it crosses between its ends, both
//!   ends farther than τ from the plane: surfaces that a segment only touches at an end (the surfaces its ends
//!   lie on, shared edges, touching objects) never occlude it.
//! - The hit point must lie in the triangle within τ (edge functions in f64), so rays through shared edges and
//!   quad diagonals hit one of the neighbours rather than slipping between them.
//!
//! The BVH's node test (the slab test of a node's eight children) is obvhs's SSE test, or, where the processor
//! has AVX2, the same arithmetic in eight lanes ([`NodeTestKind`]): the same hit masks bit for bit, so the same
//! traversal and answers either way.
//!
//! The distance of a hit is therefore exact to f64 rounding, and surfaces a millionth of the scene's size
//! apart are told apart at any scale. Quads are split into two triangles; each triangle maps back to its face.
//! Every ray cast is counted, exactly and whatever the number of threads, so solvers can report rays in
//! their stats: each thread adds to a counter slot of its own (on its own cache line, so that threads never
//! contend for one line, and with an ordinary add, not a locked one), and [`Accel::rays_cast`] sums the slots.
//! `Accel` is `Sync`: cast from any number of rayon threads.
//!
//! Segments that share most of their way down the BVH (a form factor's rays between two patches, a point's
//! rays to a polygon) can be traversed together as a packet ([`Accel::visible_many`]; ray packets after Wald,
//! Slusallek, Benthin & Wagner 2001): each node is fetched once for the segments that reach it, each of them is
//! tested against its children with the same node test as alone, and a node reached by one segment only is
//! left to that segment's own traversal. Each segment meets the same triangles as alone, so its answer is the
//! same, and it counts as one ray.

use std::cell::Cell;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::time::Duration;

use glam::{DVec3, UVec2, Vec3A, Vec4};
use obvhs::{
    BvhBuildParams, aabb::Aabb, bvh2::reinsertion::ReinsertionOptimizer, cwbvh::CwBvh,
    ploc::PlocBuilder, ray::Ray as BvhRay, splits::split_aabbs_preset, triangle::Triangle,
};

use rayon::prelude::*;
use smallvec::SmallVec;

use crate::wide_node_test::{NodeTest, Portable};
use radlab_scene::{FaceId, Ray, Scene};

/// The closest surface a ray hits.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// The face hit.
    pub face: FaceId,
    /// Distance along the ray.
    pub t: f64,
    /// The hit point, `origin + t dir`, on the plane of the triangle hit (to f64 rounding).
    pub point: DVec3,
}

/// A segment for [`Accel::visible_many`]: from `p` on face `fp` to `q` on face `fq`, the two end faces
/// ignored as in [`Accel::visible_between`] (`usize::MAX` for a point on no face).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// First end.
    pub p: DVec3,
    /// The face `p` lies on.
    pub fp: FaceId,
    /// Second end.
    pub q: DVec3,
    /// The face `q` lies on.
    pub fq: FaceId,
}

/// Most segments one packet traversal of [`Accel::visible_many`] carries (one bit each in a `u32`).
pub const PACKET_SEGMENTS: usize = 32;

/// What one ray's traversal visited: BVH nodes whose children's boxes were tested against the ray, and
/// triangles tested (leaf primitives; with spatial splits a triangle may be tested more than once).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraversalCost {
    /// Nodes visited (each tests up to 8 child boxes).
    pub nodes: u32,
    /// Triangles tested.
    pub triangles: u32,
}

/// BVH build quality. `benches/rays.rs` measures the three on enclosures (rays leaving surface points):
/// the Cornell box tessellated to 4·10⁴ triangles and a closed room with a bumped sphere of 10⁵ and 10⁶
/// triangles. There all three presets visit the same number of nodes and triangles per ray (3.3–9.7 nodes,
/// 4.2–4.7 triangles per closest hit, within 3% of each other) and cast rays at the same rate within the
/// machine's noise, while `Quality` builds 5–13 times slower than `Fast` (20 s against 1.6 s for 10⁶
/// triangles) and `Medium` 1.1–1.4 times. Only the 38-triangle Cornell box shows a difference (`Quality`
/// visits 30% fewer nodes than `Fast`). So `Fast` is the default. `VeryFast` (added later) builds quicker
/// with about the same traversal cost (see its entry); `Fast` stays the default so that the BVH, and with it
/// the face a ray through a shared edge reports, does not change under existing results.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AccelPreset {
    /// obvhs `very_fast_build`: PLOC pairing nearest neighbours only (search distance 1) and a lighter
    /// reinsertion pass: about a quarter less PLOC time than `Fast` at 10⁶ triangles, with the same nodes and
    /// triangles per ray on the bumped spheres (within 2%) and 5–9% more nodes on the tessellated Cornell box.
    VeryFast,
    /// obvhs `fast_build`: the default.
    #[default]
    Fast,
    /// obvhs `medium_build`: about as quick to build as `Fast`.
    Medium,
    /// obvhs `very_slow_build` (spatial pre-splits, full reinsertion): slow to build.
    Quality,
}

impl AccelPreset {
    fn params(self) -> BvhBuildParams {
        match self {
            AccelPreset::VeryFast => BvhBuildParams::very_fast_build(),
            AccelPreset::Fast => BvhBuildParams::fast_build(),
            AccelPreset::Medium => BvhBuildParams::medium_build(),
            AccelPreset::Quality => BvhBuildParams::very_slow_build(),
        }
    }
}

/// The ray–box test of the BVH's 8-wide nodes. Both give the same hit masks, bit for bit, so the same
/// answers and traversal costs; they differ only in speed. [`Accel::new`] takes `Avx2` where the processor
/// has it; benchmarks switch with [`Accel::set_node_test`] to time the two side by side.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NodeTestKind {
    /// obvhs's own test: SSE, four children at a time, its 8-bit planes converted one by one.
    Portable,
    /// All eight children in AVX2 lanes, the planes widened in one instruction per set.
    Avx2,
}

/// Plane tolerance τ relative to the scene's bounding diagonal. A point within τ of a triangle's plane lies on
/// it (it never hits it, except by entering its back; segments ending there are not occluded by it), and a
/// hit point may lie up to τ outside a triangle's edges. f64 positions resolve about 1e-16 of their
/// magnitude, which leaves room for points computed on faces (interpolated, or hits snapped to planes), while
/// surfaces 1e-6 of the scene apart are still told apart by a factor 1000.
pub const PLANE_TOL_REL: f64 = 1e-9;

/// Barycentric slack of the f32 filter test. The filter only has to keep every true hit (f64 decides), and
/// f32 barycentrics of a triangle 1e-3 of the scene's size are good to about 1e-4.
pub const F32_FILTER_BARY: f32 = 1e-3;

/// The scene's bounding diagonal in the f32 coordinates the BVH is built in. obvhs's node test skips boxes
/// that the ray leaves within 1e-4 units of its origin (a fixed epsilon in `cwbvh::node`): at this size that
/// is 1e-7 of the scene, whatever the scene's own units.
pub const NORMALISED_DIAGONAL: f64 = 1e3;

/// How far back, relative to the scene's diagonal, the f32 filter ray starts, so that surfaces at distance
/// ≈ 0 from the true origin lie 100 times beyond obvhs's node epsilon. Also the slack on the filter's
/// maximum distance.
pub const F32_FILTER_SHIFT: f64 = 1e-5;

/// Padding of every primitive box, relative to the scene's diagonal (about 30 f32 ulps at the scene's edge).
/// A flat box (the triangles of one wall) has no thickness of its own: a ray through the box's edge at the
/// very point where it meets the wall, as rays from points on shared edges do, would otherwise slip past it.
pub const BOX_PAD_REL: f64 = 1e-6;

/// The BVH over `tris`: obvhs's PLOC build (optionally with spatial pre-splits), reinsertion and conversion to
/// a CwBvh (on rayon threads: `cwbvh_convert`), over primitive boxes padded by [`BOX_PAD_REL`] (the steps of obvhs's `build_cwbvh_from_tris`,
/// which offers no padding).
fn build_bvh(tris: &[Triangle], params: BvhBuildParams) -> CwBvh {
    let mut boxes: Vec<Aabb> = tris.par_iter().map(Triangle::aabb).collect();
    let mut indices: Vec<u32> = (0..tris.len() as u32).collect();
    if params.pre_split && !tris.is_empty() {
        let (largest, sum) = boxes.iter().fold((0f32, 0f32), |(l, s), b| {
            let h = b.half_area();
            (l.max(h), s + h)
        });
        split_aabbs_preset(
            &mut boxes,
            &mut indices,
            tris,
            sum / tris.len() as f32,
            largest,
        );
    }
    let pad = Vec3A::splat((BOX_PAD_REL * NORMALISED_DIAGONAL) as f32);
    boxes.par_iter_mut().for_each(|b| {
        b.min -= pad;
        b.max += pad;
    });
    let mut bvh2 = PlocBuilder::with_capacity(boxes.len()).build(
        params.ploc_search_distance,
        &boxes,
        indices,
        params.sort_precision,
        params.search_depth_threshold,
    );
    bvh2.uses_spatial_splits = params.pre_split;
    ReinsertionOptimizer::default().run(&mut bvh2, params.reinsertion_batch_ratio, None);
    // The same CwBvh either way: obvhs's serial conversion is the quicker on one thread and for small
    // scenes, ours (its recursions split over rayon tasks) for large ones on more threads.
    let max_prims = params.max_prims_per_leaf.clamp(1, 3);
    if rayon::current_num_threads() > 1 && tris.len() >= PARALLEL_CONVERSION_MIN {
        crate::cwbvh_convert::bvh2_to_cwbvh(&bvh2, max_prims)
    } else {
        obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh(&bvh2, max_prims, true, false)
    }
}

/// Fewest triangles for which the wide BVH conversion runs on rayon tasks (below, rayon's overhead is
/// comparable with the serial conversion's fraction of a millisecond).
const PARALLEL_CONVERSION_MIN: usize = 4096;

/// Number of ray-counter slots ([`RayCounter`]): the first `COUNTER_SLOTS - 1` threads to cast a ray get one
/// each, alone; later threads share the last.
const COUNTER_SLOTS: usize = 64;

/// The slot that threads beyond the first `COUNTER_SLOTS - 1` share.
const SHARED_SLOT: usize = COUNTER_SLOTS - 1;

/// One counter slot, alone on its cache line pair (128 bytes: adjacent-line prefetchers fetch lines in pairs).
#[derive(Default)]
#[repr(align(128))]
struct CounterSlot(AtomicU64);

/// The slot of the calling thread: threads take slots in the order they first cast a ray, each of the first
/// [`SHARED_SLOT`] a slot of its own for the life of the process, the rest [`SHARED_SLOT`].
#[inline(always)]
fn counter_slot() -> usize {
    static NEXT: AtomicUsize = AtomicUsize::new(0);
    thread_local! {
        // `usize::MAX` until the thread first casts a ray (a constant initialiser: no lazy-init check on the
        // hot path beyond this comparison).
        static SLOT: Cell<usize> = const { Cell::new(usize::MAX) };
    }
    SLOT.with(|s| {
        let slot = s.get();
        if slot != usize::MAX {
            return slot;
        }
        let slot = NEXT.fetch_add(1, Ordering::Relaxed).min(SHARED_SLOT);
        s.set(slot);
        slot
    })
}

/// An exact count over all threads without a shared per-ray atomic: each thread adds to its own slot, and the
/// total is the sum of the slots. A slot of one thread alone is only ever written by that thread, so it adds
/// with a plain load and store (relaxed atomics, no locked read-modify-write); the shared slot adds with
/// `fetch_add`. A shared counter costs a cache-line transfer between cores per ray, a locked add on a private
/// line some twenty cycles; this one costs an ordinary add.
struct RayCounter {
    slots: Box<[CounterSlot]>,
}

impl RayCounter {
    fn new() -> Self {
        Self {
            slots: (0..COUNTER_SLOTS).map(|_| CounterSlot::default()).collect(),
        }
    }

    #[inline(always)]
    fn add_one(&self) {
        self.add(1);
    }

    #[inline(always)]
    fn add(&self, rays: u64) {
        let slot = counter_slot();
        let counter = &self.slots[slot].0;
        if slot == SHARED_SLOT {
            counter.fetch_add(rays, Ordering::Relaxed);
        } else {
            // No other thread writes this slot: the load sees this thread's own last store.
            counter.store(counter.load(Ordering::Relaxed) + rays, Ordering::Relaxed);
        }
    }

    fn total(&self) -> u64 {
        self.slots.iter().map(|s| s.0.load(Ordering::Relaxed)).sum()
    }
}

/// The scene's acceleration structure and ray counter.
pub struct Accel {
    bvh: CwBvh,
    /// Per BVH primitive slot (the order of `bvh.primitive_indices`, so that a leaf's triangles lie side by
    /// side): the triangle in f32, normalised: (p − offset) × NORMALISED_DIAGONAL / diagonal, and its face.
    slot_tri: Vec<FilterTriangle>,
    /// Per slot: the f64 plane of the triangle: its first vertex (relative to `offset`) and unit normal.
    slot_plane: Vec<[DVec3; 2]>,
    /// Per triangle: its vertices.
    tri_verts: Vec<[u32; 3]>,
    /// Bound on the rounding error of each f32 coordinate of an edge vector in `slot_tri`.
    edge_err: f32,
    /// Largest f32 coordinate magnitude of a vertex.
    vert_max: f32,
    /// The scene's vertices in f64, relative to `offset`.
    verts: Vec<DVec3>,
    offset: DVec3,
    inv_scale: f64,
    tol: f64,
    rays: RayCounter,
    build_time: Duration,
    /// The eight-lane AVX2 node test, when traversals use it (same answers, bit for bit).
    avx2: Option<crate::wide_node_test::Avx2Test>,
}

impl std::fmt::Debug for Accel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Accel")
            .field("triangles", &self.tri_verts.len())
            .field("plane_tolerance", &self.tol)
            .finish()
    }
}

/// A triangle for the f32 test: first vertex and the two edges from it (normalised coordinates), and its
/// face, in one 48-byte record (the face's bits in the first vertex's fourth lane), so that the face check
/// and the test read the same cache line.
#[derive(Clone, Copy, Debug)]
struct FilterTriangle {
    v0_face: Vec4,
    e1: Vec3A,
    e2: Vec3A,
}

impl FilterTriangle {
    #[inline(always)]
    fn face(&self) -> usize {
        self.v0_face.w.to_bits() as usize
    }

    #[inline(always)]
    fn v0(&self) -> Vec3A {
        Vec3A::from_vec4(self.v0_face)
    }
}

/// What the f32 test concludes about a triangle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Filter {
    /// The ray cannot hit it within [0, tmax] (the loose filter).
    Miss,
    /// The f64 test would find it missed: the ray's line passes farther than 2τ outside the triangle, and
    /// its origin, if on the plane, farther than τ.
    Outside,
    /// The ray's line certainly crosses the triangle's interior (the f64 edge test would pass).
    Inside,
    /// The ray may hit it: f64 decides.
    Unsure,
}

/// The f32 filter ray with what its error bounds need.
#[derive(Clone, Copy, Debug)]
struct FilterRay {
    o: Vec3A,
    d: Vec3A,
    /// ‖d‖₁.
    d_l1: f32,
    /// Bound on the error of each coordinate of `o − v0` against the exact (f64) values, which also covers
    /// the rounding of `o` onto the f64 ray's line.
    tv_err: f32,
}

/// Unit roundoff of f32.
const EPS32: f32 = f32::EPSILON / 2.0;

/// Bound on the error of a triple product a · (b × c) evaluated in f32 from inputs whose coordinates are
/// off: `moved` bounds how far the input errors move the exact product (each factor's largest coordinate
/// error times the L1 norm of the cross product of the other two, |Δa · (b × c)| ≤ ‖Δa‖∞ ‖b × c‖₁), tripled;
/// `abc` is the product of the three L1 norms, which bounds the sum of the magnitudes of its six terms, each
/// evaluated with at most five roundings (Higham 2002, §3.1). Doubled for second-order terms and for the
/// rounding of the bound itself.
#[inline(always)]
fn triple_err(moved: f32, abc: f32) -> f32 {
    2.0 * (3.0 * moved + 5.0 * EPS32 * abc)
}

/// The f32 ray-triangle test (Möller & Trumbore 1997), deciding in f32 wherever conservative error bounds
/// allow, so that f64 is needed only near a triangle's edges:
///
/// - [`Filter::Miss`] first wherever the earlier loose filter rejected (barycentric slack
///   [`F32_FILTER_BARY`], t outside [0, tmax]), with the same arithmetic, so answers are unchanged.
/// - Of the rest, with U = (o − v0) · (d × e2), V = d · ((o − v0) × e1), W = det − U − V (the scaled barycentrics, the
///   edge functions of Woop, Benthin & Wald 2013 in Möller–Trumbore form) and bounds on their errors against
///   exact arithmetic on the f64 scene (`triple_err`), det's sign being certain: [`Filter::Inside`] when all
///   three certainly have det's sign (the exact line crosses the triangle's interior, so the f64 edge test
///   would pass); missed when one certainly has the opposite sign by more than 2τ‖e‖₁, e the edge
///   where it vanishes ([`Filter::Outside`]). The line then crosses the plane farther than 2τ outside that edge (a scaled
///   barycentric is the distance from its edge × |cos θ| × |e|), and the origin, within τ/|cos θ| of the
///   crossing when it lies on the plane, farther than τ: the f64 test finds neither inside.
/// - [`Filter::Unsure`] otherwise: f64 decides.
///
/// `edge_err` bounds the coordinate errors of `e1` and `e2`; `tau` is τ in normalised units.
#[inline(always)]
fn f32_filter(tri: &FilterTriangle, ray: &FilterRay, tmax: f32, edge_err: f32, tau: f32) -> Filter {
    let (o, d) = (ray.o, ray.d);
    let (e1, e2) = (tri.e1, tri.e2);
    let pv = d.cross(e2);
    let det = e1.dot(pv);
    if det == 0.0 {
        return Filter::Miss;
    }
    let inv = 1.0 / det;
    let tv = o - tri.v0();
    let big_u = tv.dot(pv);
    let u = big_u * inv;
    let qv = tv.cross(e1);
    let big_v = d.dot(qv);
    let v = big_v * inv;
    let t = e2.dot(qv) * inv;
    let eps = F32_FILTER_BARY;
    if !(u >= -eps && v >= -eps && u + v <= 1.0 + eps && t >= 0.0 && t <= tmax) {
        return Filter::Miss;
    }
    let (n1, n2, nt, nd) = (
        e1.abs().element_sum(),
        e2.abs().element_sum(),
        tv.abs().element_sum(),
        ray.d_l1,
    );
    let (de, dt, dd) = (edge_err, ray.tv_err, 2.0 * EPS32);
    // U = e2 · ((o − v0) × d) and V = e1 · (d × (o − v0)): the edges' errors move them by at most their
    // coordinate error times ‖(o − v0) × d‖₁, small for a triangle near the line however far from the
    // origin (bounded here from its f32 value, its rounding and its inputs' errors).
    let w = tv.cross(d).abs().element_sum() + 4.0 * EPS32 * nt * nd + 2.0 * (dt * nd + nt * dd);
    let err_det = triple_err(de * nd * n2 + dd * n1 * n2 + de * n1 * nd, n1 * nd * n2);
    let err_u = triple_err(dt * nd * n2 + dd * nt * n2 + de * w, nt * nd * n2);
    let err_v = triple_err(dd * nt * n1 + dt * nd * n1 + de * w, nd * nt * n1);
    let big_w = det - big_u - big_v;
    let err_w = err_det + err_u + err_v + 4.0 * EPS32 * (det.abs() + big_u.abs() + big_v.abs());
    if det.abs() <= err_det {
        return Filter::Unsure;
    }
    let s = det.signum();
    let (su, sv, sw) = (s * big_u, s * big_v, s * big_w);
    if su > err_u && sv > err_v && sw > err_w {
        return Filter::Inside;
    }
    // Twice τ, and padded for the rounding of the edges' norms.
    let tau2 = 2.0 * tau * (1.0 + 16.0 * EPS32);
    if su < -(err_u + tau2 * (n2 + 3.0 * de))
        || sv < -(err_v + tau2 * (n1 + 3.0 * de))
        || sw < -(err_w + tau2 * (n1 + n2 + 6.0 * de))
    {
        return Filter::Outside;
    }
    Filter::Unsure
}

impl Accel {
    /// Builds with the default preset.
    pub fn new(scene: &Scene) -> Self {
        Self::with_preset(scene, AccelPreset::default())
    }

    /// Builds with a chosen preset.
    pub fn with_preset(scene: &Scene, preset: AccelPreset) -> Self {
        let (lo, hi) = scene.bounds();
        let offset = 0.5 * (lo + hi);
        let scale = scene.diagonal().max(f64::MIN_POSITIVE);
        let inv_scale = NORMALISED_DIAGONAL / scale;
        let verts: Vec<DVec3> = scene.vertices.par_iter().map(|&p| p - offset).collect();
        let to32 = |i: u32| Vec3A::from((verts[i as usize] * inv_scale).as_vec3());
        // The largest of the same values in any grouping: the same on any number of threads.
        let vert_max = verts
            .par_iter()
            .map(|&v| (v * inv_scale).abs().max_element())
            .reduce(|| 0.0, f64::max) as f32;
        // Triangles in face order (a quad's two after each other), on any number of threads.
        let (tri_face, tri_verts): (Vec<u32>, Vec<[u32; 3]>) = scene
            .faces
            .par_iter()
            .enumerate()
            .flat_map_iter(|(f, face)| {
                let idx = face.indices;
                let quad = face.vertex_count() == 4;
                std::iter::once((f as u32, [idx[0], idx[1], idx[2]]))
                    .chain(quad.then_some((f as u32, [idx[0], idx[2], idx[3]])))
            })
            .unzip();
        let tris: Vec<Triangle> = tri_verts
            .par_iter()
            .map(|&[a, b, c]| Triangle {
                v0: to32(a),
                v1: to32(b),
                v2: to32(c),
            })
            .collect();
        let start = std::time::Instant::now();
        let bvh = build_bvh(&tris, preset.params());
        let slots = &bvh.primitive_indices;
        let slot_tri = slots
            .par_iter()
            .map(|&k| {
                let t = &tris[k as usize];
                FilterTriangle {
                    v0_face: t.v0.extend(f32::from_bits(tri_face[k as usize])),
                    e1: t.v1 - t.v0,
                    e2: t.v2 - t.v0,
                }
            })
            .collect();
        let slot_plane = slots
            .par_iter()
            .map(|&k| {
                let [a, b, c] = tri_verts[k as usize].map(|i: u32| verts[i as usize]);
                [a, (b - a).cross(c - a).normalize_or_zero()]
            })
            .collect();
        // The BVH and the leaf-ordered triangle data it is traversed with.
        let build_time = start.elapsed();
        Self {
            bvh,
            slot_tri,
            slot_plane,
            tri_verts,
            // Each coordinate of v0, v1, v2 is rounded once from f64 (relative error EPS32, coordinates at
            // most vert_max), and the subtraction once more (|e| ≤ 2 vert_max).
            edge_err: 4.0 * EPS32 * vert_max,
            vert_max,
            verts,
            offset,
            inv_scale,
            tol: PLANE_TOL_REL * scale,
            rays: RayCounter::new(),
            build_time,
            avx2: crate::wide_node_test::avx2_test(),
        }
    }

    /// Chooses the node test; returns false, and keeps the current one, if the processor lacks AVX2.
    pub fn set_node_test(&mut self, kind: NodeTestKind) -> bool {
        self.avx2 = match kind {
            NodeTestKind::Portable => None,
            NodeTestKind::Avx2 => match crate::wide_node_test::avx2_test() {
                Some(test) => Some(test),
                None => return false,
            },
        };
        true
    }

    /// The plane tolerance τ in scene units ([`PLANE_TOL_REL`] × the scene's diagonal).
    pub fn plane_tolerance(&self) -> f64 {
        self.tol
    }

    /// Wall time the BVH build took (with the leaf-ordered triangle data; not the scene conversion before).
    pub fn build_time(&self) -> Duration {
        self.build_time
    }

    /// Rays cast so far, over all threads: exact once the casting threads' work has been joined (rayon's
    /// `join`, `scope` and parallel iterators do), and the same for any number of threads.
    pub fn rays_cast(&self) -> u64 {
        self.rays.total()
    }

    /// Number of triangles in the BVH (quads count two).
    pub fn triangle_count(&self) -> usize {
        self.tri_verts.len()
    }

    /// Approximate heap bytes held.
    pub fn bytes(&self) -> usize {
        self.bvh.nodes.len() * 80
            + self.bvh.primitive_indices.len() * 4
            + self.slot_tri.len() * (size_of::<FilterTriangle>() + size_of::<[DVec3; 2]>())
            + self.tri_verts.len() * size_of::<[u32; 3]>()
            + COUNTER_SLOTS * size_of::<CounterSlot>()
            + self.verts.len() * size_of::<DVec3>()
    }

    /// The f32 filter ray from `o` (relative to `offset`) along `dir`, reaching `tmax` scene units.
    fn filter_ray(&self, o: DVec3, dir: DVec3, tmax: f64) -> (BvhRay, FilterRay) {
        let shift = F32_FILTER_SHIFT * NORMALISED_DIAGONAL;
        let origin = Vec3A::from((o * self.inv_scale - shift * dir).as_vec3());
        let tmax = if tmax.is_finite() {
            (tmax * self.inv_scale + 2.0 * shift) as f32
        } else {
            f32::INFINITY
        };
        let ray = BvhRay::new(origin, Vec3A::from(dir.as_vec3()), 0.0, tmax);
        // o − v0: o rounded once (plus the f64 shift and scaling, far below f32's rounding), v0 once, and
        // the difference once (|o − v0| ≤ |o| + vert_max).
        let o_max = origin.abs().max_element();
        let filter = FilterRay {
            o: ray.origin,
            d: ray.direction,
            d_l1: ray.direction.abs().element_sum(),
            tv_err: 4.0 * EPS32 * (o_max + self.vert_max),
        };
        (ray, filter)
    }

    /// The vertices b, c of the triangle in `slot` (its first vertex and normal are in `slot_plane`).
    fn far_vertices(&self, slot: usize) -> (DVec3, DVec3) {
        let tri = self.bvh.primitive_indices[slot] as usize;
        let [_, b, c] = self.tri_verts[tri];
        (self.verts[b as usize], self.verts[c as usize])
    }

    /// Whether `x` (in the plane of triangle a, b, c with unit normal n) lies inside it within τ.
    fn inside(&self, a: DVec3, b: DVec3, c: DVec3, n: DVec3, x: DVec3) -> bool {
        [(a, b), (b, c), (c, a)].iter().all(|&(p0, p1)| {
            let e = p1 - p0;
            n.dot(e.cross(x - p0)) >= -self.tol * e.length()
        })
    }

    /// The f64 hit distance of the ray (origin `o` relative to `offset`, unit `dir`) on the triangle in
    /// `slot`; `inside` is true when the f32 test has proved that the ray's line crosses its interior.
    #[inline(always)]
    fn exact_hit(&self, slot: usize, o: DVec3, dir: DVec3, inside: bool) -> Option<f64> {
        let [a, n] = self.slot_plane[slot];
        if n == DVec3::ZERO {
            return None;
        }
        let s = n.dot(o - a);
        let dn = n.dot(dir);
        if s.abs() <= self.tol {
            // The origin lies on this triangle's plane: hit at once only if the ray enters its back from a
            // point of the (closed) triangle.
            if dn >= 0.0 {
                return None;
            }
            let (b, c) = self.far_vertices(slot);
            return self.inside(a, b, c, n, o).then_some(0.0);
        }
        if s * dn < 0.0 {
            let t = -s / dn;
            if inside {
                debug_assert!({
                    let (b, c) = self.far_vertices(slot);
                    self.inside(a, b, c, n, o + t * dir)
                });
                return Some(t);
            }
            let (b, c) = self.far_vertices(slot);
            return self.inside(a, b, c, n, o + t * dir).then_some(t);
        }
        None
    }

    /// Closest hit along the ray, if any. Surfaces the origin lies on are not hit unless the ray enters
    /// their back (see the module documentation).
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.closest(ray.origin, ray.dir, ray.tmax, usize::MAX).0
    }

    /// Closest hit along a ray leaving face `from` at `origin` (a point on that face): the face itself is
    /// never hit, nor are its coplanar neighbours.
    pub fn intersect_from(&self, from: FaceId, origin: DVec3, dir: DVec3) -> Option<Hit> {
        self.closest(origin, dir, f64::INFINITY, from).0
    }

    /// [`Accel::intersect`], also returning what the traversal visited: the cost of a ray, independent of
    /// the machine, for benchmarks and for choosing an [`AccelPreset`].
    pub fn intersect_counting(&self, ray: &Ray) -> (Option<Hit>, TraversalCost) {
        self.closest(ray.origin, ray.dir, ray.tmax, usize::MAX)
    }

    fn closest(
        &self,
        origin: DVec3,
        dir: DVec3,
        tmax: f64,
        skip: FaceId,
    ) -> (Option<Hit>, TraversalCost) {
        self.traverse(Closest {
            origin,
            dir,
            tmax,
            skip,
        })
    }

    /// Runs a traversal with the node test in use: with AVX2, inside pulp's `V3::vectorize`, which compiles
    /// the (inlined) traversal with AVX2 enabled around the eight-lane test.
    #[inline(always)]
    fn traverse<Q: Traversal>(&self, query: Q) -> Q::Output {
        #[cfg(target_arch = "x86_64")]
        if let Some(test) = self.avx2 {
            return test.0.vectorize(Vectorized {
                accel: self,
                test,
                query,
            });
        }
        query.run(self, Portable)
    }

    #[inline(always)]
    fn closest_with<T: NodeTest>(
        &self,
        test: T,
        origin: DVec3,
        dir: DVec3,
        tmax: f64,
        skip: FaceId,
    ) -> (Option<Hit>, TraversalCost) {
        let mut cost = TraversalCost::default();
        if !(origin.is_finite() && dir.is_finite()) {
            debug_assert!(
                false,
                "ray with non-finite origin {origin:?} or direction {dir:?}"
            );
            return (None, cost);
        }
        self.rays.add_one();
        let o = origin - self.offset;
        let (mut ray, fray) = self.filter_ray(o, dir, tmax);
        let tau32 = (PLANE_TOL_REL * NORMALISED_DIAGONAL) as f32;
        let shift = F32_FILTER_SHIFT * NORMALISED_DIAGONAL;
        let mut best: Option<(usize, f64)> = None;
        // obvhs's closest-hit traversal (its `traverse!` macro, as in `CwBvh::ray_traverse`), counting the
        // nodes and triangles it visits.
        let mut state = self.bvh.new_traversal(ray.direction);
        let mut node;
        obvhs::traverse!(
            self.bvh,
            node,
            state,
            {
                cost.nodes += 1;
                test.hits(node, &ray, state.oct_inv4)
            },
            {
                cost.triangles += 1;
                let slot = state.primitive_id as usize;
                let tri = &self.slot_tri[slot];
                let face = tri.face();
                let filter = if face == skip {
                    Filter::Miss
                } else {
                    f32_filter(tri, &fray, ray.tmax, self.edge_err, tau32)
                };
                let hit = match filter {
                    Filter::Miss => None,
                    Filter::Outside => {
                        debug_assert!(self.exact_hit(slot, o, dir, false).is_none());
                        None
                    }
                    f => self.exact_hit(slot, o, dir, f == Filter::Inside),
                };
                if let Some(t) = hit {
                    let better = match best {
                        None => t <= tmax,
                        Some((_, bt)) => t < bt,
                    };
                    if better {
                        best = Some((face, t));
                        // Shrink the traversal's reach to this hit, with the filter's slack.
                        ray.tmax = ray.tmax.min((t * self.inv_scale + 2.0 * shift) as f32);
                    }
                }
            }
        );
        let hit = best.map(|(face, t)| Hit {
            face,
            t,
            point: origin + t * dir,
        });
        (hit, cost)
    }

    /// The distance from `p` to the nearest face, and every face within `slack` (scene units) of that
    /// distance, in increasing order; `None` for a scene without faces. A branch-and-bound descent of the BVH
    /// (nearer boxes first; a box farther than the best distance so far plus `slack` is skipped), with exact
    /// f64 point-to-triangle distances at the leaves: O(log n) for a point on a surface of n faces, where
    /// comparing with every face costs O(n).
    pub fn nearest_faces(&self, p: DVec3, slack: f64) -> Option<(f64, Vec<FaceId>)> {
        if self.bvh.nodes.is_empty() || self.slot_tri.is_empty() {
            return None;
        }
        let po = p - self.offset;
        let pn = Vec3A::from((po * self.inv_scale).as_vec3());
        // The boxes hold the f32 triangles padded by BOX_PAD_REL of the diagonal; a box distance is a lower
        // bound on the f64 distance up to the f32 rounding of p and of the box (far below that pad).
        let box_distance = |b: &Aabb| -> f64 {
            let d = (b.min - pn).max(pn - b.max).max(Vec3A::ZERO);
            d.length() as f64 / self.inv_scale
        };
        let slack = slack.max(0.0);
        let mut best = f64::INFINITY;
        let mut found: Vec<(f64, FaceId)> = Vec::new();
        let mut stack: Vec<(f64, u32)> = vec![(0.0, 0)];
        while let Some((d_node, i)) = stack.pop() {
            if d_node > best + slack {
                continue;
            }
            let node = &self.bvh.nodes[i as usize];
            let mut inner: [(f64, u32); 8] = [(f64::INFINITY, 0); 8];
            let mut n_inner = 0;
            for child in 0..8 {
                if node.is_child_empty(child) {
                    continue;
                }
                let d = box_distance(&node.child_aabb(child));
                if d > best + slack {
                    continue;
                }
                if node.is_leaf(child) {
                    let (first, count) = node.child_primitives(child);
                    for slot in first as usize..(first + count) as usize {
                        let [a, n] = self.slot_plane[slot];
                        if n == DVec3::ZERO {
                            continue;
                        }
                        let (b, c) = self.far_vertices(slot);
                        let dist = radlab_scene::Polygon::triangle(a, b, c).distance_to(po);
                        best = best.min(dist);
                        found.push((dist, self.slot_tri[slot].face()));
                    }
                } else {
                    inner[n_inner] = (d, node.child_node_index(child));
                    n_inner += 1;
                }
            }
            // Nearest child last, so it is taken first.
            let inner = &mut inner[..n_inner];
            inner.sort_by(|x, y| y.0.total_cmp(&x.0));
            stack.extend_from_slice(inner);
        }
        if !best.is_finite() {
            return None;
        }
        let mut faces: Vec<FaceId> = found
            .into_iter()
            .filter(|&(d, _)| d <= best + slack)
            .map(|(_, f)| f)
            .collect();
        faces.sort_unstable();
        faces.dedup();
        Some((best, faces))
    }

    /// Whether the segment between `p` and `q` is unobstructed, for points that may lie on surfaces: a
    /// surface the segment only touches at an end never occludes it.
    pub fn visible(&self, p: DVec3, q: DVec3) -> bool {
        self.visible_ignoring(p, q, usize::MAX, usize::MAX).0
    }

    /// Whether the segment from `p` on face `fp` to `q` on face `fq` is unobstructed; the two end faces
    /// are ignored (pass `usize::MAX` for a point on no face).
    pub fn visible_between(&self, p: DVec3, fp: FaceId, q: DVec3, fq: FaceId) -> bool {
        self.visible_ignoring(p, q, fp, fq).0
    }

    /// For each segment, whether it is unobstructed: `visible[k]` is exactly
    /// `visible_between(s.p, s.fp, s.q, s.fq)` for `s = segments[k]`, and every segment counts as one ray, as
    /// there. The segments are traversed together, up to [`PACKET_SEGMENTS`] at a time (a packet, Wald et al.
    /// 2001): a node is fetched once for the packet and its children's boxes tested against each segment still
    /// open that reached it, so segments between two patches, which share most of their path down the BVH,
    /// share its node loads. A segment's triangle tests are those of its own traversal, so its answer is too.
    ///
    /// # Panics
    /// If the slices differ in length.
    pub fn visible_many(&self, segments: &[Segment], visible: &mut [bool]) {
        assert_eq!(segments.len(), visible.len(), "one answer per segment");
        for (segs, out) in segments
            .chunks(PACKET_SEGMENTS)
            .zip(visible.chunks_mut(PACKET_SEGMENTS))
        {
            let mask = self.traverse(VisiblePacket { segments: segs });
            for (k, v) in out.iter_mut().enumerate() {
                *v = mask & (1 << k) != 0;
            }
        }
    }

    /// [`Accel::visible`], also returning what the traversal visited.
    pub fn visible_counting(&self, p: DVec3, q: DVec3) -> (bool, TraversalCost) {
        self.visible_ignoring(p, q, usize::MAX, usize::MAX)
    }

    /// [`Accel::visible_between`], also returning what the traversal visited.
    pub fn visible_between_counting(
        &self,
        p: DVec3,
        fp: FaceId,
        q: DVec3,
        fq: FaceId,
    ) -> (bool, TraversalCost) {
        self.visible_ignoring(p, q, fp, fq)
    }

    fn visible_ignoring(
        &self,
        p: DVec3,
        q: DVec3,
        fp: FaceId,
        fq: FaceId,
    ) -> (bool, TraversalCost) {
        self.traverse(Visible { p, q, fp, fq })
    }

    #[inline(always)]
    fn visible_with<T: NodeTest>(
        &self,
        test: T,
        p: DVec3,
        q: DVec3,
        fp: FaceId,
        fq: FaceId,
    ) -> (bool, TraversalCost) {
        let mut cost = TraversalCost::default();
        let Some(segment) = self.segment(p, q, fp, fq) else {
            return (true, cost);
        };
        self.rays.add_one();
        let visible = self.unoccluded_below(test, &segment, 0, &mut cost);
        (visible, cost)
    }

    /// Whether no triangle under node `root` occludes the segment: obvhs's any-hit traversal (as in
    /// `CwBvh::ray_traverse_miss`) of that subtree, adding the nodes and triangles it visits to `cost`.
    #[inline(always)]
    fn unoccluded_below<T: NodeTest>(
        &self,
        test: T,
        segment: &SegmentRay,
        root: u32,
        cost: &mut TraversalCost,
    ) -> bool {
        let ray = segment.ray;
        let mut visible = true;
        let mut state = self.bvh.new_traversal(ray.direction);
        if !self.bvh.nodes.is_empty() {
            // The group obvhs starts from (the root as the only child of a node with no inner children), at
            // `root` instead.
            state.current_group = UVec2::new(root, 0x8000_0000);
        }
        let mut node;
        'traversal: {
            obvhs::traverse!(
                self.bvh,
                node,
                state,
                {
                    cost.nodes += 1;
                    test.hits(node, &ray, state.oct_inv4)
                },
                {
                    cost.triangles += 1;
                    let slot = state.primitive_id as usize;
                    if self.occludes(slot, segment) {
                        visible = false;
                        break 'traversal;
                    }
                }
            );
        }
        visible
    }

    /// The f32 and f64 forms of a segment from `p` to `q` (scene coordinates) with its end faces, or `None`
    /// for a segment of zero or non-finite length (unobstructed, and not a ray cast).
    #[inline(always)]
    fn segment(&self, p: DVec3, q: DVec3, fp: FaceId, fq: FaceId) -> Option<SegmentRay> {
        let d = q - p;
        let len = d.length();
        if !(len > 0.0 && len.is_finite()) {
            debug_assert!(len == 0.0, "segment with non-finite ends {p:?} {q:?}");
            return None;
        }
        let dir = d / len;
        let (p, q) = (p - self.offset, q - self.offset);
        let (ray, fray) = self.filter_ray(p, dir, len);
        Some(SegmentRay {
            ray,
            fray,
            p,
            q,
            fp,
            fq,
        })
    }

    /// Whether the triangle in `slot` occludes the segment: its plane is crossed between the segment's ends,
    /// both farther than τ from it, at a point inside it within τ (decided in f32 where the error bounds
    /// allow, in f64 otherwise); the segment's end faces never do.
    #[inline(always)]
    fn occludes(&self, slot: usize, s: &SegmentRay) -> bool {
        let tau32 = (PLANE_TOL_REL * NORMALISED_DIAGONAL) as f32;
        let tol = self.tol;
        let (p, q) = (s.p, s.q);
        let tri = &self.slot_tri[slot];
        let f = tri.face();
        let filter = if f == s.fp || f == s.fq {
            Filter::Miss
        } else {
            f32_filter(tri, &s.fray, s.ray.tmax, self.edge_err, tau32)
        };
        if filter == Filter::Outside {
            debug_assert!({
                let [a, n] = self.slot_plane[slot];
                let (b, c) = self.far_vertices(slot);
                let (sp, sq) = (n.dot(p - a), n.dot(q - a));
                !((sp > tol && sq < -tol) || (sp < -tol && sq > tol))
                    || !self.inside(a, b, c, n, p + (sp / (sp - sq)) * (q - p))
            });
            return false;
        }
        if filter == Filter::Miss {
            return false;
        }
        let [a, n] = self.slot_plane[slot];
        let (sp, sq) = (n.dot(p - a), n.dot(q - a));
        // Only a plane crossed between the ends, both ends clear of it, can occlude.
        ((sp > tol && sq < -tol) || (sp < -tol && sq > tol)) && {
            let check = || {
                let (b, c) = self.far_vertices(slot);
                self.inside(a, b, c, n, p + (sp / (sp - sq)) * (q - p))
            };
            debug_assert!(filter != Filter::Inside || check());
            filter == Filter::Inside || check()
        }
    }

    /// The packet traversal of [`Accel::visible_many`] for at most [`PACKET_SEGMENTS`] segments: a stack of
    /// (node, segments that reached it); at a node, each of those segments' child hits (the same slab tests as
    /// its own traversal) are gathered per child slot, inner children are pushed with the segments that hit
    /// them, and leaf children's triangles are tested against theirs. A segment leaves the packet at its
    /// first occluder. Returns the mask of unobstructed segments.
    #[inline(always)]
    fn visible_packet_with<T: NodeTest>(&self, test: T, segments: &[Segment]) -> u32 {
        debug_assert!(segments.len() <= PACKET_SEGMENTS);
        // The segments' rays, in packet order (a segment of zero length keeps its place, closed).
        let mut rays: SmallVec<[(SegmentRay, u32); PACKET_SEGMENTS]> = SmallVec::new();
        let mut open = 0u32;
        let mut visible = 0u32;
        for (k, s) in segments.iter().enumerate() {
            match self.segment(s.p, s.q, s.fp, s.fq) {
                Some(r) => {
                    let oct = octant_inv4(r.ray.direction);
                    rays.push((r, oct));
                    open |= 1 << k;
                }
                None => {
                    rays.push((SegmentRay::NONE, 0));
                    visible |= 1 << k;
                }
            }
        }
        if open == 0 {
            return visible;
        }
        self.rays.add(u64::from(open.count_ones()));
        if self.bvh.nodes.is_empty() {
            return visible | open;
        }
        // obvhs visits a node's inner children in decreasing order of slot ^ (its octant code & 7): here in
        // the order of the first open segment's octant.
        let octant = (rays[open.trailing_zeros() as usize].1 & 7) as usize;
        let mut stack: SmallVec<[(u32, u32); 64]> = SmallVec::new();
        stack.push((0, open));
        while let Some((index, reached)) = stack.pop() {
            let reached = reached & open;
            if reached == 0 {
                continue;
            }
            if reached.count_ones() == 1 {
                // One segment left here: its own traversal of the subtree, without the packet's bookkeeping.
                let k = reached.trailing_zeros() as usize;
                let mut cost = TraversalCost::default();
                if !self.unoccluded_below(test, &rays[k].0, index, &mut cost) {
                    open &= !reached;
                }
                continue;
            }
            let node = &self.bvh.nodes[index as usize];
            let mut by_slot = [0u32; 8];
            for k in bits(reached) {
                let (r, oct) = &rays[k];
                for i in bits(test.slot_hits(node, &r.ray, *oct)) {
                    by_slot[i] |= 1 << k;
                }
            }
            // Leaf children's triangles first, then the inner children, nearest first for the packet's
            // direction.
            for (i, &who) in by_slot.iter().enumerate() {
                if who == 0 || node.imask & (1 << i) != 0 {
                    continue;
                }
                let meta = node.child_meta[i];
                let first = node.primitive_base_idx as usize + usize::from(meta & 0b1_1111);
                for slot in first..first + (meta >> 5).count_ones() as usize {
                    for k in bits(who & open) {
                        if self.occludes(slot, &rays[k].0) {
                            open &= !(1 << k);
                        }
                    }
                }
            }
            if open == 0 {
                break;
            }
            for key in 0..8 {
                let i = key ^ octant;
                if by_slot[i] != 0 && node.imask & (1 << i) != 0 {
                    let below = u32::from(node.imask) & ((1u32 << i) - 1);
                    stack.push((node.child_base_idx + below.count_ones(), by_slot[i]));
                }
            }
        }
        visible | open
    }
}

/// obvhs's code of a direction's octant (its private `ray_get_octant_inv4`): 4, 2, 1 for non-negative x, y,
/// z, repeated in each byte.
#[inline(always)]
fn octant_inv4(d: Vec3A) -> u32 {
    (if d.x < 0.0 { 0 } else { 0x0404_0404 })
        | (if d.y < 0.0 { 0 } else { 0x0202_0202 })
        | (if d.z < 0.0 { 0 } else { 0x0101_0101 })
}

/// A segment ready for traversal: the f32 ray of the BVH and of the triangle filter, and the f64 ends
/// (relative to the scene's centre) with their faces.
#[derive(Clone, Copy, Debug)]
struct SegmentRay {
    ray: BvhRay,
    fray: FilterRay,
    p: DVec3,
    q: DVec3,
    fp: FaceId,
    fq: FaceId,
}

impl SegmentRay {
    /// A placeholder for a segment that is not traversed.
    const NONE: Self = Self {
        ray: BvhRay {
            origin: Vec3A::ZERO,
            direction: Vec3A::ZERO,
            inv_direction: Vec3A::ZERO,
            tmin: 0.0,
            tmax: 0.0,
        },
        fray: FilterRay {
            o: Vec3A::ZERO,
            d: Vec3A::ZERO,
            d_l1: 0.0,
            tv_err: 0.0,
        },
        p: DVec3::ZERO,
        q: DVec3::ZERO,
        fp: usize::MAX,
        fq: usize::MAX,
    };
}

/// The indices of the set bits of `mask`, lowest first.
#[inline(always)]
fn bits(mut mask: u32) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (mask != 0).then(|| {
            let i = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            i
        })
    })
}

/// One traversal's query, run with a given node test.
trait Traversal {
    type Output;
    fn run<T: NodeTest>(self, accel: &Accel, test: T) -> Self::Output;
}

/// A closest-hit query ([`Accel::closest`]).
struct Closest {
    origin: DVec3,
    dir: DVec3,
    tmax: f64,
    skip: FaceId,
}

impl Traversal for Closest {
    type Output = (Option<Hit>, TraversalCost);

    #[inline(always)]
    fn run<T: NodeTest>(self, accel: &Accel, test: T) -> Self::Output {
        accel.closest_with(test, self.origin, self.dir, self.tmax, self.skip)
    }
}

/// A visibility query ([`Accel::visible_ignoring`]).
struct Visible {
    p: DVec3,
    q: DVec3,
    fp: FaceId,
    fq: FaceId,
}

impl Traversal for Visible {
    type Output = (bool, TraversalCost);

    #[inline(always)]
    fn run<T: NodeTest>(self, accel: &Accel, test: T) -> Self::Output {
        accel.visible_with(test, self.p, self.q, self.fp, self.fq)
    }
}

/// A packet of visibility queries ([`Accel::visible_many`]).
struct VisiblePacket<'s> {
    segments: &'s [Segment],
}

impl Traversal for VisiblePacket<'_> {
    type Output = u32;

    #[inline(always)]
    fn run<T: NodeTest>(self, accel: &Accel, test: T) -> Self::Output {
        accel.visible_packet_with(test, self.segments)
    }
}

/// A query with the AVX2 node test, for `V3::vectorize` (which compiles what it calls with AVX2 enabled;
/// `call` and the traversal are inlined into it).
#[cfg(target_arch = "x86_64")]
struct Vectorized<'a, Q> {
    accel: &'a Accel,
    test: crate::wide_node_test::Avx2,
    query: Q,
}

#[cfg(target_arch = "x86_64")]
impl<Q: Traversal> pulp::NullaryFnOnce for Vectorized<'_, Q> {
    type Output = Q::Output;

    #[inline(always)]
    fn call(self) -> Self::Output {
        self.query.run(self.accel, self.test)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// obvhs's parallel build (its `parallel` feature) splits work by the number of rayon threads; the BVH,
    /// and with it the order in which ties between equally distant hits (rays through shared edges) are
    /// broken, must not depend on it.
    #[test]
    fn bvh_is_the_same_on_any_number_of_threads() {
        // More primitives than every parallel threshold of obvhs 0.4's PLOC build (4·10³ for the neighbour
        // search, 3·10⁵ for the merge costs, 5·10⁵ for the leaf setup); one triangle in eight repeated
        // exactly, so that Morton codes tie.
        let tris = crate::cwbvh_convert::tests::random_triangles(5, 520_000, 500.0, 8);
        // The default preset (the others run the same parallel stages with other parameters).
        let build = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool")
                .install(|| build_bvh(&tris, AccelPreset::Fast.params()))
        };
        let one = build(1);
        assert!(one == build(2), "1 and 2 threads differ");
        assert!(one == build(3), "1 and 3 threads differ");
    }
}

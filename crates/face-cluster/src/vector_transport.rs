//! The vector radiosity transport of face cluster radiosity (Willmott, Heckbert & Garland 1999, section 4).
//! Every node carries an irradiance vector e per channel; its exitance state is its power vector
//! p = Σ B_i A_i n_i per channel. A link from source S to receiver R, with unit direction d from S's centroid
//! to R's, distance r and visibility V, adds
//!
//!   e_R += V max(0, p_S·d) / (π r²) · (−d)                      (Willmott et al. 1999, eq. 4)
//!
//! (the point approximation of the kernel: a face i of R with n_i·(−d) ≥ 0 receives n_i·e, the irradiance of
//! the classic point-to-point transfer). With `irradiance_field = "linear"` (the default) a link to a cluster
//! also adds its kernel's Jacobian J = ∂e/∂y over the receiver ([`crate::irradiance_gradient`]). Push:
//! children add their parent's field at their own centroid, e + J (c_child − c_parent), and J. At an engine
//! leaf that is a cluster, p = p_E + M e + s Σ ρ_i A_i n_i with M = Σ ρ_i A_i n_i n_iᵀ and p_E = Σ E_i A_i n_i, and the
//! area-mean radiosity B̄ = (Σ E_i A_i + (Σ ρ_i A_i n_i)·e + s Σ ρ_i A_i)/A; at a patch of one face,
//! B = E + ρ max(0, n·e + s) and p = B A n (s, the isotropic irradiance, is zero but for the straddled links
//! below).
//! Pull: power vectors add. No step of gather, push or pull reads an input face.
//!
//! The vector form holds only while every face of the receiver faces the link's directions and every face of
//! the source faces the receiver (n_i·(−d) ≥ 0, n_i·d ≥ 0): with θ the node's normal-cone half-angle, α the
//! angle between the cone axis and ±d and σ the spread of the link's directions (σ = asin((ρ_R + ρ_S)/|c_R −
//! c_S|) for bounding spheres of radii ρ_R, ρ_S), a link is made when α + θ + σ ≤ 90° at both ends, dropped
//! when α − θ − σ ≥ 90° at either (nothing faces the other), and otherwise refused as overlapping so the
//! refinement splits it — unless its geometric estimate max(F_RS, F_SR) ρ_R (× A_R/A_scene with the power
//! norm) is already below the final ε, which bounds the error of keeping it. Without that exception every
//! pair whose cones straddle the link direction splits down to the input faces whatever light it carries
//! (measured: 316,000 links for 600 faces of concentric spheres at ε = 1e-3). A kept link whose curved end's
//! cone straddles it (α + θ > 90°) does not use the vector form at that end: its receiver gathers, and its
//! source sends, the least-squares line a + b x of the clamped cosine max(0, x) over the spread of its
//! faces' cosines x = n_i·d (uniform with their area-weighted mean and variance, from the node's Σ A_i n_i
//! and Σ A_i n_i n_iᵀ, within [cos(α + θ), cos(α − θ)] its cone allows): b g (−d) into e and a g into an
//! isotropic irradiance s, of which every face takes s; a source sends a Σ B_i A_i + b p·d
//! ([`crate::clamped_irradiance`]). Summed over many such links the vector form alone cancels what
//! opposite sides bring (a closed part in a furnace gathered nothing), and counts faces that see a link from
//! behind negatively.
//!
//! Pairs whose bounds overlap get a link that transfers nothing, with the form-factor bounds
//! F_RS ≤ min(1, A_S/A_R) (reciprocity), so the oracle splits them until the power they could carry is below
//! ε (the light such kept links would carry is lost). Every point transfer is capped so that neither end's
//! form factor exceeds one: g = min(V/(π r²), V/max(A_R, A_S)). A node whose two children face each other
//! (each child's centroid in front of the other's mean plane: a concave node) has a self-link; it carries
//! f B̄ along the node's cone axis with f = (1 − cos θ)/2, the share of its own power a spherical cap of
//! half-angle θ sends to itself (A_cap/(4πR²), exact for the inside of a sphere); flat (θ < 1e-6 rad), convex
//! and single-face nodes have none, and a node whose children are single faces refines its self-link into
//! the faces' links (flat facets exchange more across their shared edge than the cap's share says). That is
//! `self_exchange = "cap"`. By default (`traced`) a one-sided curved cluster (|Σ A_i n_i| ≥ A/2) of at
//! least [`TRACED_MIN_FACES`] faces has a self-link carrying instead its traced self form factor F_NN,
//! and its two one-sided children a link carrying their traced exchange, both as an isotropic irradiance t
//! of their own ([`crate::self_exchange`]) that push hands each child in proportion to the trace's landings
//! on it per unit area, (L_C/A_C)/(L_P/A_P), what a node's sibling sent it, at the first push, in
//! proportion to where that sibling's own rays landed, and below that by where the rays from beyond each
//! node landed (near the boundary the light crossed); a siblings' link is never refined. A wider or smaller node whose children do
//! not face each other has a self-link that carries nothing and is split while its traced F_NN could carry
//! more than ε, so that one-sided parts, or the faces' exact kernels, carry it (spread evenly over a slab,
//! its top's light would reach its bottom; over a few facets, a facet beside the sibling would get no more
//! than one across).
//! Two patches exchange light by the patch kernel of radlab-hierarchical (exact point-to-polygon factors). A
//! near single-face source (a neighbour across a shared edge included) is evaluated at each leaf below its
//! flat receiver, over a patch leaf's Gauss points: a leaf's row then sums exact factors at the same points,
//! one in a closed scene (Hanrahan, Salzman & Aupperle 1991's gather at leaves).
//!
//! Visibility: the fraction of unobstructed segments between the two nodes' sample points (all pairs, up to
//! the `visibility` ray count), through the scene's one `Accel`, from the samples of each end whose face
//! faces the other end's centre (all of them if none does): the transfer already gives faces turned away
//! nothing, and their rays, leaving behind them into the rest of their part, would count that loss twice
//! (on the 10⁵-face bumpy sphere at ε = 1e-5 the sphere's rows summed to 0.9957 with every sample, 0.9982
//! with the facing ones; `examples/row_sums_by_source.rs`). A pair none of whose segments passes is
//! dropped only once its unoccluded estimate is below ε; above, it is split like a straddling one.

use glam::DVec3;
use radlab_hierarchical::{GatherAt, Link, NodeKind, NodeView, Patch, PatchKernel, Transport};
use radlab_kernels::form_factor::{VisibilitySampling, point_polygon_vector};
use radlab_scene::{Ray, Rgb};
use radlab_visibility::Accel;

use std::sync::atomic::{AtomicU64, Ordering};

use crate::bounds::angle_between;
use crate::clamped_irradiance::{ClampedIrradiance, CosineFit, LinkCoefficient};
use crate::face_node::FaceNode;
use crate::irradiance_gradient::{
    IrradianceField, JACOBIAN_EVALUATIONS, central_jacobian, point_field,
};

/// A single-face source is near when its bounding radius exceeds this fraction of the distance between the
/// two ends' centres: there the point form's relative error, of order (R/r)², would pass 1%, and the link
/// uses the face's exact irradiance vector instead.
pub const NEAR: f64 = 0.1;

/// Normal-cone half-angle (radians) below which a node is flat: rounding, not curvature, and no self-link.
pub const FLAT_CONE: f64 = 1e-6;

/// The vector transport.
#[derive(Debug)]
pub struct VectorTransport<'a> {
    patches: PatchKernel<'a>,
    accel: &'a Accel,
    visibility: VisibilitySampling,
    /// Links whose vector form fails, or whose visibility samples are all blocked, are refused while
    /// max(F_RS, F_SR) ρ_R × A_R/`norm_area` exceeds this.
    refuse_above: f64,
    /// A_R's divisor in the refusal estimate: the scene's area (power norm), or 0 for the radiosity norm.
    norm_area: f64,
    /// Whether links bring a linear irradiance field over cluster receivers.
    field: IrradianceField,
    /// Kernel evaluations the irradiance Jacobians took (the engine counts one per coefficient).
    jacobian_evaluations: AtomicU64,
}

impl<'a> VectorTransport<'a> {
    /// A transport whose patch pairs use `patches` and whose vector links cast up to `visibility` rays.
    /// Links whose vector form fails are refused (split) while their geometric estimate max(F_RS, F_SR) ρ_R,
    /// times A_R / `scene_area` when `scene_area` > 0 (the power norm), exceeds `epsilon`.
    pub fn new(
        patches: PatchKernel<'a>,
        accel: &'a Accel,
        visibility: VisibilitySampling,
        epsilon: f64,
        scene_area: f64,
    ) -> Self {
        Self {
            patches,
            accel,
            visibility,
            refuse_above: epsilon,
            norm_area: scene_area,
            field: IrradianceField::Constant,
            jacobian_evaluations: AtomicU64::new(0),
        }
    }

    /// The same transport, its links bringing `field` over cluster receivers.
    pub fn with_field(self, field: IrradianceField) -> Self {
        Self { field, ..self }
    }

    /// Kernel evaluations the irradiance Jacobians have taken so far (besides the engine's one per
    /// coefficient).
    pub fn jacobian_evaluations(&self) -> u64 {
        self.jacobian_evaluations.load(Ordering::Relaxed)
    }

    /// The Jacobian of `f` over `target` (central differences across half its bounding radius), counted;
    /// `None` for a constant field, a volume or patch target, or where `f` is undefined.
    fn jacobian(
        &self,
        target: &FaceNode<'_>,
        f: impl Fn(DVec3) -> Option<DVec3>,
    ) -> Option<glam::DMat3> {
        if self.field == IrradianceField::Constant || !matches!(target, FaceNode::Cluster(_)) {
            return None;
        }
        self.jacobian_evaluations
            .fetch_add(JACOBIAN_EVALUATIONS, Ordering::Relaxed);
        central_jacobian(f, target.centroid(), 0.5 * target.bound().radius)
    }

    fn visibility(&self, a: &FaceNode<'_>, b: &FaceNode<'_>) -> f64 {
        let rays = self.visibility.rays() as usize;
        if rays == 0 {
            return 1.0;
        }
        // Same segments for the link and its reverse: order the ends by key.
        let (a, b) = if a.key() <= b.key() { (a, b) } else { (b, a) };
        // Each end's samples facing the other end: a point transfer already gives a face turned away from
        // the link nothing (its power vector, or the clamped cosine's fit), so the rays from such a face,
        // which leave behind it and meet the rest of its part, must not count again as occlusion.
        let (ca, cb) = (a.bound().centre, b.bound().centre);
        let (pa, pb) = (a.sample_points_facing(cb), b.sample_points_facing(ca));
        let n = rays.min(pa.len() * pb.len());
        let seen = (0..n)
            .filter(|&i| {
                let (p, q) = (pa[i % pa.len()], pb[(i / pa.len() + i) % pb.len()]);
                self.visible_past_ends(p, q, a, b)
            })
            .count();
        seen as f64 / n as f64
    }
}

/// A single-face source as a patch: itself, or a tree leaf's face (reading it, counted as a face read).
fn source_patch(src: &FaceNode<'_>) -> Option<Patch> {
    match src {
        FaceNode::Patch(p) => Some(*p),
        FaceNode::Cluster(c) if c.node().is_leaf() => {
            let f = c.ctx.tree.faces_of(c.id as usize)[0] as usize;
            c.ctx.count_face_read();
            Some(Patch::root(c.ctx.scene, f))
        }
        _ => None,
    }
}

/// Whether a link `recv ← src` is of the near single-face kind ([`VectorTransport::near_face_link`] makes it
/// only when this holds): a flat cluster receiver and a single-face source whose bounding radius exceeds
/// [`NEAR`] times the distance between the two ends' centres. Reads no face.
fn near_single_face(recv: &FaceNode<'_>, src: &FaceNode<'_>) -> bool {
    let single = match src {
        FaceNode::Patch(_) => true,
        FaceNode::Cluster(c) => c.node().is_leaf(),
        FaceNode::Volume(_) => false,
    };
    if !single || recv.is_volume() || recv.as_patch().is_some() || src.area() <= 0.0 {
        return false;
    }
    let (rb, sb) = (recv.bound(), src.bound());
    recv.cone().half_angle < FLAT_CONE && sb.radius > NEAR * (rb.centre - sb.centre).length()
}

/// Most surfaces a visibility ray passes through its own ends before it counts as blocked (beyond this the
/// segment is taken as blocked).
const MAX_END_CROSSINGS: usize = 32;

impl VectorTransport<'_> {
    /// The link from a near single-face source to a flat receiver, whose every face has the whole source
    /// above its plane: the source's exact irradiance vector at the receiver's centroid per unit radiosity,
    /// Φ(c_R) = (1/2π) Σ_edges Θ_e û_e (Arvo 1994), so that each receiving face gets n·Φ B_S, the exact
    /// point-to-polygon factor (Baum, Rushmeier & Winget 1989, eq. 3) times the source's radiosity.
    /// `None` when the link is not of that kind; `Some(None)` when nothing is transferred; an overlapping link
    /// (for the oracle to split) when every visibility sample is blocked but it could carry more than ε.
    fn near_face_link(
        &self,
        recv: &FaceNode<'_>,
        src: &FaceNode<'_>,
        src_id: u32,
    ) -> Option<Option<Link>> {
        if !near_single_face(recv, src) {
            return None;
        }
        let cone = recv.cone();
        let poly = source_patch(src)?.polygon;
        let (n, c) = (cone.axis, recv.centroid());
        // The whole source above or in the receiver's plane (a neighbour across a shared edge touches it):
        // no receiving face clips it.
        let tol = 1e-9 * (recv.bound().radius + src.bound().radius);
        if poly.vertices().iter().any(|v| n.dot(*v - c) < -tol) {
            return None;
        }
        let f = n.dot(point_polygon_vector(c, &poly));
        if f <= 0.0 {
            // Nothing reaches the centroid. Nothing reaches the receiver only if all of it lies behind or in
            // the source's plane; a receiver reaching in front of a source that stands on it (a lamp on a
            // floor, the centroid in the lamp's plane) takes the general path instead.
            let (sn, s0) = (poly.normal(), poly.vertices()[0]);
            let behind = recv.hull().iter().all(|p| sn.dot(*p - s0) <= tol);
            return if behind { Some(None) } else { None };
        }
        let f_src = (f * recv.area() / src.area()).min(1.0);
        let v = self.visibility(recv, src);
        if v <= 0.0 {
            // No sampled segment passes. As on the general path, that is no proof that nothing does: a lamp
            // over half a room's floor whose few sample points stand under a table, a ball and a platform
            // lost the whole half's direct light. Split while it could carry more than ε unoccluded.
            return Some(
                self.above_final_epsilon(recv, f, f_src)
                    .then(|| Link::overlapping(src_id)),
            );
        }
        Some(Some(Link {
            source: src_id,
            coefficient: v,
            f_recv: f as f32,
            f_src: f_src as f32,
            spread: f as f32,
            visibility: v as f32,
            overlap: false,
            clustered: false,
        }))
    }

    /// Whether a link's geometric estimate max(F_RS, F_SR) ρ_R (× A_R/A_scene with the power norm) exceeds
    /// the final ε, so that the error of keeping it in a form that may be wrong is not bounded by ε.
    fn above_final_epsilon(&self, recv: &FaceNode<'_>, f_rs: f64, f_sr: f64) -> bool {
        let norm = if self.norm_area > 0.0 {
            recv.area() / self.norm_area
        } else {
            1.0
        };
        f_rs.max(f_sr) * recv.reflectance().max_element() * norm > self.refuse_above
    }

    /// Whether the segment p → q between sample points of ends `a` and `b` is unobstructed by anything but
    /// the ends themselves. A point transfer already counts which of an end's faces face the other end (its
    /// power vector, or A/4 for a volume), so an end's own surfaces must not occlude its rays: a sample point
    /// on the far side of a closed part would otherwise hide the whole part.
    fn visible_past_ends(&self, p: DVec3, q: DVec3, a: &FaceNode<'_>, b: &FaceNode<'_>) -> bool {
        let len = (q - p).length();
        if !(len > 0.0 && len.is_finite()) {
            return true;
        }
        let dir = (q - p) / len;
        let mut hit = self.accel.intersect(&Ray {
            origin: p,
            dir,
            tmax: len,
        });
        for _ in 0..MAX_END_CROSSINGS {
            let Some(h) = hit else {
                return true;
            };
            // Ends touched at q itself never occlude (as in Accel::visible).
            if h.t >= len * (1.0 - 1e-9) {
                return true;
            }
            if !(a.holds(h.face) || b.holds(h.face)) {
                return false;
            }
            hit = self
                .accel
                .intersect_from(h.face, h.point, dir)
                .map(|mut h2| {
                    h2.t += h.t;
                    h2
                });
        }
        false
    }
}

/// The traced flux per unit radiosity (A F_NN, [`crate::self_exchange`]) that a one-sided curved cluster of
/// at least [`TRACED_MIN_FACES`] faces sends onto itself, where the exchange was traced
/// (`self_exchange = "traced"`); `None` otherwise.
fn traced_self(node: &FaceNode<'_>) -> Option<f64> {
    let FaceNode::Cluster(c) = node else {
        return None;
    };
    let n = c.id as usize;
    let traced = c.ctx.exchange.onto_itself.get(n)?;
    traced_tree_node(c.node()).then_some(*traced)
}

/// Whether a tree node is curved and its faces mostly face one way: |Σ A_i n_i| ≥ Σ A_i / 2 (for a
/// spherical cap, (1 + cos θ)/2 ≥ 1/2: a cone of at most 90°, and a heightfield's few steep faces do not
/// change it). Light spread evenly over it then reaches faces that could receive it; a closed part or a slab
/// (its top and bottom cancel in Σ A_i n_i) would hand its top's light to its bottom.
fn one_sided_tree_node(n: &crate::Node) -> bool {
    n.cone.half_angle >= FLAT_CONE && n.vector_area.length() >= 0.5 * n.area
}

/// Whether a tree node's self-exchange is traced: one-sided ([`one_sided_tree_node`]), with at least [`TRACED_MIN_FACES`] faces.
fn traced_tree_node(n: &crate::Node) -> bool {
    one_sided_tree_node(n) && n.faces().len() >= TRACED_MIN_FACES
}

/// Faces a cluster needs, at least, for its self-exchange to be traced (default 32: a self-link with its
/// F_NN, and a link between its two children with their traced exchange). In a smaller node, how much a face
/// receives from the sibling depends on where it lies (a facet beside the sibling sees more of it than one
/// across the node) more than an even spread allows: a 48-face furnace sphere, whose one-sided nodes have 12
/// faces or fewer, had faces 2.1% apart at ρ = 0.5 with even spreads, and is exact refined to its faces. Such
/// nodes keep the cap's rule and reach the exact kernels between faces where ε asks. The terrain does not
/// mind: 16, 32 and 64 agree within 0.02% relative L1 at 10⁴ and 10⁵ faces, ε = 1e-4 … 1e-6.
pub const TRACED_MIN_FACES: usize = 32;

/// The traced flux per unit radiosity that each of two one-sided sibling clusters sends onto the other,
/// where the exchange was traced and their parent has at least [`TRACED_MIN_FACES`] faces; `None` for
/// other pairs.
fn traced_between(recv: &FaceNode<'_>, src: &FaceNode<'_>) -> Option<f64> {
    let (FaceNode::Cluster(r), FaceNode::Cluster(s)) = (recv, src) else {
        return None;
    };
    if r.id == s.id || !std::sync::Arc::ptr_eq(&r.ctx, &s.ctx) {
        return None;
    }
    let p = r.node().parent()?;
    if s.node().parent() != Some(p) {
        return None;
    }
    let traced = r.ctx.exchange.between_children.get(p)?;
    let parent = r.ctx.tree.node(p);
    // A concave parent whose own self-link follows the cap's rule hands its children's pairs to the exact
    // kernels (inside a sphere, an even spread over a hemisphere was 2% off at its faces).
    let cap_parent = r.ctx.concave(p) && !traced_tree_node(parent);
    (!cap_parent
        && parent.faces().len() >= TRACED_MIN_FACES
        && one_sided_tree_node(r.node())
        && one_sided_tree_node(s.node()))
    .then_some(*traced)
}

/// A link that transfers nothing but tells the oracle how much it might: form-factor bounds `f_rs`, `f_sr`.
fn bound_only(src_id: u32, f_rs: f64, f_sr: f64) -> Link {
    Link {
        source: src_id,
        coefficient: 0.0,
        f_recv: f_rs as f32,
        f_src: f_sr as f32,
        spread: f_rs.max(f_sr) as f32,
        visibility: 1.0,
        overlap: false,
        clustered: true,
    }
}

/// Whether `flat` has one orientation and all of `other` lies behind or in its plane, so that nothing passes
/// between them (coplanar parts, such as tiles of one floor, would otherwise touch and be refined to their
/// faces). `size` scales the tolerance of "in the plane".
fn behind_flat(flat: &FaceNode<'_>, other: &FaceNode<'_>, size: f64) -> bool {
    let cone = flat.cone();
    if flat.is_volume() || cone.half_angle >= FLAT_CONE {
        return false;
    }
    let (n, c) = (cone.axis, flat.centroid());
    let tol = 1e-9 * (size + flat.bound().radius);
    other.hull().iter().all(|p| n.dot(*p - c) <= tol)
}

/// Per end of a link, whether nothing of it faces the other and whether some face might see the link from
/// behind: with α the angle between the node's cone axis and `toward` (the direction to the other end), θ
/// the cone's half-angle and σ the link's `spread`, α − θ − σ ≥ 90° and α + θ + σ > 90°. A volume is
/// isotropic: neither.
fn facing(n: &FaceNode<'_>, toward: DVec3, spread: f64) -> (bool, bool) {
    if n.is_volume() {
        return (false, false);
    }
    let c = n.cone();
    let alpha = angle_between(c.axis, toward);
    (
        alpha - c.half_angle - spread >= HALF_PI,
        alpha + c.half_angle + spread > HALF_PI,
    )
}

/// How end `n` of a link takes (or sends) light along `toward`, the unit direction between the two ends'
/// bound centres: exactly by its vector (a volume, a flat node, or a curved node whose faces all face the
/// other end, α + θ ≤ 90°), else by the least-squares line of the clamped cosine over the spread of its
/// faces' cosines ([`CosineFit::of_node`], from the node's normal moments, within the range its cone allows).
/// The link's spread σ is left out, as the point transfer itself takes the link along one direction: when the
/// fit spanned the cone's range, widening that range by σ raised the fitted offsets, and the concentric
/// spheres' furnace went from 0.2% low to 1.5% high.
fn cosine_fit(n: &FaceNode<'_>, toward: DVec3) -> CosineFit {
    match n {
        FaceNode::Cluster(c) => CosineFit::of_node(c.node(), toward),
        FaceNode::Volume(_) | FaceNode::Patch(_) => CosineFit::FACING,
    }
}

/// The unit direction from `src`'s bound centre to `recv`'s, as the link was made with; `None` for
/// coincident centres.
fn bound_direction(recv: &FaceNode<'_>, src: &FaceNode<'_>) -> Option<DVec3> {
    let between = recv.bound().centre - src.bound().centre;
    let dist = between.length();
    (dist > 0.0 && dist.is_finite()).then(|| between / dist)
}

/// Direction and squared distance from `src` to `recv` centroids.
fn centroid_geometry(recv: DVec3, src: DVec3) -> (DVec3, f64) {
    let v = recv - src;
    (v.normalize_or_zero(), v.length_squared())
}

/// The point transfer's coefficient g = V/(π r²), capped so that neither end's form factor exceeds one:
/// F_RS ≤ g A_S ≤ 1 and F_SR ≤ g A_R ≤ 1 (close or touching clusters would otherwise gain energy).
fn point_coefficient(v: f64, r2: f64, area_r: f64, area_s: f64) -> f64 {
    (v / (std::f64::consts::PI * r2)).min(v / area_r.max(area_s))
}

const HALF_PI: f64 = std::f64::consts::FRAC_PI_2;

/// Relative slack of the test for touching bounds, |c_R − c_S| ≤ (r_R + r_S)(1 + `TANGENT`): the bounding
/// spheres of an octree's diagonal neighbours are exactly tangent, so without slack rounding decided whether
/// they touch, and the answer changed with the scene's scale (2.7e-7 between × 1e-4 and × 1e4).
const TANGENT: f64 = 1e-9;

impl<'a> Transport<FaceNode<'a>> for VectorTransport<'a> {
    type Irradiance = ClampedIrradiance;
    type Exitance = [DVec3; 3];
    /// Per unit flux: g (−d) for a vector link (b g (−d) and a g when its receiver straddles it), c n for a
    /// patch link's scalar c.
    type Coefficient = LinkCoefficient;
    type Link = Link;
    type Flux = Rgb;

    fn may_interact(&self, _recv: &FaceNode<'a>, _src: &FaceNode<'a>) -> bool {
        true
    }

    fn link(
        &self,
        recv: &FaceNode<'a>,
        recv_id: u32,
        src: &FaceNode<'a>,
        src_id: u32,
    ) -> Option<Link> {
        if let (FaceNode::Patch(r), FaceNode::Patch(s)) = (recv, src) {
            return self.patches.patch_link(r, s, src_id);
        }
        if recv_id == src_id {
            if recv.is_volume() {
                // A volume's self-link carries nothing: it is refined into its children's links.
                return Some(Link::overlapping(src_id));
            }
            let theta = recv.cone().half_angle;
            if theta < FLAT_CONE {
                return None;
            }
            if let Some(flux) = traced_self(recv) {
                // Split while it could carry more than ε, into the children's self-links and the traced
                // exchange between them; kept, it spreads what the node sends onto itself evenly.
                let f = (flux / recv.area()).min(1.0);
                return (f > 0.0).then(|| {
                    let mut l = bound_only(src_id, f, f);
                    l.coefficient = f;
                    l
                });
            }
            if !recv.sees_itself() {
                // A wide node (a closed part, a slab) or a small one whose children do not face each other:
                // with traced factors, split while what it could send onto itself exceeds ε, so that its
                // one-sided parts (or its faces' exact kernels) carry it; it carries nothing itself.
                let FaceNode::Cluster(c) = recv else {
                    return None;
                };
                let n = c.id as usize;
                let f = c
                    .ctx
                    .exchange
                    .onto_itself
                    .get(n)
                    .map_or(0.0, |x| x / recv.area());
                return (f > 0.0 && !c.node().is_leaf())
                    .then(|| bound_only(src_id, f.min(1.0), f.min(1.0)));
            }
            if recv.children_are_faces() {
                // Two faces that see each other: the cap's share below underestimates what flat facets
                // exchange across their shared edge (measured on a 48-face furnace sphere: 9.1e-4 against
                // 3.6e-4 to 9.9e-3 at points of the faces, rows summing to 0.9979), so the pair is split into
                // the faces' exact near-face links.
                return Some(Link::overlapping(src_id));
            }
            let f = (0.5 * (1.0 - theta.min(std::f64::consts::PI).cos())).min(1.0);
            let mut l = bound_only(src_id, f, f);
            l.coefficient = f;
            return Some(l);
        }
        let (rb, sb) = (recv.bound(), src.bound());
        if behind_flat(recv, src, sb.radius) || behind_flat(src, recv, rb.radius) {
            return None;
        }
        if let Some(l) = self.near_face_link(recv, src, src_id) {
            return l;
        }
        if let Some(flux) = traced_between(recv, src) {
            // Children of a node whose self-link is traced: the traced exchange between them, spread evenly
            // over the receiver; never refined (its total is known, and what their parts exchange is their
            // own self-links' and their children's).
            let f = flux / recv.area();
            return (f > 0.0).then(|| {
                let mut l = bound_only(src_id, 0.0, 0.0);
                l.coefficient = f;
                l
            });
        }
        let between = rb.centre - sb.centre;
        let dist = between.length();
        let (ar, as_) = (recv.area(), src.area());
        let volume_end = recv.is_volume() || src.is_volume();
        if dist <= (rb.radius + sb.radius) * (1.0 + TANGENT) {
            if volume_end {
                // A volume and something within its box: refined until the ends are apart (Sillion 1995).
                return Some(Link::overlapping(src_id));
            }
            if !(ar > 0.0 && as_ > 0.0) {
                return None;
            }
            // Touching clusters: no point transfer (between touching clusters the centroid transfer can
            // exceed what any face sees, and the solution diverged on boxes flush against walls); the oracle
            // splits the pair until it is below ε, and patches meet through the exact kernel.
            let l = bound_only(src_id, (as_ / ar).min(1.0), (ar / as_).min(1.0));
            return Some(l);
        }
        let d_c = between / dist;
        let spread = ((rb.radius + sb.radius) / dist).min(1.0).asin();
        let ((away_s, straddle_s), (away_r, straddle_r)) =
            (facing(src, d_c, spread), facing(recv, -d_c, spread));
        // Nothing of one end faces the other.
        if away_s || away_r {
            return None;
        }
        let (_, r2) = centroid_geometry(recv.centroid(), src.centroid());
        if r2 <= 0.0 {
            return Some(Link::overlapping(src_id));
        }
        let gap = dist - rb.radius - sb.radius;
        let pi_g2 = std::f64::consts::PI * gap * gap;
        let (f_rs, f_sr) = ((as_ / pi_g2).min(1.0), (ar / pi_g2).min(1.0));
        // Some face of an end might see the link from behind: the vector form does not hold; split, unless
        // the link's geometric estimate is already below the final ε (then its error is too).
        if (straddle_s || straddle_r) && self.above_final_epsilon(recv, f_rs, f_sr) {
            return Some(Link::overlapping(src_id));
        }
        let v = self.visibility(recv, src);
        if v <= 0.0 {
            // Every sampled segment is blocked. With few rays that is no proof that nothing passes: a source
            // partly hidden (behind the inner of two concentric spheres) would be lost whole, and the more
            // links a finer ε makes, the more such losses (with one ray, the concentric spheres' furnace went
            // from 3.2% low at ε = 1e-3 to 5.7% at 1e-4). So the pair is split while it could carry more
            // than ε unoccluded, as a patch link with no visible sample is kept for the oracle to split.
            return self
                .above_final_epsilon(recv, f_rs, f_sr)
                .then(|| Link::overlapping(src_id));
        }
        Some(Link {
            source: src_id,
            coefficient: point_coefficient(v, r2, ar, as_),
            f_recv: f_rs as f32,
            f_src: f_sr as f32,
            spread: f_rs.max(f_sr) as f32,
            visibility: v as f32,
            overlap: false,
            clustered: true,
        })
    }

    fn gather_at(&self, recv: &FaceNode<'a>, src: &FaceNode<'a>) -> GatherAt {
        match (recv, src) {
            (FaceNode::Patch(_), FaceNode::Patch(_)) => self.patches.patch_gather_at(),
            // A near face's exact irradiance varies over the receiver as much as it matters: evaluated at
            // each leaf below the receiver (at a patch leaf, over its own Gauss points, as the patch links it
            // shares a row with), so a leaf's row sums exact point-to-polygon factors at the same points.
            // Evaluated once at the receiver's centroid and pushed, a patch leaf near the receiver's edge got
            // up to 40% more than its factor, and a furnace sphere's rows summed to 1.014 (divergence at
            // ρ = 0.999).
            _ if near_single_face(recv, src) => GatherAt::Leaves,
            _ => GatherAt::Receiver,
        }
    }

    fn own_visibility(&self, target: &FaceNode<'a>, src: &FaceNode<'a>, link: &Link) -> bool {
        matches!((target, src), (FaceNode::Patch(_), FaceNode::Patch(_)))
            && self.patches.patch_own_visibility(link)
    }

    fn coefficient(
        &self,
        target: &FaceNode<'a>,
        src: &FaceNode<'a>,
        link: &Link,
        at_receiver: bool,
    ) -> LinkCoefficient {
        if !link.clustered {
            if let (FaceNode::Patch(t), FaceNode::Patch(s)) = (target, src) {
                return LinkCoefficient::vector(
                    t.normal * self.patches.patch_coefficient(t, s, link, at_receiver),
                );
            }
            // A near single-face source: its exact irradiance vector times the link's visibility, at a cluster
            // target's centroid, or the point-to-polygon factor over a patch target's Gauss points.
            if let Some(s) = source_patch(src) {
                if let FaceNode::Patch(t) = target {
                    return LinkCoefficient::vector(
                        t.normal * (self.patches.kernel_mean(t, &s) * link.coefficient),
                    );
                }
                let plane = |y: DVec3| (y - s.polygon.vertices()[0]).dot(s.polygon.vector_area());
                let c = LinkCoefficient::vector(
                    point_polygon_vector(target.centroid(), &s.polygon) * link.coefficient,
                );
                let j = self.jacobian(target, |y| {
                    (plane(y) > 0.0).then(|| point_polygon_vector(y, &s.polygon))
                });
                return j.map_or(c, |j| c.with_gradient(j * link.coefficient));
            }
        }
        if target.key() == src.key() {
            if traced_self(target).is_some() {
                // A traced self-link: its share of the node's own mean radiosity, on every face.
                return LinkCoefficient::traced(link.coefficient);
            }
            // A self-link: the cap's share f of its own mean radiosity, along its axis.
            return LinkCoefficient::vector(target.cone().axis * link.coefficient);
        }
        if traced_between(target, src).is_some() {
            return LinkCoefficient::from_sibling(link.coefficient);
        }
        let (d, r2) = centroid_geometry(target.centroid(), src.centroid());
        let d_c = bound_direction(target, src);
        let fit = d_c.map_or(CosineFit::FACING, |d_c| cosine_fit(target, -d_c));
        let c = fit.coefficient(-d, link.coefficient);
        // The point field's Jacobian, unless the transfer is capped (g = V/max(A_R, A_S) no longer falls as
        // 1/r²); uncapped, g = V/(π r²), so V = g π r².
        let pi_r2 = std::f64::consts::PI * r2;
        if pi_r2 < target.area().max(src.area()) || fit.slope == 0.0 {
            return c;
        }
        let v = link.coefficient * pi_r2;
        // The source's cosine turns with the direction where every face of it faces the receiver.
        let axis = (!src.is_volume()
            && d_c.is_none_or(|d_c| cosine_fit(src, d_c) == CosineFit::FACING))
        .then(|| src.cone().axis);
        let s = src.centroid();
        let j = self.jacobian(target, |y| point_field(y, s, axis, d));
        j.map_or(c, |j| c.with_gradient(j * (fit.slope * v)))
    }

    fn emit(
        &self,
        view: &NodeView<'_, FaceNode<'a>>,
        b: &[Rgb],
        x: &[[DVec3; 3]],
        recv: u32,
        link: &Link,
    ) -> Rgb {
        let s = link.source as usize;
        if !link.clustered
            || link.source == recv
            || traced_between(&view.nodes[recv as usize], &view.nodes[s]).is_some()
        {
            return b[s];
        }
        if view.nodes[s].is_volume() {
            // An isotropic source: projected area A/4 toward every direction (Sillion 1995).
            return b[s] * (0.25 * view.nodes[s].area());
        }
        let (r, src) = (&view.nodes[recv as usize], &view.nodes[s]);
        let (d, _) = centroid_geometry(r.centroid(), src.centroid());
        let fit = bound_direction(r, src).map_or(CosineFit::FACING, |d_c| cosine_fit(src, d_c));
        fit.sent(&x[s], b[s] * src.area(), d)
    }

    fn weighs_source_leaves(&self, recv: &FaceNode<'a>, link: &Link) -> bool {
        PatchKernel::sends_source_radiosity(link) && recv.patch().is_some()
    }

    fn source_leaf_weight(&self, leaf: &FaceNode<'a>, recv: &FaceNode<'a>) -> Option<f64> {
        Some(self.patches.source_weight(leaf.patch()?, recv.patch()?))
    }

    fn open_share(&self, leaf: &FaceNode<'a>) -> Option<f64> {
        Transport::<Patch>::open_share(&self.patches, leaf.patch()?)
    }

    fn deliver(&self, h: &mut ClampedIrradiance, c: &LinkCoefficient, flux: Rgb) {
        for k in 0..3 {
            h.vector[k] += c.vector * flux[k];
            h.gradient[k] += c.gradient * flux[k];
        }
        h.isotropic += flux * c.isotropic;
        h.traced += flux * c.traced;
        h.from_sibling += flux * c.from_sibling;
    }

    fn push(
        &self,
        parent: &FaceNode<'a>,
        child: &FaceNode<'a>,
        h: &ClampedIrradiance,
    ) -> ClampedIrradiance {
        // The parent's field at the child's centroid (unchanged where the parent gathered no Jacobian), and
        // its traced light by where the trace's rays landed: its self-exchange in proportion to how much of
        // their view the parts' mesh fills, what siblings sent by where light from beyond landed.
        let mut down = h.moved(child.centroid() - parent.centroid());
        if let (FaceNode::Cluster(p), FaceNode::Cluster(c)) = (parent, child) {
            debug_assert_eq!(c.node().parent(), Some(p.id as usize));
            (down.traced, down.outside) = p.ctx.exchange.hand_down(
                c.id as usize,
                [down.traced, down.from_sibling, down.outside],
            );
        } else {
            down.traced += down.from_sibling + down.outside;
            down.outside = Rgb::ZERO;
        }
        down.from_sibling = Rgb::ZERO;
        down
    }

    fn reflect(
        &self,
        leaf: &FaceNode<'a>,
        h: &ClampedIrradiance,
        with_emission: bool,
    ) -> (Rgb, [DVec3; 3]) {
        match leaf {
            FaceNode::Volume(_) => {
                // An isotropic receiver: its faces' mean irradiance is |e|/4 + s; it sends as a volume (from
                // its radiosity), so no power vector.
                let e = if with_emission {
                    leaf.emission()
                } else {
                    Rgb::ZERO
                };
                let rho = leaf.reflectance();
                let (v, s) = (&h.vector, h.isotropic_total());
                let b = Rgb::new(
                    e[0] + rho[0] * (0.25 * v[0].length() + s[0]),
                    e[1] + rho[1] * (0.25 * v[1].length() + s[1]),
                    e[2] + rho[2] * (0.25 * v[2].length() + s[2]),
                );
                (b, [DVec3::ZERO; 3])
            }
            FaceNode::Patch(p) => {
                let e = if with_emission { p.emission } else { Rgb::ZERO };
                let b = e + p.reflectance * h.at(p.normal);
                (b, std::array::from_fn(|k| p.normal * (b[k] * p.area)))
            }
            FaceNode::Cluster(c) => {
                // Σ ρ_i A_i n_i (n_i·e + s) = M e + s Σ ρ_i A_i n_i, and Σ ρ_i A_i (n_i·e + s) for the
                // area mean (clamped as a whole).
                let node = c.node();
                let i = c.id as usize;
                let rv = &c.ctx.rho_vector[i];
                let (v, s) = (&h.vector, h.isotropic_total());
                let reflected: [DVec3; 3] =
                    std::array::from_fn(|k| node.m[k].mul_vec(v[k]) + rv[k] * s[k]);
                let p = if with_emission {
                    std::array::from_fn(|k| node.p_e[k] + reflected[k])
                } else {
                    reflected
                };
                let rho_area = c.ctx.rho_area[i];
                let e = if with_emission {
                    c.ctx.emitted[i]
                } else {
                    Rgb::ZERO
                };
                let b = if node.area > 0.0 {
                    Rgb::new(
                        e[0] + (rv[0].dot(v[0]) + rho_area[0] * s[0]).max(0.0),
                        e[1] + (rv[1].dot(v[1]) + rho_area[1] * s[1]).max(0.0),
                        e[2] + (rv[2].dot(v[2]) + rho_area[2] * s[2]).max(0.0),
                    ) / node.area
                } else {
                    Rgb::ZERO
                };
                (b, p)
            }
        }
    }

    fn uniform_response(&self, leaf: &FaceNode<'a>) -> (Rgb, [DVec3; 3]) {
        match leaf {
            // Unit irradiance from every direction: B = ρ.
            FaceNode::Volume(_) => (leaf.reflectance(), [DVec3::ZERO; 3]),
            FaceNode::Patch(p) => (
                p.reflectance,
                std::array::from_fn(|k| p.normal * (p.reflectance[k] * p.area)),
            ),
            FaceNode::Cluster(c) => (leaf.reflectance(), c.ctx.rho_vector[c.id as usize]),
        }
    }

    fn unit_response(&self, leaf: &FaceNode<'a>) -> Option<(Rgb, [DVec3; 3])> {
        // Every face sending B = 1 on every channel: a volume sends from its radiosity alone, a face's power
        // vector is A n and a cluster's the sum of its faces', Σ A_i n_i.
        Some(match leaf {
            FaceNode::Volume(_) => (Rgb::ONE, [DVec3::ZERO; 3]),
            FaceNode::Patch(p) => (Rgb::ONE, [p.normal * p.area; 3]),
            FaceNode::Cluster(c) => (Rgb::ONE, [c.node().vector_area; 3]),
        })
    }
}

//! Area-to-area form factor with visibility (Wallace, Elmquist & Haines 1989 split kernel and visibility this way):
//!
//! F_ij ≈ V_ij · Σ_k w_k F_{dA(x_k)→A_j},  (x_k, w_k) a product Gauss–Legendre rule over A_i,
//!
//! the receiver-side quadrature of the exact point-to-polygon kernel (so unoccluded point receivers are exact
//! and the integrable singularity at contact is handled analytically), times a visibility fraction V_ij from
//! rays between stratified, jittered points on both elements (Wallace, Elmquist & Haines 1989 use the same
//! split of kernel and visibility). The ray count is a parameter ([`VisibilitySampling`]).
//!
//! The receiver rule is m × m Gauss–Legendre points over the bilinear parametrisation of a quad (a triangle is
//! the quad a, b, c, c, collapsed at c), weighted by the parametrisation's Jacobian, so the weights are exact
//! area fractions for any planar convex quad. The point kernel is analytic wherever the source lies wholly
//! above the receiver's horizon, and there the rule converges exponentially in m (parallel unit squares at
//! distance 1: relative error 2e-1, 7e-3, 8e-6, 4e-11 for m = 1, 2, 4, 8); where the source touches the
//! receiver along a shared edge the kernel's derivatives are singular at the edge's ends and the error falls
//! as m⁻⁴; where the source crosses the receiver's horizon the kernel has a kink and it falls as m⁻².
//! m = 1 is the centroid. Any rule's weights sum to 1, so in a closed convex enclosure the unoccluded row sums
//! Σ_j F_ij are 1 to rounding, as they are for every receiver point.

use super::gauss_legendre;
use glam::DVec3;
use smallvec::SmallVec;

use radlab_scene::{FaceId, Polygon, sampling};
use radlab_visibility::{Accel, Segment};

/// How a visibility fraction between two elements is estimated.
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum VisibilitySampling {
    /// Assume the two are mutually visible (no rays): exact only in convex enclosures.
    Unoccluded,
    /// One ray between the two centroids.
    Centre,
    /// n × n rays between stratified jittered points (n = 4 gives the 16 rays of the literature).
    #[default]
    Jittered4x4,
    /// 2 × 2 stratified jittered rays.
    Jittered2x2,
    /// 8 × 8 stratified jittered rays.
    Jittered8x8,
}

impl VisibilitySampling {
    /// Whether the estimate samples points over both areas (the jittered grids), so that the share of an
    /// element from which nothing is visible enters its form factors ([`crate::open_fraction`]).
    pub fn is_area_sampled(self) -> bool {
        matches!(
            self,
            Self::Jittered2x2 | Self::Jittered4x4 | Self::Jittered8x8
        )
    }

    /// Rays cast per estimate.
    pub fn rays(self) -> u32 {
        match self {
            Self::Unoccluded => 0,
            Self::Centre => 1,
            Self::Jittered2x2 => 4,
            Self::Jittered4x4 => 16,
            Self::Jittered8x8 => 64,
        }
    }

    fn side(self) -> u32 {
        match self {
            Self::Jittered2x2 => 2,
            Self::Jittered4x4 => 4,
            Self::Jittered8x8 => 8,
            _ => 1,
        }
    }
}

/// Fraction of rays between element `a` (on face `fa`) and `b` (on face `fb`) that are unobstructed.
/// `stream` selects the random stream (derive it from the pair's indices for determinism).
///
/// The n × n jittered samples on each element are paired through a random permutation of the strata, drawn
/// afresh for every call: each ray then joins two points distributed uniformly and independently over the
/// elements (for triangles and parallelograms), while the samples stay stratified on both elements. Each pair
/// is weighted by its kernel, w = cos θ cos θ' / r² ([`pair_kernel`]), so the estimate is the ratio estimator
/// (consistent, its bias falling as 1/n) of the kernel-weighted visibility V = ∫∫ G v / ∫∫ G, the factor that turns the unoccluded form factor into the
/// occluded one (Wallace, Elmquist & Haines 1989 weight their visibility samples by their form-factor share
/// alike). An unweighted fraction biases V × F low wherever visibility and kernel are correlated: a pair behind
/// either plane (zero kernel) would count as blocked, and near-horizon pairs (small kernel) are the ones a
/// curved surface's own faces block. No facing pair among the samples gives 0. The facing pairs' rays are cast
/// as one packet ([`Accel::visible_many`]: the same answers as one at a time).
#[allow(clippy::too_many_arguments)]
pub fn visibility_fraction(
    accel: &Accel,
    a: &Polygon,
    fa: FaceId,
    b: &Polygon,
    fb: FaceId,
    how: VisibilitySampling,
    seed: u64,
    stream: u64,
) -> f64 {
    match how {
        VisibilitySampling::Unoccluded => 1.0,
        VisibilitySampling::Centre => {
            if accel.visible_between(a.centroid(), fa, b.centroid(), fb) {
                1.0
            } else {
                0.0
            }
        }
        _ => {
            let n = how.side() as usize;
            let total = n * n;
            let mut r = sampling::rng(seed, stream);
            // Fisher–Yates shuffle of the strata of `b`.
            let mut perm = [0u8; 64];
            for (k, p) in perm.iter_mut().enumerate().take(total) {
                *p = k as u8;
            }
            for k in (1..total).rev() {
                let j = ((sampling::uniform(&mut r) * (k + 1) as f64) as usize).min(k);
                perm.swap(k, j);
            }
            let (na, nb) = (a.normal(), b.normal());
            // The facing pairs and their kernels, then their visibility as one packet (held inline, filled
            // only as far as this estimate's rays: most cast 4 or 16, not 64).
            let mut weights: SmallVec<[f64; 64]> = SmallVec::new();
            let mut segments: SmallVec<[Segment; 64]> = SmallVec::new();
            for (k, &m) in perm.iter().enumerate().take(total) {
                let m = m as usize;
                let u =
                    |x: usize, r: &mut sampling::Rng| (x as f64 + sampling::uniform(r)) / n as f64;
                let x = a.point_at(u(k % n, &mut r), u(k / n, &mut r));
                let y = b.point_at(u(m % n, &mut r), u(m / n, &mut r));
                let w = pair_kernel(x, na, y, nb);
                if w <= 0.0 {
                    continue;
                }
                weights.push(w);
                segments.push(Segment {
                    p: x,
                    fp: fa,
                    q: y,
                    fq: fb,
                });
            }
            let mut visible = [false; 64];
            let visible = &mut visible[..segments.len()];
            accel.visible_many(&segments, visible);
            let (mut seen, mut facing) = (0.0, 0.0);
            for (&w, &v) in weights.iter().zip(visible.iter()) {
                facing += w;
                if v {
                    seen += w;
                }
            }
            if facing > 0.0 { seen / facing } else { 0.0 }
        }
    }
}

/// The point-to-point kernel cos θ cos θ' / r² between x (normal `nx`) and y (normal `ny`), zero unless each
/// point is in front of the other's plane (π G of the radiosity equation).
pub fn pair_kernel(x: DVec3, nx: DVec3, y: DVec3, ny: DVec3) -> f64 {
    let v = y - x;
    let (cx, cy) = (nx.dot(v), -ny.dot(v));
    if cx <= 0.0 || cy <= 0.0 {
        return 0.0;
    }
    let r2 = v.length_squared();
    cx * cy / (r2 * r2)
}

/// The receiver rule over `poly`: m × m product Gauss–Legendre points of the bilinear parametrisation (a
/// triangle as the quad a, b, c, c collapsed at c), each with its weight w_s w_t |∂p/∂s × ∂p/∂t| (not yet
/// normalised: the weights sum to the area, to rounding). m = 0 is taken as 1 (the bilinear centre; see
/// [`receiver_points`] for the centroid rule).
fn receiver_rule(poly: &Polygon, m: u32) -> impl Iterator<Item = (DVec3, f64)> + '_ {
    let v = poly.vertices();
    let (a, b, c, d) = if v.len() == 3 {
        (v[0], v[1], v[2], v[2])
    } else {
        (v[0], v[1], v[2], v[3])
    };
    let rule = gauss_legendre::rule(m.max(1) as usize);
    let n = rule.len();
    (0..n * n).map(move |k| {
        let ((t, wt), (s, ws)) = (rule[k / n], rule[k % n]);
        // Points along the edges a→b (t = 0) and d→c (t = 1), and the derivative along t.
        let p0 = a.lerp(b, s);
        let p1 = d.lerp(c, s);
        let x = p0.lerp(p1, t);
        let ds = (b - a).lerp(c - d, t);
        let jac = ds.cross(p1 - p0).length();
        (x, wt * ws * jac)
    })
}

/// The receiver quadrature of the module documentation as points with weights summing to 1 (an area mean):
/// m × m Gauss–Legendre points for m ≥ 2, the centroid alone for m ≤ 1. Every receiver-side integral of the
/// point kernel (matrix, progressive and hierarchical radiosity) uses this rule.
pub fn receiver_points(poly: &Polygon, m: u32) -> Vec<(DVec3, f64)> {
    if m <= 1 {
        return vec![(poly.centroid(), 1.0)];
    }
    let mut pts: Vec<(DVec3, f64)> = receiver_rule(poly, m).collect();
    let total: f64 = pts.iter().map(|p| p.1).sum();
    let uniform = 1.0 / pts.len() as f64;
    for p in &mut pts {
        p.1 = if total > 0.0 { p.1 / total } else { uniform };
    }
    pts
}

/// Unoccluded form factor from receiver polygon `recv` to the front of source `src`: the point-to-polygon
/// factor integrated over the receiver with the m × m product Gauss–Legendre rule described in the module
/// documentation (m = 1: the centroid only; m = 0 is taken as 1). Exact for point-like receivers; see the
/// module documentation for how fast it converges in m.
pub fn polygon_polygon_unoccluded(recv: &Polygon, src: &Polygon, m: u32) -> f64 {
    let n = recv.normal();
    if m <= 1 {
        return super::point_polygon(recv.centroid(), n, src);
    }
    let (mut sum, mut area) = (0.0, 0.0);
    for (x, w) in receiver_rule(recv, m) {
        sum += w * super::point_polygon(x, n, src);
        area += w;
    }
    if area > 0.0 { sum / area } else { 0.0 }
}

/// Form factor with visibility: unoccluded quadrature times the visibility fraction. Skips the rays when the
/// unoccluded factor is zero.
#[allow(clippy::too_many_arguments)]
pub fn polygon_polygon(
    accel: &Accel,
    recv: &Polygon,
    f_recv: FaceId,
    src: &Polygon,
    f_src: FaceId,
    quadrature: u32,
    how: VisibilitySampling,
    seed: u64,
    stream: u64,
) -> f64 {
    let f = polygon_polygon_unoccluded(recv, src, quadrature);
    if f <= 0.0 {
        return 0.0;
    }
    f * visibility_fraction(accel, recv, f_recv, src, f_src, how, seed, stream)
}

#[cfg(test)]
mod tests {
    use glam::dvec3;

    use super::*;

    #[test]
    fn receiver_points_give_area_means() {
        // Mean of x² over the unit right triangle: ∫x² dA / A = (1/12)/(1/2) = 1/6 (degree 2: exact at m = 2).
        let t = Polygon::triangle(dvec3(0., 0., 0.), dvec3(1., 0., 0.), dvec3(0., 1., 0.));
        for m in [2, 3, 5] {
            let q: f64 = receiver_points(&t, m)
                .iter()
                .map(|(p, w)| w * p.x * p.x)
                .sum();
            assert!((q - 1.0 / 6.0).abs() < 1e-14, "m {m}: {q}");
        }
        // A trapezoid (not a parallelogram): width 4 − y at height y ∈ [0, 2], so the mean of y is
        // ∫ y(4 − y) dy / ∫ (4 − y) dy = (16/3)/6 = 8/9.
        let z = Polygon::quad(
            dvec3(0., 0., 0.),
            dvec3(4., 0., 0.),
            dvec3(3., 2., 0.),
            dvec3(1., 2., 0.),
        );
        let q: f64 = receiver_points(&z, 2).iter().map(|(p, w)| w * p.y).sum();
        assert!((q - 8.0 / 9.0).abs() < 1e-14, "{q}");
        // m = 1: the centroid, whose mean of any linear function is exact.
        let c: DVec3 = receiver_points(&z, 1).iter().map(|(p, w)| *w * *p).sum();
        assert!((c.y - 8.0 / 9.0).abs() < 1e-14, "{c}");
    }
}

//! Area-to-area form factor with visibility (ALGORITHMS.md, "Area to area"):
//!
//! F_ij ≈ V_ij · (1/m) Σ_k F_{dA(x_k)→A_j},  x_k stratified over A_i,
//!
//! the receiver-side quadrature of the exact point-to-polygon kernel (so unoccluded point receivers are exact
//! and the integrable singularity at contact is handled analytically), times a visibility fraction V_ij from
//! rays between stratified, jittered points on both elements (Wallace, Elmquist & Haines 1989 use the same
//! split of kernel and visibility). The ray count is a parameter ([`VisibilitySampling`]).

use glam::DVec3;

use crate::{Accel, FaceId, Polygon, sampling};

/// How a visibility fraction between two elements is estimated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
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
            let n = how.side();
            let mut r = sampling::rng(seed, stream);
            let mut seen = 0u32;
            // Pair stratum k on `a` with stratum σ(k) on `b`, σ a fixed scramble, so the pairs cover both
            // elements without correlating positions.
            let total = n * n;
            for k in 0..total {
                let (i, j) = (k % n, k / n);
                let m = (k * 7 + 3) % total;
                let (p, q) = (m % n, m / n);
                let u =
                    |x: u32, r: &mut sampling::Rng| (x as f64 + sampling::uniform(r)) / n as f64;
                let x = a.point_at(u(i, &mut r), u(j, &mut r));
                let y = b.point_at(u(p, &mut r), u(q, &mut r));
                if accel.visible_between(x, fa, y, fb) {
                    seen += 1;
                }
            }
            seen as f64 / total as f64
        }
    }
}

/// Unoccluded form factor from receiver polygon `recv` to source `src`: the mean of the point-to-polygon
/// factor over `m × m` midpoint-stratified receiver points (m = 1: the centroid only).
pub fn polygon_polygon_unoccluded(recv: &Polygon, src: &Polygon, m: u32) -> f64 {
    let n = recv.normal();
    let m = m.max(1);
    if m == 1 {
        return super::point_polygon(recv.centroid(), n, src);
    }
    let mut sum = 0.0;
    for j in 0..m {
        for i in 0..m {
            let x: DVec3 = recv.point_at((i as f64 + 0.5) / m as f64, (j as f64 + 0.5) / m as f64);
            sum += super::point_polygon(x, n, src);
        }
    }
    // point_at is uniform for triangles and parallelograms; weight by the local area for general quads
    // would be more exact, but meshed elements are parallelograms or triangles.
    sum / (m * m) as f64
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

//! Kernel density estimation on a planar polygonal domain with the boundary bias removed by local linear
//! estimation (Walter, Hubbard, Shirley & Greenberg 1997, "Global illumination using local linear density
//! estimation", ACM TOG 16(3); the estimator is the two-dimensional local linear density estimator of Jones
//! 1993, "Simple boundary correction for kernel density estimation", Statistics and Computing 3).
//!
//! Particles X_i with weights w_i land on a domain D (a surface's faces in its own 2-D coordinates). With the
//! Epanechnikov kernel K_h(u) = K̃(u/h)/h², K̃(ξ) = (2/π)(1 − |ξ|²) on the unit disc, the plain estimate
//! f̂(x) = Σ_i w_i K_h(X_i − x) has bias O(h²) inside D but O(h) within h of D's boundary, where part of the
//! kernel's disc hangs outside D (the estimate falls to about 1/2 on an edge and 1/4 in a right-angled corner).
//! The local linear estimate fits a + bᵀ(y − x) to the density by kernel-weighted least squares over D:
//!
//! f̂(x) = e₁ᵀ M⁻¹ Σ_i w_i K̃(ξ_i) (1, ξ_i)ᵀ / h²,  ξ_i = (X_i − x)/h,
//! M = ∫_{D_x} K̃(ξ) (1, ξ)(1, ξ)ᵀ dξ,  D_x = (D − x)/h ∩ unit disc,
//!
//! so every particle counts with the weight K̃(ξ)·(l₀ + l₁ξ₁ + l₂ξ₂), l = M⁻¹e₁. Its expectation reproduces
//! every linear density exactly, at edges and corners too; inside D (D_x the whole disc) M = diag(1, 1/6, 1/6)
//! and it is the plain estimate. The moments M are integrals of polynomials of degree ≤ 4 over D_x: each face
//! is clipped to a regular 64-gon inscribed in the unit disc (the kernel is below 2.4e-3 of its peak in the
//! sliver left out, about 1e-5 of a0) and integrated exactly by a degree-5 triangle rule (Dunavant 1985).
//! The renormalised (local constant) estimate, l = (1/M₀₀, 0, 0), removes the O(h) bias only where the
//! density is flat; the plain one not at all. Both are kept for comparison.

use glam::{DMat3, DVec2, DVec3};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Sides of the polygon standing in for the kernel's disc when it is clipped to a face.
const DISC_SIDES: usize = 64;
/// det M (normalised) below this fraction of the whole disc's is treated as singular (a domain thinner than
/// about 1e-3 h, a sliver on its own): the estimate falls back to the renormalised one.
const SINGULAR_DET: f64 = 1e-9;
/// M₀₀ below this: the domain barely meets the disc; no kernel estimate (the caller uses the histogram).
const EMPTY_MASS: f64 = 1e-12;

/// How the kernel estimate treats a surface's boundary.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum BoundaryCorrection {
    /// Local linear estimation (Walter et al. 1997): unbiased for linear densities up to the boundary; bias
    /// O(h²) everywhere. The default.
    #[default]
    LocalLinear,
    /// The kernel renormalised by its mass inside the surface (local constant): exact at the boundary for a
    /// flat density only, O(h) bias where the density slopes.
    Renormalized,
    /// The plain kernel estimate (Silverman 1986): O(h) bias within h of the boundary, about half the density
    /// on an edge and a quarter in a right-angled corner.
    None,
}

/// The normalised Epanechnikov kernel K̃(ξ) = (2/π)(1 − |ξ|²) for |ξ|² < 1, else 0 (unit mass on the unit
/// disc), from |ξ|².
pub fn epanechnikov(r2: f64) -> f64 {
    if r2 < 1.0 {
        std::f64::consts::FRAC_2_PI * (1.0 - r2)
    } else {
        0.0
    }
}

/// A planar domain: convex polygons (counter-clockwise) tiling it, and its boundary segments (edges of one
/// polygon only; an edge met by none of the others counts, so a T-junction is boundary too, which only
/// costs time).
#[derive(Clone, Debug, Default)]
pub struct Domain {
    polygons: Vec<Vec<DVec2>>,
    boxes: Vec<(DVec2, DVec2)>,
    boundary: Vec<[DVec2; 2]>,
    area: f64,
}

/// A degree-5 rule on a triangle (Dunavant 1985, 7 points): barycentric coordinates and weights.
const DUNAVANT5: [([f64; 3], f64); 7] = [
    ([1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0], 0.225),
    (
        [0.059715871789770, 0.470142064105115, 0.470142064105115],
        0.132394152788506,
    ),
    (
        [0.470142064105115, 0.059715871789770, 0.470142064105115],
        0.132394152788506,
    ),
    (
        [0.470142064105115, 0.470142064105115, 0.059715871789770],
        0.132394152788506,
    ),
    (
        [0.797426985353087, 0.101286507323456, 0.101286507323456],
        0.125939180544827,
    ),
    (
        [0.101286507323456, 0.797426985353087, 0.101286507323456],
        0.125939180544827,
    ),
    (
        [0.101286507323456, 0.101286507323456, 0.797426985353087],
        0.125939180544827,
    ),
];

fn cross(a: DVec2, b: DVec2) -> f64 {
    a.x * b.y - a.y * b.x
}

fn signed_area(p: &[DVec2]) -> f64 {
    (1..p.len().saturating_sub(1))
        .map(|k| cross(p[k] - p[0], p[k + 1] - p[0]))
        .sum::<f64>()
        / 2.0
}

/// Keeps the part of convex polygon `p` where a + b·ξ ≥ 0 (Sutherland & Hodgman 1974).
fn clip_half_plane(p: &[DVec2], a: f64, b: DVec2) -> Vec<DVec2> {
    let mut out = Vec::with_capacity(p.len() + 1);
    for k in 0..p.len() {
        let (u, v) = (p[k], p[(k + 1) % p.len()]);
        let (su, sv) = (a + b.dot(u), a + b.dot(v));
        if su >= 0.0 {
            out.push(u);
        }
        if (su >= 0.0) != (sv >= 0.0) {
            out.push(u + (v - u) * (su / (su - sv)));
        }
    }
    out
}

/// ∫ g over convex polygon `p` (a fan of triangles, each by the degree-5 rule).
fn integrate_polygon<const N: usize>(p: &[DVec2], g: &impl Fn(DVec2) -> [f64; N]) -> [f64; N] {
    let mut sum = [0.0; N];
    for k in 1..p.len().saturating_sub(1) {
        let (a, b, c) = (p[0], p[k], p[k + 1]);
        let area = cross(b - a, c - a) / 2.0;
        for (bc, w) in DUNAVANT5 {
            let v = g(a * bc[0] + b * bc[1] + c * bc[2]);
            for (s, x) in sum.iter_mut().zip(v) {
                *s += area * w * x;
            }
        }
    }
    sum
}

/// The inscribed 64-gon of the unit disc, counter-clockwise.
fn unit_disc() -> Vec<DVec2> {
    (0..DISC_SIDES)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / DISC_SIDES as f64;
            DVec2::new(t.cos(), t.sin())
        })
        .collect()
}

fn segment_distance2(x: DVec2, a: DVec2, b: DVec2) -> f64 {
    let d = b - a;
    let len2 = d.length_squared();
    let t = if len2 > 0.0 {
        ((x - a).dot(d) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + d * t - x).length_squared()
}

impl Domain {
    /// A domain from convex polygons (either orientation; made counter-clockwise) and its boundary segments.
    pub fn new(polygons: Vec<Vec<DVec2>>, boundary: Vec<[DVec2; 2]>) -> Self {
        let polygons: Vec<Vec<DVec2>> = polygons
            .into_iter()
            .map(|mut p| {
                if signed_area(&p) < 0.0 {
                    p.reverse();
                }
                p
            })
            .collect();
        let boxes = polygons
            .iter()
            .map(|p| {
                p.iter().fold(
                    (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
                    |(lo, hi), &v| (lo.min(v), hi.max(v)),
                )
            })
            .collect();
        let area = polygons.iter().map(|p| signed_area(p)).sum();
        Self {
            polygons,
            boxes,
            boundary,
            area,
        }
    }

    /// The domain's area.
    pub fn area(&self) -> f64 {
        self.area
    }

    /// Approximate heap bytes held.
    pub fn bytes(&self) -> usize {
        self.polygons
            .iter()
            .map(|p| p.capacity() * size_of::<DVec2>() + size_of::<Vec<DVec2>>())
            .sum::<usize>()
            + self.boxes.capacity() * size_of::<(DVec2, DVec2)>()
            + self.boundary.capacity() * size_of::<[DVec2; 2]>()
    }

    /// Whether the disc of radius `h` about `x` (a point of the domain) meets no boundary segment, i.e. lies
    /// wholly in the domain.
    pub fn disc_inside(&self, x: DVec2, h: f64) -> bool {
        let h2 = h * h;
        self.boundary
            .iter()
            .all(|s| segment_distance2(x, s[0], s[1]) >= h2)
    }

    /// ∫ g(ξ) dξ over D_x = (D − x)/h ∩ unit disc (the disc as its inscribed 64-gon where it is clipped),
    /// restricted to a + b·ξ ≥ 0 when `half_plane` is given.
    pub fn integrate<const N: usize>(
        &self,
        x: DVec2,
        h: f64,
        half_plane: Option<(f64, DVec2)>,
        g: &impl Fn(DVec2) -> [f64; N],
    ) -> [f64; N] {
        let mut sum = [0.0; N];
        let disc = unit_disc();
        for (p, &(lo, hi)) in self.polygons.iter().zip(&self.boxes) {
            if lo.x > x.x + h || lo.y > x.y + h || hi.x < x.x - h || hi.y < x.y - h {
                continue;
            }
            let local: Vec<DVec2> = p.iter().map(|&v| (v - x) / h).collect();
            let mut piece = if local.iter().all(|v| v.length_squared() <= 1.0) {
                local.clone()
            } else {
                let mut piece = disc.clone();
                for k in 0..local.len() {
                    let (a, b) = (local[k], local[(k + 1) % local.len()]);
                    // Inside: left of a→b, i.e. cross(b − a, ξ − a) ≥ 0.
                    let e = b - a;
                    let nrm = DVec2::new(-e.y, e.x);
                    piece = clip_half_plane(&piece, -nrm.dot(a), nrm);
                    if piece.len() < 3 {
                        break;
                    }
                }
                piece
            };
            if let Some((a, b)) = half_plane {
                piece = clip_half_plane(&piece, a, b);
            }
            if piece.len() < 3 {
                continue;
            }
            for (s, v) in sum.iter_mut().zip(integrate_polygon(&piece, g)) {
                *s += v;
            }
        }
        sum
    }

    /// The kernel's moments over D_x: ∫ K̃(ξ)·(1, ξ₁, ξ₂, ξ₁², ξ₁ξ₂, ξ₂²) dξ (exact, the whole disc's
    /// (1, 0, 0, 1/6, 0, 1/6), when the disc lies inside the domain).
    pub fn moments(&self, x: DVec2, h: f64) -> [f64; 6] {
        if self.disc_inside(x, h) {
            return [1.0, 0.0, 0.0, 1.0 / 6.0, 0.0, 1.0 / 6.0];
        }
        self.integrate(x, h, None, &|xi: DVec2| {
            let k = std::f64::consts::FRAC_2_PI * (1.0 - xi.length_squared());
            [
                k,
                k * xi.x,
                k * xi.y,
                k * xi.x * xi.x,
                k * xi.x * xi.y,
                k * xi.y * xi.y,
            ]
        })
    }

    /// The coefficients l of the particle weight K̃(ξ)(l₀ + l₁ξ₁ + l₂ξ₂) at `x` with bandwidth `h`, or None
    /// where the domain barely meets the disc (no kernel estimate there).
    pub fn weights(&self, x: DVec2, h: f64, correction: BoundaryCorrection) -> Option<DVec3> {
        if correction == BoundaryCorrection::None {
            return Some(DVec3::X);
        }
        let m = self.moments(x, h);
        if !(m[0] > EMPTY_MASS) {
            return None;
        }
        let renormalized = DVec3::new(1.0 / m[0], 0.0, 0.0);
        if correction == BoundaryCorrection::Renormalized {
            return Some(renormalized);
        }
        let mat = DMat3::from_cols(
            DVec3::new(m[0], m[1], m[2]),
            DVec3::new(m[1], m[3], m[4]),
            DVec3::new(m[2], m[4], m[5]),
        );
        let det = mat.determinant();
        if !(det > SINGULAR_DET / 36.0) {
            return Some(renormalized);
        }
        let l = mat.inverse() * DVec3::X;
        l.is_finite().then_some(l).or(Some(renormalized))
    }

    /// Λ(x) = ∫_{D_x} |l₀ + l₁ξ₁ + l₂ξ₂| K̃(ξ) |ξ|² dξ for weights `l`: the factor of the local linear
    /// estimate's bias bound |E f̂(x) − f(x)| ≤ ½ h² Λ(x) max‖∇²f‖ over the disc (the estimate reproduces
    /// linear densities, so only the Taylor remainder ≤ ½‖∇²f‖ h²|ξ|² is left). 1/3 inside the domain.
    pub fn bias_factor(&self, x: DVec2, h: f64, l: DVec3) -> f64 {
        let g = |xi: DVec2| {
            let r2 = xi.length_squared();
            [(l.x + l.y * xi.x + l.z * xi.y) * std::f64::consts::FRAC_2_PI * (1.0 - r2) * r2]
        };
        let b = DVec2::new(l.y, l.z);
        let pos = self.integrate(x, h, Some((l.x, b)), &g)[0];
        let neg = self.integrate(x, h, Some((-l.x, -b)), &g)[0];
        pos - neg
    }
}

/// The estimate at `x` from particles `points` with weights `w` (brute force; the solver uses a k-d tree):
/// Σ_i w_i K̃(ξ_i)(l·(1, ξ_i)) / h², or None where [`Domain::weights`] gives none.
pub fn estimate(
    domain: &Domain,
    x: DVec2,
    h: f64,
    correction: BoundaryCorrection,
    points: &[DVec2],
    w: &[f64],
) -> Option<f64> {
    let l = domain.weights(x, h, correction)?;
    let mut sum = 0.0;
    for (&p, &wi) in points.iter().zip(w) {
        let xi = (p - x) / h;
        let k = epanechnikov(xi.length_squared());
        if k > 0.0 {
            sum += wi * k * (l.x + l.y * xi.x + l.z * xi.y);
        }
    }
    Some(sum / (h * h))
}

#[cfg(test)]
mod tests {
    use super::*;
    use radlab_scene::sampling;

    fn unit_square() -> Domain {
        let (a, b, c, d) = (
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(0.0, 1.0),
        );
        Domain::new(vec![vec![a, b, c, d]], vec![[a, b], [b, c], [c, d], [d, a]])
    }

    /// The square as two triangles (an interior diagonal): the moments must not depend on the tiling.
    fn split_square() -> Domain {
        let (a, b, c, d) = (
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(0.0, 1.0),
        );
        Domain::new(
            vec![vec![a, b, c], vec![a, c, d]],
            vec![[a, b], [b, c], [c, d], [d, a]],
        )
    }

    #[test]
    fn moments_are_the_disc_and_its_quarter() {
        let sq = split_square();
        // A disc wholly inside, computed by clipping too (a tiling edge crosses it).
        let x = DVec2::new(0.5, 0.5);
        let m = sq.integrate(x, 0.2, None, &|xi: DVec2| {
            [std::f64::consts::FRAC_2_PI * (1.0 - xi.length_squared())]
        });
        assert!((m[0] - 1.0).abs() < 1e-4, "{m:?}");
        // A corner: a quarter of the disc; first moments ∫K̃ξ₁ over the quarter = (2/π)(1/3 − 1/5) = 4/(15π).
        let m = sq.moments(DVec2::ZERO, 0.2);
        assert!((m[0] - 0.25).abs() < 1e-4, "{m:?}");
        let first = 4.0 / (15.0 * std::f64::consts::PI);
        assert!(
            (m[1] - first).abs() < 1e-4 && (m[2] - first).abs() < 1e-4,
            "{m:?}"
        );
        assert!((m[3] - 1.0 / 24.0).abs() < 1e-4, "{m:?}");
        // Same moments from the single quad.
        let q = unit_square().moments(DVec2::ZERO, 0.2);
        for (a, b) in q.iter().zip(m) {
            assert!((a - b).abs() < 1e-12);
        }
    }

    /// n points of density `f` on the unit square by rejection, weights 1/n.
    fn sample(n: usize, seed: u64, f: impl Fn(DVec2) -> f64, fmax: f64) -> Vec<DVec2> {
        let mut rng = sampling::rng(seed, 0);
        let mut pts = Vec::with_capacity(n);
        while pts.len() < n {
            let p = DVec2::new(sampling::uniform(&mut rng), sampling::uniform(&mut rng));
            if sampling::uniform(&mut rng) * fmax < f(p) {
                pts.push(p);
            }
        }
        pts
    }

    /// The estimate and its standard error (the estimate is a mean of n i.i.d. terms).
    fn estimate_se(
        d: &Domain,
        x: DVec2,
        h: f64,
        c: BoundaryCorrection,
        pts: &[DVec2],
    ) -> (f64, f64) {
        let n = pts.len() as f64;
        let l = d.weights(x, h, c).expect("weights");
        let terms: Vec<f64> = pts
            .iter()
            .map(|&p| {
                let xi = (p - x) / h;
                epanechnikov(xi.length_squared()) * (l.x + l.y * xi.x + l.z * xi.y) / (h * h)
            })
            .collect();
        let mean = terms.iter().sum::<f64>() / n;
        let var = terms.iter().map(|t| (t - mean) * (t - mean)).sum::<f64>() / (n - 1.0);
        (mean, (var / n).sqrt())
    }

    const PROBES: [(f64, f64); 5] = [(0.5, 0.5), (0.0, 0.5), (0.5, 1.0), (0.0, 0.0), (1.0, 1.0)];

    #[test]
    fn uniform_density_to_the_corners_only_with_the_correction() {
        let d = unit_square();
        let pts = sample(40_000, 7, |_| 1.0, 1.0);
        let w = vec![1.0 / pts.len() as f64; pts.len()];
        let h = 0.15;
        for (x, y) in PROBES {
            let x = DVec2::new(x, y);
            let (f, se) = estimate_se(&d, x, h, BoundaryCorrection::LocalLinear, &pts);
            assert!(
                (f - 1.0).abs() < 4.0 * se,
                "local linear at {x}: {f} ± {se}"
            );
            let g =
                estimate(&d, x, h, BoundaryCorrection::LocalLinear, &pts, &w).expect("estimate");
            assert!((f - g).abs() < 1e-12);
            let (p, se) = estimate_se(&d, x, h, BoundaryCorrection::None, &pts);
            // The plain kernel: the share of the disc inside the square (1, 1/2 on an edge, 1/4 at a corner).
            let share = d.moments(x, h)[0];
            assert!(
                (p - share).abs() < 4.0 * se,
                "plain at {x}: {p} ± {se}, share {share}"
            );
            if share < 0.9 {
                assert!(
                    (p - 1.0).abs() > 10.0 * se,
                    "the plain kernel must fail at {x}: {p}"
                );
            }
        }
    }

    #[test]
    fn linear_density_to_the_corners_only_with_local_linear() {
        // f(x, y) = (1 + 2x)/2 on the unit square (mass 1).
        let f = |p: DVec2| (1.0 + 2.0 * p.x) / 2.0;
        let d = unit_square();
        let pts = sample(200_000, 11, f, 1.5);
        let h = 0.25;
        for (x, y) in PROBES {
            let x = DVec2::new(x, y);
            let (ll, se) = estimate_se(&d, x, h, BoundaryCorrection::LocalLinear, &pts);
            assert!(
                (ll - f(x)).abs() < 4.0 * se,
                "local linear at {x}: {ll} ± {se}, exact {}",
                f(x)
            );
            // Renormalising is exact for flat densities only: where the kernel's mass inside the square is
            // off-centre in x (the x = 0 and x = 1 edges, corners) its bias is ∂f/∂x · h · M₀₁/M₀₀.
            let (rn, se) = estimate_se(&d, x, h, BoundaryCorrection::Renormalized, &pts);
            let m = d.moments(x, h);
            let expected = f(x) + 1.0 * h * m[1] / m[0]; // E = ∫K̃ f(x + hξ)/M₀₀ with ∂f/∂x = 1
            assert!(
                (rn - expected).abs() < 4.0 * se,
                "renormalised at {x}: {rn} vs {expected}"
            );
            if m[1].abs() > 0.05 {
                assert!(
                    (rn - f(x)).abs() > 4.0 * se,
                    "renormalised must be biased at {x}"
                );
            }
        }
    }

    #[test]
    fn bias_factor_inside_is_a_sixth() {
        let d = split_square();
        let x = DVec2::new(0.5, 0.5);
        let l = d
            .weights(x, 0.2, BoundaryCorrection::LocalLinear)
            .expect("w");
        assert!((l - DVec3::X).length() < 1e-12);
        // Inside: ∫K̃|ξ|² = 1/3 (1/6 per axis); computed with the disc polygon, so to its accuracy.
        let b = d.bias_factor(x, 0.2, l);
        assert!((b - 1.0 / 3.0).abs() < 1e-3, "{b}");
        // At a corner the weights change sign: the factor exceeds the interior's.
        let l = d
            .weights(DVec2::ZERO, 0.2, BoundaryCorrection::LocalLinear)
            .expect("w");
        assert!(d.bias_factor(DVec2::ZERO, 0.2, l) > 1.0 / 3.0);
    }
}

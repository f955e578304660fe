//! Quadrature rules over an element: Gauss–Legendre points on [0, 1] (nodes the roots of P_m, found by Newton's
//! method on the three-term recurrence (k+1) P_{k+1} = (2k+1) x P_k − k P_{k−1}; weights
//! w_i = 2 / ((1 − x_i²) P_m'(x_i)²), Abramowitz & Stegun 25.4.29), mapped onto polygons:
//!
//! - a quad through its bilinear map p(s, t), weights w_i w_j |∂p/∂s × ∂p/∂t| / A;
//! - a triangle through the collapsed square p(s, t) = (1−s) a + s(1−t) b + s t c, Jacobian 2A·s,
//!   weights 2 w_i w_j s_i (Duffy's transform).
//!
//! Weights are normalised to sum to one, so a rule returns an area mean. With m points per side the rule
//! integrates polynomials of degree 2m − 1 in each parameter exactly.

use glam::DVec3;
use radlab_scene::Polygon;

/// Gauss–Legendre nodes and weights for `m` points on [0, 1] (weights sum to 1).
pub fn gauss_legendre(m: u32) -> Vec<(f64, f64)> {
    let m = m.max(1) as usize;
    let mut out = Vec::with_capacity(m);
    for i in 0..m {
        // Initial guess (Tricomi), then Newton on P_m.
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (m as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 1..m {
                let p2 = ((2 * k + 1) as f64 * x * p1 - k as f64 * p0) / (k + 1) as f64;
                p0 = p1;
                p1 = p2;
            }
            dp = m as f64 * (x * p1 - p0) / (x * x - 1.0);
            let dx = p1 / dp;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        // Map [-1, 1] to [0, 1]; weights halve.
        out.push((0.5 * (1.0 - x), 0.5 * w));
    }
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    out
}

/// Quadrature points (position, weight) over a polygon from a rule on [0, 1] (e.g. [`gauss_legendre`]),
/// weights summing to 1: an area mean.
pub fn polygon_points(poly: &Polygon, g: &[(f64, f64)]) -> Vec<(DVec3, f64)> {
    let v = poly.vertices();
    let mut pts = Vec::with_capacity(g.len() * g.len());
    if poly.is_triangle() {
        let (a, b, c) = (v[0], v[1], v[2]);
        for &(s, ws) in g {
            for &(t, wt) in g {
                let p = a * (1.0 - s) + b * (s * (1.0 - t)) + c * (s * t);
                pts.push((p, 2.0 * ws * wt * s));
            }
        }
    } else {
        for &(s, ws) in g {
            for &(t, wt) in g {
                let p = poly.point_at(s, t);
                // ∂p/∂s and ∂p/∂t of p = (1−t)[(1−s)v0 + s v1] + t[(1−s)v3 + s v2].
                let ds = (v[1] - v[0]) * (1.0 - t) + (v[2] - v[3]) * t;
                let dt = (v[3] - v[0]) * (1.0 - s) + (v[2] - v[1]) * s;
                pts.push((p, ws * wt * ds.cross(dt).length()));
            }
        }
    }
    let total: f64 = pts.iter().map(|p| p.1).sum();
    if total > 0.0 {
        for p in &mut pts {
            p.1 /= total;
        }
    } else {
        let w = 1.0 / pts.len() as f64;
        for p in &mut pts {
            p.1 = w;
        }
    }
    pts
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::dvec3;

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        for m in 1..=8u32 {
            let g = gauss_legendre(m);
            assert_eq!(g.len(), m as usize);
            for deg in 0..(2 * m) {
                let q: f64 = g.iter().map(|&(x, w)| w * x.powi(deg as i32)).sum();
                let exact = 1.0 / (deg as f64 + 1.0);
                assert!((q - exact).abs() < 1e-13, "m={m} deg={deg}: {q} vs {exact}");
            }
        }
    }

    #[test]
    fn polygon_rules_give_area_means() {
        // Mean of x² over the unit right triangle: ∫x² dA / A = (1/12)/(1/2) = 1/6.
        let t = Polygon::triangle(dvec3(0., 0., 0.), dvec3(1., 0., 0.), dvec3(0., 1., 0.));
        let q: f64 = polygon_points(&t, &gauss_legendre(3))
            .iter()
            .map(|(p, w)| w * p.x * p.x)
            .sum();
        assert!((q - 1.0 / 6.0).abs() < 1e-14, "{q}");
        // A trapezoid (non-parallelogram quad): mean of y over x ∈ [0, 4 − y], y ∈ [0, 2] with top width 2.
        let z = Polygon::quad(
            dvec3(0., 0., 0.),
            dvec3(4., 0., 0.),
            dvec3(3., 2., 0.),
            dvec3(1., 2., 0.),
        );
        // Width at height y is 4 − y; mean y = ∫ y(4 − y) dy / ∫ (4 − y) dy over [0, 2] = (16/3)/6 = 8/9.
        let q: f64 = polygon_points(&z, &gauss_legendre(2))
            .iter()
            .map(|(p, w)| w * p.y)
            .sum();
        assert!((q - 8.0 / 9.0).abs() < 1e-14, "{q}");
    }
}

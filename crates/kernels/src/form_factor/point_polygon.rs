//! Unoccluded form factor from a differential area at x (unit normal n) to a polygon P:
//!
//! F_{dA→P} = (1/2π) Σ_k γ_k · n·(r_k × r_{k+1}) / |r_k × r_{k+1}|
//!
//! with r_k the unit vectors from x to P's vertices and γ_k = angle(r_k, r_{k+1}) (Lambert's contour integral;
//! Nishita & Nakamae 1985; Baum, Rushmeier & Winget 1989, eq. 3). P is first clipped to the receiver's upper
//! half-space n·(y − x) ≥ 0 (Sutherland–Hodgman against one plane), so the result is exact for polygons that
//! straddle the receiver's horizon. A polygon emits from its front only: if x lies behind or in P's plane the
//! factor is 0. No singularity at contact: a point on P's edge or plane gives a finite answer.

use glam::DVec3;

use radlab_scene::Polygon;

/// Form factor from the differential area at `x` with unit normal `n` to the front of `poly`, unoccluded.
pub fn point_polygon(x: DVec3, n: DVec3, poly: &Polygon) -> f64 {
    let pn = poly.vector_area();
    let v = poly.vertices();
    // One-sided source: x must be strictly in front of the polygon's plane.
    if (x - v[0]).dot(pn) <= 0.0 {
        return 0.0;
    }
    // Clip to the receiver's upper half-space, in coordinates relative to x.
    let mut clipped = [DVec3::ZERO; 8];
    let mut m = 0;
    for k in 0..v.len() {
        let a = v[k] - x;
        let b = v[(k + 1) % v.len()] - x;
        let (da, db) = (a.dot(n), b.dot(n));
        if da >= 0.0 {
            clipped[m] = a;
            m += 1;
        }
        if (da >= 0.0) != (db >= 0.0) {
            let t = da / (da - db);
            clipped[m] = a + t * (b - a);
            m += 1;
        }
    }
    if m < 3 {
        return 0.0;
    }
    contour_sum(n, &clipped[..m])
}

/// The contour integral without the half-space clip or the facing test: exact only when the whole polygon
/// lies above the receiver's tangent plane and faces it. For tests and for callers that know both hold.
pub fn point_polygon_unclipped(x: DVec3, n: DVec3, poly: &Polygon) -> f64 {
    let rel: Vec<DVec3> = poly.vertices().iter().map(|&p| p - x).collect();
    contour_sum(n, &rel)
}

/// The polygon's irradiance vector at `x` per unit radiosity of its front,
///
///   Φ(x) = (1/2π) Σ_k γ_k û_k,  û_k = (r_{k+1} × r_k)/|r_{k+1} × r_k|,
///
/// (the irradiance vector of a polygon: Arvo 1994, "The Irradiance Jacobian for Partially Occluded Polyhedral
/// Sources", section 3), so that
/// F_{dA→P} = n·Φ(x) for every normal n whose upper half-space holds the whole polygon (the unclipped contour
/// integral above). Zero when `x` lies behind or in the polygon's plane (it emits from its front only).
pub fn point_polygon_vector(x: DVec3, poly: &Polygon) -> DVec3 {
    let v = poly.vertices();
    if (x - v[0]).dot(poly.vector_area()) <= 0.0 {
        return DVec3::ZERO;
    }
    let rel: Vec<DVec3> = v.iter().map(|&p| p - x).collect();
    contour_vector(&rel)
}

/// The edges of the polygon with vertices `rel` (relative to the receiving point) as (c, γ, |c|), with
/// c = r̂_k × r̂_{k+1} and γ the angle the edge subtends: the terms of the contour integral.
fn contour_edges(rel: &[DVec3]) -> impl Iterator<Item = (DVec3, f64, f64)> + '_ {
    (0..rel.len()).filter_map(|k| {
        let a = rel[k].normalize_or_zero();
        let b = rel[(k + 1) % rel.len()].normalize_or_zero();
        let c = a.cross(b);
        let cl = c.length();
        (cl > 1e-300).then(|| (c, cl.atan2(a.dot(b)), cl))
    })
}

/// Σ_k γ_k û_k / 2π over the edges, oriented toward the side the polygon's front faces (counter-clockwise seen
/// from the front).
fn contour_vector(rel: &[DVec3]) -> DVec3 {
    -contour_edges(rel)
        .map(|(c, gamma, cl)| c * (gamma / cl))
        .sum::<DVec3>()
        / (2.0 * std::f64::consts::PI)
}

fn contour_sum(n: DVec3, rel: &[DVec3]) -> f64 {
    // Each edge's term is projected on n before summing (summing the vector first cancels digits: a wall
    // grazing the horizon lost 1e-10 of its tiny factor). Vertices ordered counter-clockwise seen from the
    // front give a negative sum seen from in front; seen from behind a clipped piece the sign flips, hence the
    // magnitude.
    let s: f64 = contour_edges(rel)
        .map(|(c, gamma, cl)| gamma * n.dot(c) / cl)
        .sum();
    (s.abs() / (2.0 * std::f64::consts::PI)).min(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::dvec3;

    #[test]
    fn infinite_plane_limit_is_one() {
        // A huge square facing down, at height 1 above an upward receiver: F → 1.
        let s = 1e6;
        let p = Polygon::quad(
            dvec3(-s, -s, 1.),
            dvec3(-s, s, 1.),
            dvec3(s, s, 1.),
            dvec3(s, -s, 1.),
        );
        let f = point_polygon(DVec3::ZERO, DVec3::Z, &p);
        assert!((f - 1.0).abs() < 1e-5, "{f}");
    }

    #[test]
    fn parallel_rectangle_corner_closed_form() {
        // Differential area below the corner of a parallel a × b rectangle at height h (Howell B-3):
        // F = (1/2π)[X/√(1+X²) atan(Y/√(1+X²)) + Y/√(1+Y²) atan(X/√(1+Y²))], X = a/h, Y = b/h.
        let corner = |x: f64, y: f64| {
            (x / (1. + x * x).sqrt() * (y / (1. + x * x).sqrt()).atan()
                + y / (1. + y * y).sqrt() * (x / (1. + y * y).sqrt()).atan())
                / (2.0 * std::f64::consts::PI)
        };
        for (a, b, h) in [(1.0, 1.0, 1.0), (0.3, 2.0, 0.7), (5.0, 0.1, 2.0)] {
            let p = Polygon::quad(
                dvec3(0., 0., h),
                dvec3(0., b, h),
                dvec3(a, b, h),
                dvec3(a, 0., h),
            );
            let f = point_polygon(DVec3::ZERO, DVec3::Z, &p);
            let exact = corner(a / h, b / h);
            assert!(
                (f - exact).abs() < 1e-12 * exact.max(1.0),
                "{a} {b} {h}: {f} vs {exact}"
            );
        }
    }

    #[test]
    fn back_facing_and_below_horizon_give_zero() {
        let up = Polygon::quad(
            dvec3(0., 0., 1.),
            dvec3(1., 0., 1.),
            dvec3(1., 1., 1.),
            dvec3(0., 1., 1.),
        );
        assert_eq!(point_polygon(DVec3::ZERO, DVec3::Z, &up), 0.0); // its front faces away (+z)
        let down = Polygon::quad(
            dvec3(0., 0., -1.),
            dvec3(0., 1., -1.),
            dvec3(1., 1., -1.),
            dvec3(1., 0., -1.),
        );
        assert_eq!(point_polygon(DVec3::ZERO, DVec3::Z, &down), 0.0); // below the horizon
    }

    #[test]
    fn horizon_clipping_halves_a_symmetric_wall() {
        // A vertical wall facing the receiver, centred on its horizon: the clipped half equals the factor of a
        // wall that only spans the upper half.
        let full = Polygon::quad(
            dvec3(1., -1., -1.),
            dvec3(1., -1., 1.),
            dvec3(1., 1., 1.),
            dvec3(1., 1., -1.),
        );
        let upper = Polygon::quad(
            dvec3(1., -1., 0.),
            dvec3(1., -1., 1.),
            dvec3(1., 1., 1.),
            dvec3(1., 1., 0.),
        );
        let a = point_polygon(DVec3::ZERO, DVec3::Z, &full);
        let b = point_polygon(DVec3::ZERO, DVec3::Z, &upper);
        assert!(a > 0.0 && (a - b).abs() < 1e-14, "{a} {b}");
    }

    #[test]
    fn irradiance_vector_dotted_with_a_normal_is_the_form_factor() {
        // A unit square above the origin, facing down, seen from normals tilted so that it stays above.
        let p = Polygon::quad(
            dvec3(-0.5, -0.5, 1.),
            dvec3(-0.5, 0.5, 1.),
            dvec3(0.5, 0.5, 1.),
            dvec3(0.5, -0.5, 1.),
        );
        let x = dvec3(0.1, -0.2, 0.0);
        let phi = point_polygon_vector(x, &p);
        for n in [
            dvec3(0., 0., 1.),
            dvec3(0.2, 0.1, 1.).normalize(),
            dvec3(-0.3, 0.2, 1.).normalize(),
        ] {
            let f = point_polygon(x, n, &p);
            assert!(
                (n.dot(phi) - f).abs() <= 1e-14,
                "{n}: {} vs {f}",
                n.dot(phi)
            );
        }
        // Behind the polygon: nothing.
        assert_eq!(point_polygon_vector(dvec3(0., 0., 2.), &p), DVec3::ZERO);
    }
}

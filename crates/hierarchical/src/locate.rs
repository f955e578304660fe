//! Locating a surface point in a face's quadtree. The point is mapped into the face's parameter space
//! (triangles: p = a + u(b − a) + v(c − a), solved in the face's plane; quads: the inverse of the bilinear map
//! p(s, t), by Gauss–Newton from the centre), then the quadtree is descended by containment in that space,
//! where every element is a lattice polygon (see [`crate::node::Patch::uv`]).

use glam::{DVec2, DVec3};
use radlab_scene::Polygon;

use crate::node::{LATTICE, Patch};

/// Parameter coordinates of `p` (a point on or near the polygon) in the polygon's own map, clamped to it.
pub fn param_coords(poly: &Polygon, p: DVec3) -> DVec2 {
    let v = poly.vertices();
    if poly.is_triangle() {
        let (e1, e2, d) = (v[1] - v[0], v[2] - v[0], p - v[0]);
        let (a, b, c) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let det = a * c - b * b;
        if det == 0.0 || det.is_nan() {
            return DVec2::ZERO;
        }
        let (r1, r2) = (d.dot(e1), d.dot(e2));
        let u = (c * r1 - b * r2) / det;
        let w = (a * r2 - b * r1) / det;
        let (u, w) = (u.max(0.0), w.max(0.0));
        let s = u + w;
        return if s > 1.0 {
            DVec2::new(u / s, w / s)
        } else {
            DVec2::new(u, w)
        };
    }
    let mut st = DVec2::splat(0.5);
    for _ in 0..12 {
        let (s, t) = (st.x, st.y);
        let r = poly.point_at(s, t) - p;
        let ds = (v[1] - v[0]) * (1.0 - t) + (v[2] - v[3]) * t;
        let dt = (v[3] - v[0]) * (1.0 - s) + (v[2] - v[1]) * s;
        let (a, b, c) = (ds.dot(ds), ds.dot(dt), dt.dot(dt));
        let det = a * c - b * b;
        if det == 0.0 || det.is_nan() {
            break;
        }
        let (r1, r2) = (r.dot(ds), r.dot(dt));
        let step = DVec2::new((c * r1 - b * r2) / det, (a * r2 - b * r1) / det);
        st = (st - step).clamp(DVec2::ZERO, DVec2::ONE);
        if step.length_squared() < 1e-28 {
            break;
        }
    }
    st
}

/// The element's corners in parameter space, in [0, 1]².
pub fn param_corners(patch: &Patch) -> ([DVec2; 4], usize) {
    let n = patch.corners();
    let mut c = [DVec2::ZERO; 4];
    for (k, uv) in patch.uv.iter().take(n).enumerate() {
        c[k] = DVec2::new(uv[0] as f64, uv[1] as f64) / LATTICE as f64;
    }
    (c, n)
}

/// How far inside the parameter-space polygon `q` lies: the smallest signed distance to its edges (positive
/// inside), over its size.
pub fn insideness(corners: &[DVec2], q: DVec2) -> f64 {
    let n = corners.len();
    // Orientation of the polygon in parameter space (children of a triangle can be inverted).
    let mut area2 = 0.0;
    for k in 0..n {
        area2 += corners[k].perp_dot(corners[(k + 1) % n]);
    }
    let sign = if area2 >= 0.0 { 1.0 } else { -1.0 };
    let mut best = f64::INFINITY;
    for k in 0..n {
        let (a, b) = (corners[k], corners[(k + 1) % n]);
        let e = b - a;
        let len = e.length();
        if len > 0.0 {
            best = best.min(sign * e.perp_dot(q - a) / len);
        }
    }
    best
}

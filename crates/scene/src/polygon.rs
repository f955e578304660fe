//! Planar convex polygons with three or four vertices: area, normal, centroid, sampling, point location
//! and regular subdivision.
//!
//! Area and normal come from the vector area ½ Σ_k v_k × v_{k+1} (Newell's method), exact for any planar
//! polygon. Uniform sampling of a triangle uses the square-root map (Shirley & Chiu 1997,
//! x = (1 − √u) a + √u (1 − v) b + √u v c); a quad is sampled as two triangles chosen by area. Quads are
//! subdivided bilinearly (a planar convex quad stays planar and convex under bilinear interpolation),
//! triangles by edge midpoints (four congruent children, the quadtree of Hanrahan et al. 1991).

use glam::DVec3;

/// A planar convex polygon with 3 or 4 vertices in counter-clockwise order seen from its normal side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Polygon {
    verts: [DVec3; 4],
    n: u8,
}

impl Polygon {
    /// A triangle.
    pub fn triangle(a: DVec3, b: DVec3, c: DVec3) -> Self {
        Self {
            verts: [a, b, c, c],
            n: 3,
        }
    }

    /// A quadrilateral (must be planar and convex; see [`Polygon::is_planar_convex`]).
    pub fn quad(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> Self {
        Self {
            verts: [a, b, c, d],
            n: 4,
        }
    }

    /// From a slice of 3 or 4 vertices; `None` for any other count.
    pub fn from_slice(v: &[DVec3]) -> Option<Self> {
        match *v {
            [a, b, c] => Some(Self::triangle(a, b, c)),
            [a, b, c, d] => Some(Self::quad(a, b, c, d)),
            _ => None,
        }
    }

    /// The vertices, in order.
    pub fn vertices(&self) -> &[DVec3] {
        &self.verts[..self.n as usize]
    }

    /// Number of vertices (3 or 4).
    pub fn len(&self) -> usize {
        self.n as usize
    }

    /// Always false: a polygon has at least three vertices.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// True for a triangle.
    pub fn is_triangle(&self) -> bool {
        self.n == 3
    }

    /// Vector area: ½ Σ v_k × v_{k+1}. Its length is the area, its direction the normal.
    pub fn vector_area(&self) -> DVec3 {
        // Relative to the first vertex (the same sum, since Σ v0 × (v_{k+1} − v_k) = 0), so a small polygon
        // far from the origin keeps its digits.
        let v = self.vertices();
        let mut s = DVec3::ZERO;
        for k in 1..v.len() - 1 {
            s += (v[k] - v[0]).cross(v[k + 1] - v[0]);
        }
        0.5 * s
    }

    /// Area.
    pub fn area(&self) -> f64 {
        self.vector_area().length()
    }

    /// Unit normal (zero for a degenerate polygon).
    pub fn normal(&self) -> DVec3 {
        self.vector_area().normalize_or_zero()
    }

    /// Area-weighted centroid.
    pub fn centroid(&self) -> DVec3 {
        let v = self.vertices();
        if self.n == 3 {
            return (v[0] + v[1] + v[2]) / 3.0;
        }
        let (a1, a2) = self.split_areas();
        let c1 = (v[0] + v[1] + v[2]) / 3.0;
        let c2 = (v[0] + v[2] + v[3]) / 3.0;
        if a1 + a2 > 0.0 {
            (a1 * c1 + a2 * c2) / (a1 + a2)
        } else {
            (v[0] + v[1] + v[2] + v[3]) / 4.0
        }
    }

    /// Longest edge length.
    pub fn max_edge(&self) -> f64 {
        let v = self.vertices();
        (0..v.len())
            .map(|k| (v[(k + 1) % v.len()] - v[k]).length())
            .fold(0.0, f64::max)
    }

    /// Diameter: the largest distance between two vertices.
    pub fn diameter(&self) -> f64 {
        let v = self.vertices();
        let mut d: f64 = 0.0;
        for i in 0..v.len() {
            for j in i + 1..v.len() {
                d = d.max((v[i] - v[j]).length());
            }
        }
        d
    }

    fn split_areas(&self) -> (f64, f64) {
        let v = &self.verts;
        let a1 = 0.5 * (v[1] - v[0]).cross(v[2] - v[0]).length();
        let a2 = 0.5 * (v[2] - v[0]).cross(v[3] - v[0]).length();
        (a1, a2)
    }

    /// A point distributed uniformly over the polygon's area, from two numbers in [0,1).
    pub fn sample_uniform(&self, u1: f64, u2: f64) -> DVec3 {
        AreaSampler::new(*self).sample(u1, u2)
    }

    /// A point from parameters (s, t) in \[0, 1\]²: bilinear over a quad, the square-root map over a triangle.
    /// Stratifying (s, t) stratifies the polygon (exactly uniform for triangles and parallelograms).
    pub fn point_at(&self, s: f64, t: f64) -> DVec3 {
        let v = &self.verts;
        if self.n == 3 {
            sample_triangle(v[0], v[1], v[2], s, t)
        } else {
            let a = v[0].lerp(v[1], s);
            let b = v[3].lerp(v[2], s);
            a.lerp(b, t)
        }
    }

    /// The inverse of the polygon's lattice parameterisation: (s, t) with p = v0 + s (v1 − v0) + t (v2 − v0)
    /// for a triangle (barycentric coordinates; the map [`Polygon::subdivide`] cuts along), with
    /// p = [`Polygon::point_at`]\(s, t) for a quad (the inverse bilinear map, by Gauss–Newton from the centre:
    /// exact in one step for a parallelogram, quadratically convergent for any planar convex quad). Of a point
    /// off the plane, the coordinates of its projection; not clamped, so a point outside the polygon gets
    /// coordinates outside [0, 1]². Zero for a degenerate polygon.
    pub fn param_coords(&self, p: DVec3) -> glam::DVec2 {
        use glam::DVec2;
        let v = self.vertices();
        // Solves the 2 × 2 normal equations [a b; b c] x = r of a least-squares step.
        let solve = |ds: DVec3, dt: DVec3, d: DVec3| -> Option<DVec2> {
            let (a, b, c) = (ds.dot(ds), ds.dot(dt), dt.dot(dt));
            let det = a * c - b * b;
            if det == 0.0 || det.is_nan() {
                return None;
            }
            let (r1, r2) = (d.dot(ds), d.dot(dt));
            Some(DVec2::new((c * r1 - b * r2) / det, (a * r2 - b * r1) / det))
        };
        if self.n == 3 {
            return solve(v[1] - v[0], v[2] - v[0], p - v[0]).unwrap_or(DVec2::ZERO);
        }
        let mut st = DVec2::splat(0.5);
        for _ in 0..12 {
            let (s, t) = (st.x, st.y);
            let r = self.point_at(s, t) - p;
            let ds = (v[1] - v[0]) * (1.0 - t) + (v[2] - v[3]) * t;
            let dt = (v[3] - v[0]) * (1.0 - s) + (v[2] - v[1]) * s;
            let Some(step) = solve(ds, dt, r) else {
                break;
            };
            st -= step;
            if step.length_squared() < 1e-28 {
                break;
            }
        }
        st
    }

    /// Whether every vertex lies on or behind the plane through `origin` with unit normal `normal`, to `tol`
    /// (scene units).
    pub fn behind_plane(&self, origin: DVec3, normal: DVec3, tol: f64) -> bool {
        self.vertices()
            .iter()
            .all(|&v| (v - origin).dot(normal) <= tol)
    }

    /// Whether `p` (assumed near the polygon's plane) projects inside the polygon, with a relative tolerance.
    pub fn contains(&self, p: DVec3, tol: f64) -> bool {
        let n = self.vector_area();
        let v = self.vertices();
        let scale = self.max_edge();
        for k in 0..v.len() {
            let e = v[(k + 1) % v.len()] - v[k];
            // Signed distance of p from edge k, in the polygon's plane, positive inside.
            let inward = n.cross(e).normalize_or_zero();
            if (p - v[k]).dot(inward) < -tol * scale {
                return false;
            }
        }
        true
    }

    /// Distance from `p` to the polygon (zero inside its projection, plus the distance to the plane).
    pub fn distance_to(&self, p: DVec3) -> f64 {
        let n = self.normal();
        let v = self.vertices();
        let plane = (p - v[0]).dot(n);
        let q = p - plane * n;
        if self.contains(q, 0.0) {
            return plane.abs();
        }
        let mut best = f64::INFINITY;
        for k in 0..v.len() {
            let a = v[k];
            let b = v[(k + 1) % v.len()];
            let e = b - a;
            let t = ((p - a).dot(e) / e.length_squared().max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
            best = best.min((p - (a + t * e)).length());
        }
        best
    }

    /// Split into four children: a quad at the midpoints of its edges and its centre, a triangle at its edge
    /// midpoints. Children keep the parent's orientation and their areas sum to the parent's.
    pub fn split4(&self) -> [Polygon; 4] {
        let v = &self.verts;
        if self.n == 3 {
            let (a, b, c) = (v[0], v[1], v[2]);
            let (ab, bc, ca) = ((a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5);
            [
                Self::triangle(a, ab, ca),
                Self::triangle(ab, b, bc),
                Self::triangle(ca, bc, c),
                Self::triangle(ab, bc, ca),
            ]
        } else {
            let m = |s, t| self.point_at(s, t);
            let c = m(0.5, 0.5);
            [
                Self::quad(v[0], m(0.5, 0.0), c, m(0.0, 0.5)),
                Self::quad(m(0.5, 0.0), v[1], m(1.0, 0.5), c),
                Self::quad(c, m(1.0, 0.5), v[2], m(0.5, 1.0)),
                Self::quad(m(0.0, 0.5), c, m(0.5, 1.0), v[3]),
            ]
        }
    }

    /// The grid [`Polygon::subdivide`] cuts at `size`: (nu, nv) pieces along a quad's two parameter
    /// directions (ceil(length / size) of the longer opposite edge of each pair), or (m, m) for a triangle's m²
    /// pieces (m from its second-longest edge). At least 1 and at most 4096 per direction; a size that is
    /// not positive, or a non-finite edge, gives 1.
    pub fn subdivision(&self, size: f64) -> (usize, usize) {
        let v = &self.verts;
        let segs = |len: f64| -> usize {
            if !(size > 0.0) || !len.is_finite() {
                1
            } else {
                ((len / size).ceil() as usize).clamp(1, 1 << 12)
            }
        };
        if self.n == 4 {
            (
                segs((v[1] - v[0]).length().max((v[2] - v[3]).length())),
                segs((v[3] - v[0]).length().max((v[2] - v[1]).length())),
            )
        } else {
            let (a, b, c) = (v[0], v[1], v[2]);
            let mut e = [(b - a).length(), (c - b).length(), (a - c).length()];
            e.sort_by(f64::total_cmp);
            let m = segs(e[1]);
            (m, m)
        }
    }

    /// Regular subdivision into pieces of about `size` (at least one piece): a quad into a nu × nv bilinear grid
    /// (no piece longer than `size` along an edge), a triangle into m² similar triangles with m set by its
    /// second-longest edge, so the two halves of a split quad get the same grid as the quad would (the longest
    /// edge, their diagonal, would make them four times finer). The grid is [`Polygon::subdivision`].
    pub fn subdivide(&self, size: f64) -> Vec<Polygon> {
        let v = &self.verts;
        let (nu, nv) = self.subdivision(size);
        if self.n == 4 {
            let mut out = Vec::with_capacity(nu * nv);
            for j in 0..nv {
                for i in 0..nu {
                    let (s0, s1) = (i as f64 / nu as f64, (i + 1) as f64 / nu as f64);
                    let (t0, t1) = (j as f64 / nv as f64, (j + 1) as f64 / nv as f64);
                    out.push(Self::quad(
                        self.point_at(s0, t0),
                        self.point_at(s1, t0),
                        self.point_at(s1, t1),
                        self.point_at(s0, t1),
                    ));
                }
            }
            out
        } else {
            let (a, b, c) = (v[0], v[1], v[2]);
            let m = nu;
            // Lattice point (i, j) = a + i/m (b - a) + j/m (c - a), i + j <= m.
            let p = |i: usize, j: usize| {
                a + (b - a) * (i as f64 / m as f64) + (c - a) * (j as f64 / m as f64)
            };
            let mut out = Vec::with_capacity(m * m);
            for j in 0..m {
                for i in 0..m - j {
                    out.push(Self::triangle(p(i, j), p(i + 1, j), p(i, j + 1)));
                    if i + j + 1 < m {
                        out.push(Self::triangle(p(i + 1, j), p(i + 1, j + 1), p(i, j + 1)));
                    }
                }
            }
            out
        }
    }

    /// Whether the polygon is planar and convex within a relative tolerance, and not degenerate.
    pub fn is_planar_convex(&self, rel_tol: f64) -> bool {
        let va = self.vector_area();
        let scale = self.diameter();
        if !(va.length() > rel_tol * scale * scale) {
            return false;
        }
        let n = va.normalize();
        let v = self.vertices();
        for k in 0..v.len() {
            let a = v[k];
            let b = v[(k + 1) % v.len()];
            let c = v[(k + 2) % v.len()];
            if (b - a).cross(c - b).dot(n) < -rel_tol * scale * scale {
                return false;
            }
            if ((a - v[0]).dot(n)).abs() > rel_tol * scale {
                return false;
            }
        }
        true
    }
}

/// Relative tolerance of the back-face test [`facing_away`]: a vertex within this fraction of the two
/// polygons' longest edge from a plane counts as on it. Relative, so the test does not depend on the scene's
/// units; 1e-9 is far above the rounding of f64 coordinates (about 1e-16 of their magnitude, so faces up to
/// 1e6 times smaller than their distance from the origin are still told apart) and far below any gap a scene
/// models on purpose.
pub const FACING_TOL_REL: f64 = 1e-9;

/// The back-face test: whether polygon `b` lies wholly on or behind the plane of `a` (through `a_origin`, any
/// point of `a`, with unit normal `a_normal`) or `a` wholly on or behind the plane of `b`. Then neither sees
/// the other's front, and both form factors vanish (the point kernel is zero at every receiver point:
/// Baum, Rushmeier & Winget 1989, eq. 3 with the source clipped to the receiver's horizon). Tolerance:
/// [`FACING_TOL_REL`] × the longer of the two longest edges.
pub fn facing_away(
    a: &Polygon,
    a_origin: DVec3,
    a_normal: DVec3,
    b: &Polygon,
    b_origin: DVec3,
    b_normal: DVec3,
) -> bool {
    let tol = FACING_TOL_REL * a.max_edge().max(b.max_edge());
    b.behind_plane(a_origin, a_normal, tol) || a.behind_plane(b_origin, b_normal, tol)
}

/// [`Polygon::sample_uniform`] with the choice between a quad's two triangles (probability proportional to
/// area) computed once, for drawing many points from one polygon (emitter sampling): the same points, bit
/// for bit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaSampler {
    poly: Polygon,
    /// Probability of the first triangle (v0, v1, v2) of a quad; 1 for a triangle.
    p1: f64,
}

impl AreaSampler {
    /// The sampler of `poly`.
    pub fn new(poly: Polygon) -> Self {
        let p1 = if poly.n == 3 {
            1.0
        } else {
            let (a1, a2) = poly.split_areas();
            if a1 + a2 > 0.0 { a1 / (a1 + a2) } else { 0.5 }
        };
        Self { poly, p1 }
    }

    /// A point distributed uniformly over the polygon's area, from two numbers in [0,1).
    #[inline]
    pub fn sample(&self, u1: f64, u2: f64) -> DVec3 {
        let (v, p1) = (&self.poly.verts, self.p1);
        if self.poly.n == 3 {
            return sample_triangle(v[0], v[1], v[2], u1, u2);
        }
        if u1 < p1 {
            sample_triangle(v[0], v[1], v[2], u1 / p1, u2)
        } else {
            sample_triangle(v[0], v[2], v[3], ((u1 - p1) / (1.0 - p1)).min(1.0), u2)
        }
    }
}

fn sample_triangle(a: DVec3, b: DVec3, c: DVec3, u1: f64, u2: f64) -> DVec3 {
    let su = u1.max(0.0).sqrt();
    a * (1.0 - su) + b * (su * (1.0 - u2)) + c * (su * u2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::dvec3;

    fn unit_quad() -> Polygon {
        Polygon::quad(
            dvec3(0., 0., 0.),
            dvec3(1., 0., 0.),
            dvec3(1., 1., 0.),
            dvec3(0., 1., 0.),
        )
    }

    #[test]
    fn area_normal_centroid() {
        let q = unit_quad();
        assert!((q.area() - 1.0).abs() < 1e-15);
        assert_eq!(q.normal(), dvec3(0., 0., 1.));
        assert!((q.centroid() - dvec3(0.5, 0.5, 0.)).length() < 1e-15);
        let t = Polygon::triangle(dvec3(0., 0., 0.), dvec3(2., 0., 0.), dvec3(0., 2., 0.));
        assert!((t.area() - 2.0).abs() < 1e-15);
    }

    #[test]
    fn subdivisions_conserve_area_and_orientation() {
        let polys = [
            unit_quad(),
            Polygon::triangle(dvec3(0., 0., 0.), dvec3(3., 0., 1.), dvec3(0., 2., 0.5)),
            Polygon::quad(
                dvec3(0., 0., 0.),
                dvec3(4., 0., 0.),
                dvec3(3., 2., 0.),
                dvec3(1., 2., 0.),
            ),
        ];
        for p in polys {
            for size in [0.3, 0.77, 5.0] {
                let kids = p.subdivide(size);
                let total: f64 = kids.iter().map(|k| k.area()).sum();
                assert!((total - p.area()).abs() < 1e-12 * p.area(), "{p:?} {size}");
                for k in &kids {
                    assert!(k.normal().dot(p.normal()) > 0.999_999);
                    // Quads: no edge longer than the size. Triangles: the second-longest edge is.
                    let mut e: Vec<f64> = (0..k.len())
                        .map(|i| (k.vertices()[(i + 1) % k.len()] - k.vertices()[i]).length())
                        .collect();
                    e.sort_by(f64::total_cmp);
                    let bound = if p.is_triangle() {
                        e[1]
                    } else {
                        e[e.len() - 1]
                    };
                    assert!(bound <= size.max(p.max_edge()) + 1e-12);
                }
            }
            let kids = p.split4();
            let total: f64 = kids.iter().map(|k| k.area()).sum();
            assert!((total - p.area()).abs() < 1e-12 * p.area());
        }
    }

    #[test]
    fn vector_area_keeps_its_digits_far_from_the_origin() {
        let o = dvec3(5.0, -3.0, 7.0);
        let s = 1e-4;
        let q = Polygon::quad(
            o,
            o + dvec3(s, 0., 0.),
            o + dvec3(s, s, 0.),
            o + dvec3(0., s, 0.),
        );
        assert!(
            (q.area() / (s * s) - 1.0).abs() < 1e-11,
            "{}",
            q.area() / (s * s)
        );
        assert!((q.normal() - DVec3::Z).length() < 1e-11);
    }

    #[test]
    fn half_of_a_quad_gets_the_quads_grid() {
        let q = unit_quad();
        let t = Polygon::triangle(dvec3(0., 0., 0.), dvec3(1., 0., 0.), dvec3(1., 1., 0.));
        // 10 × 10 cells for the quad; its half gets 10² triangles, i.e. one per half cell.
        assert_eq!(q.subdivide(0.1 + 1e-12).len(), 100);
        assert_eq!(t.subdivide(0.1 + 1e-12).len(), 100);
    }

    #[test]
    fn samples_stay_inside_and_are_uniform() {
        let p = Polygon::quad(
            dvec3(0., 0., 0.),
            dvec3(4., 0., 0.),
            dvec3(3., 2., 0.),
            dvec3(1., 2., 0.),
        );
        let n = 200;
        let mut left = 0usize;
        for i in 0..n {
            for j in 0..n {
                let x = p.sample_uniform((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
                assert!(p.contains(x, 1e-12));
                if x.x < 2.0 {
                    left += 1;
                }
            }
        }
        // The trapezoid is symmetric about x = 2: half its area lies left of it.
        let frac = left as f64 / (n * n) as f64;
        assert!((frac - 0.5).abs() < 0.01, "{frac}");
    }

    #[test]
    fn distance_and_containment() {
        let q = unit_quad();
        assert!(q.contains(dvec3(0.5, 0.5, 0.0), 0.0));
        assert!(!q.contains(dvec3(1.5, 0.5, 0.0), 1e-9));
        assert!((q.distance_to(dvec3(0.5, 0.5, 2.0)) - 2.0).abs() < 1e-15);
        assert!((q.distance_to(dvec3(2.0, 0.5, 0.0)) - 1.0).abs() < 1e-15);
    }

    #[test]
    fn planarity_and_convexity() {
        assert!(unit_quad().is_planar_convex(1e-9));
        let bent = Polygon::quad(
            dvec3(0., 0., 0.),
            dvec3(1., 0., 0.),
            dvec3(1., 1., 0.3),
            dvec3(0., 1., 0.),
        );
        assert!(!bent.is_planar_convex(1e-6));
        let dart = Polygon::quad(
            dvec3(0., 0., 0.),
            dvec3(1., 0., 0.),
            dvec3(0.2, 0.2, 0.),
            dvec3(0., 1., 0.),
        );
        assert!(!dart.is_planar_convex(1e-6));
        let sliver = Polygon::triangle(dvec3(0., 0., 0.), dvec3(1., 0., 0.), dvec3(2., 0., 0.));
        assert!(!sliver.is_planar_convex(1e-9));
    }
}

//! Gouraud (vertex-interpolated) reconstruction of a piecewise-constant element solution, shared by every
//! finite-element method whose elements are planar triangles and quads (matrix, progressive, mesh Monte Carlo
//! radiosity).
//!
//! Each input face's element corners become its vertices (corners at the same position on the same face are
//! one vertex; faces never share vertices, so radiosity may jump across creases as it does). A vertex value
//! is the least-squares linear fit B(u, v) = a + b u + c v, in the face's plane, to the constant values B_i of
//! the elements having that vertex as a corner (weighted by area, values taken at the element centroids), so
//! it is exact when the radiosity is linear over the face and needs no special rule at boundaries, where plain
//! averaging would pull a corner toward the interior (Cohen & Greenberg 1985 average at interior vertices and
//! extrapolate at boundary ones; the fit does both). Where the fitting centroids are collinear (an edge of one
//! row of elements) the fit widens to the elements sharing a corner with those; where that is still
//! degenerate (a face of one element) the vertex takes the area-weighted mean. Fitted values are clamped at
//! zero (radiosity is non-negative).
//!
//! A T-vertex, a corner of finer elements lying at the midpoint of a coarser element's edge (P, Q), as
//! adaptive subdivision by [`radlab_scene::Polygon::split4`] creates, takes instead the value the coarse edge
//! interpolates, (B_P + B_Q)/2, assigned coarsest edge first (Baum, Mann, Smith & Winget 1991 anchor such
//! vertices). Inside an element the value is bilinear in the quad's parameters or linear in the triangle's
//! barycentric coordinates, so the field is continuous across every element edge within a face.

use std::collections::HashMap;

use glam::{DVec2, DVec3};

use radlab_scene::{FaceId, Polygon, Rgb, sampling};

/// One element of a piecewise-constant solution, as the reconstructions see it.
#[derive(Clone, Copy, Debug)]
pub struct ElementValue {
    /// The input face it lies on.
    pub face: FaceId,
    /// Its geometry (a triangle or a planar quad).
    pub polygon: Polygon,
    /// Its radiosity (W/m²): over its open part where the solver estimated one
    /// ([`radlab_kernels::open_fraction`]), else its area mean.
    pub radiosity: Rgb,
    /// The share of its area light can reach ([`radlab_kernels::open_fraction`]); 1 unless the solver estimated it.
    pub open: f64,
}

/// Corner values of every element, ready to interpolate.
#[derive(Clone, Debug, Default)]
pub struct GouraudField {
    corners: Vec<[Rgb; 4]>,
    polygons: Vec<Polygon>,
}

/// Positions of one face's vertices are merged when they agree to this fraction of the face's element size.
const MERGE_REL: f64 = 1e-7;

impl GouraudField {
    /// Corner values for `elements` (in the caller's element order).
    pub fn new(elements: &[ElementValue]) -> Self {
        let mut corners = vec![[Rgb::ZERO; 4]; elements.len()];
        // Group by face, keeping the caller's order within each face.
        let mut by_face: HashMap<FaceId, Vec<usize>> = HashMap::new();
        for (i, e) in elements.iter().enumerate() {
            by_face.entry(e.face).or_default().push(i);
        }
        let mut faces: Vec<FaceId> = by_face.keys().copied().collect();
        faces.sort_unstable();
        for f in faces {
            fill_face(elements, &by_face[&f], &mut corners);
        }
        Self {
            corners,
            polygons: elements.iter().map(|e| e.polygon).collect(),
        }
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        self.corners.len()
    }

    /// Whether there are no elements.
    pub fn is_empty(&self) -> bool {
        self.corners.is_empty()
    }

    /// The corner values of element `e` (the first 3 for a triangle).
    pub fn corner_values(&self, e: usize) -> &[Rgb; 4] {
        &self.corners[e]
    }

    /// The interpolated radiosity at `point` inside element `e` (bilinear over a quad, linear over a
    /// triangle; a point slightly outside is clamped to the element).
    pub fn at(&self, e: usize, point: DVec3) -> Rgb {
        interpolate_corners(&self.polygons[e], &self.corners[e], point)
    }

    /// Approximate heap bytes held.
    pub fn bytes(&self) -> usize {
        self.corners.len() * (size_of::<[Rgb; 4]>() + size_of::<Polygon>())
    }
}

/// The value at `point` of the field taking `corners[k]` at vertex k of `poly` (its first three for a
/// triangle): bilinear over a quad, linear over a triangle; a point slightly outside is clamped to the
/// polygon.
pub fn interpolate_corners(poly: &Polygon, corners: &[Rgb; 4], point: DVec3) -> Rgb {
    let (s, t) = parameters(poly, point);
    let c = corners;
    if poly.is_triangle() {
        // point_at's triangle map is a + s(b − a) + t(c − a) on the fold s + t ≤ 1.
        (1.0 - s - t) * c[0] + s * c[1] + t * c[2]
    } else {
        (1.0 - s) * (1.0 - t) * c[0] + s * (1.0 - t) * c[1] + s * t * c[2] + (1.0 - s) * t * c[3]
    }
}

/// Affine parameters (s, t) of `p` in a triangle (barycentric weights of b and c, clamped to the triangle),
/// or bilinear parameters in a quad (inverted by Newton's method; clamped to [0, 1]²).
fn parameters(poly: &Polygon, p: DVec3) -> (f64, f64) {
    let v = poly.vertices();
    let n = poly.vector_area();
    // Project to the plane with the largest normal component for a well-conditioned 2D problem.
    let (t, b) = sampling::basis(n.normalize_or_zero());
    let to2 = |x: DVec3| DVec2::new((x - v[0]).dot(t), (x - v[0]).dot(b));
    let q = to2(p);
    if poly.is_triangle() {
        let (e1, e2) = (to2(v[1]), to2(v[2]));
        let det = e1.perp_dot(e2);
        if det == 0.0 {
            return (1.0 / 3.0, 1.0 / 3.0);
        }
        let s = (q.perp_dot(e2) / det).max(0.0);
        let tt = (e1.perp_dot(q) / det).max(0.0);
        let sum = s + tt;
        return if sum > 1.0 {
            (s / sum, tt / sum)
        } else {
            (s, tt)
        };
    }
    let (a, bb, c, d) = (DVec2::ZERO, to2(v[1]), to2(v[2]), to2(v[3]));
    let (mut s, mut tt) = (0.5, 0.5);
    for _ in 0..8 {
        let x = (1.0 - tt) * ((1.0 - s) * a + s * bb) + tt * ((1.0 - s) * d + s * c);
        let ds = (1.0 - tt) * (bb - a) + tt * (c - d);
        let dt = ((1.0 - s) * d + s * c) - ((1.0 - s) * a + s * bb);
        let det = ds.perp_dot(dt);
        if det == 0.0 {
            break;
        }
        let r = q - x;
        s += r.perp_dot(dt) / det;
        tt += ds.perp_dot(r) / det;
    }
    (
        if s.is_finite() {
            s.clamp(0.0, 1.0)
        } else {
            0.5
        },
        if tt.is_finite() {
            tt.clamp(0.0, 1.0)
        } else {
            0.5
        },
    )
}

type Key = [i64; 3];

fn fill_face(elements: &[ElementValue], ids: &[usize], corners: &mut [[Rgb; 4]]) {
    let first = &elements[ids[0]];
    let size = ids
        .iter()
        .map(|&i| elements[i].polygon.max_edge())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let quantum = size * MERGE_REL;
    let origin = first.polygon.vertices()[0];
    let key = |p: DVec3| -> Key {
        let r = ((p - origin) / quantum).round();
        [r.x as i64, r.y as i64, r.z as i64]
    };
    let (tu, tv) = sampling::basis(first.polygon.normal());
    let local = |p: DVec3| DVec2::new((p - origin).dot(tu), (p - origin).dot(tv));

    // Vertices and their incident elements (indices into `ids`).
    let mut vertex_of: HashMap<Key, usize> = HashMap::new();
    let mut positions: Vec<DVec3> = Vec::new();
    let mut incident: Vec<Vec<usize>> = Vec::new();
    let mut element_vertices: Vec<[usize; 4]> = Vec::with_capacity(ids.len());
    for (k, &i) in ids.iter().enumerate() {
        let mut vs = [usize::MAX; 4];
        for (c, &p) in elements[i].polygon.vertices().iter().enumerate() {
            let id = *vertex_of.entry(key(p)).or_insert_with(|| {
                positions.push(p);
                incident.push(Vec::new());
                positions.len() - 1
            });
            if !incident[id].contains(&k) {
                incident[id].push(k);
            }
            vs[c] = id;
        }
        element_vertices.push(vs);
    }
    let centroid: Vec<DVec2> = ids
        .iter()
        .map(|&i| local(elements[i].polygon.centroid()))
        .collect();
    let area: Vec<f64> = ids.iter().map(|&i| elements[i].polygon.area()).collect();
    let value: Vec<Rgb> = ids.iter().map(|&i| elements[i].radiosity).collect();

    let mut vertex_value: Vec<Rgb> = Vec::with_capacity(positions.len());
    for (v, inc) in incident.iter().enumerate() {
        let at = local(positions[v]);
        let fitted = fit(inc, &centroid, &area, &value, at, size).or_else(|| {
            // Widen to the elements sharing a corner with the incident ones.
            let mut ring: Vec<usize> = inc.clone();
            for &k in inc {
                for &w in element_vertices[k].iter().filter(|&&w| w != usize::MAX) {
                    for &k2 in &incident[w] {
                        if !ring.contains(&k2) {
                            ring.push(k2);
                        }
                    }
                }
            }
            fit(&ring, &centroid, &area, &value, at, size)
        });
        let b = fitted.unwrap_or_else(|| {
            let (s, a) = inc.iter().fold((Rgb::ZERO, 0.0), |(s, a), &k| {
                (s + area[k] * value[k], a + area[k])
            });
            if a > 0.0 { s / a } else { Rgb::ZERO }
        });
        vertex_value.push(b.max(Rgb::ZERO));
    }

    // T-vertices: midpoints of element edges that are vertices of other elements, coarsest edge first.
    let mut constraints: Vec<(f64, usize, usize, usize)> = Vec::new();
    for vs in &element_vertices {
        let n = vs.iter().filter(|&&w| w != usize::MAX).count();
        for c in 0..n {
            let mut edges = vec![(vs[c], vs[(c + 1) % n])];
            while let Some((a, b)) = edges.pop() {
                let mid = 0.5 * (positions[a] + positions[b]);
                if let Some(&m) = vertex_of.get(&key(mid))
                    && m != a
                    && m != b
                {
                    constraints.push(((positions[b] - positions[a]).length(), m, a, b));
                    edges.push((a, m));
                    edges.push((m, b));
                }
            }
        }
    }
    constraints.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
    for (_, m, a, b) in constraints {
        vertex_value[m] = 0.5 * (vertex_value[a] + vertex_value[b]);
    }

    for (k, &i) in ids.iter().enumerate() {
        let vs = element_vertices[k];
        for c in 0..elements[i].polygon.len() {
            corners[i][c] = vertex_value[vs[c]];
        }
    }
}

/// Area-weighted least-squares fit of B = a + b·(x − at) to the element centroid values, evaluated at `at`
/// (that is, a). `None` when the centroids do not span the plane (fewer than 3 or collinear).
fn fit(
    set: &[usize],
    centroid: &[DVec2],
    area: &[f64],
    value: &[Rgb],
    at: DVec2,
    size: f64,
) -> Option<Rgb> {
    if set.len() < 3 {
        return None;
    }
    // Normal equations in coordinates scaled by the element size (well conditioned).
    let mut m = [[0.0f64; 3]; 3];
    let mut rhs = [Rgb::ZERO; 3];
    let mut wsum = 0.0;
    for &k in set {
        let d = (centroid[k] - at) / size;
        let phi = [1.0, d.x, d.y];
        let w = area[k];
        wsum += w;
        for r in 0..3 {
            for c in 0..3 {
                m[r][c] += w * phi[r] * phi[c];
            }
            rhs[r] += w * phi[r] * value[k];
        }
    }
    if !(wsum > 0.0) {
        return None;
    }
    let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    // Collinear centroids make the spatial block singular: compare the determinant of the normalised moment
    // matrix M/Σw with the square of its spatial spread.
    let spread = (m[1][1] + m[2][2]) / wsum;
    if !((det / (wsum * wsum * wsum)).abs() > 1e-8 * spread * spread) {
        return None;
    }
    // Cramer's rule for the constant term a = det(M with column 0 replaced by rhs) / det(M).
    let col = |r: usize| rhs[r];
    let a = col(0) * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (col(1) * m[2][2] - m[1][2] * col(2))
        + m[0][2] * (col(1) * m[2][1] - m[1][1] * col(2));
    let b = a / det;
    b.is_finite().then_some(b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::dvec3;

    fn grid(n: usize, field: impl Fn(DVec3) -> Rgb) -> Vec<ElementValue> {
        let face = Polygon::quad(
            dvec3(0., 0., 0.),
            dvec3(2., 0., 0.),
            dvec3(2., 1., 0.),
            dvec3(0., 1., 0.),
        );
        face.subdivide(1.0 / n as f64)
            .into_iter()
            .map(|p| ElementValue {
                face: 0,
                polygon: p,
                radiosity: field(p.centroid()),
                open: 1.0,
            })
            .collect()
    }

    #[test]
    fn linear_field_is_reproduced_exactly_on_quads_and_triangles() {
        let field = |p: DVec3| Rgb::new(1.0 + 2.0 * p.x - 0.5 * p.y, 3.0 + p.y, 2.0 + 0.1 * p.x);
        let els = grid(4, field);
        let g = GouraudField::new(&els);
        for (e, el) in els.iter().enumerate() {
            for (u, v) in [(0.0, 0.0), (0.3, 0.7), (1.0, 1.0), (0.5, 0.1)] {
                let p = el.polygon.point_at(u, v);
                let d = (g.at(e, p) - field(p)).abs().max_element();
                assert!(d < 1e-12, "element {e} at ({u},{v}): {d}");
            }
        }
        // A triangle face in the m² lattice subdivision.
        let tri = Polygon::triangle(dvec3(0., 0., 1.), dvec3(1., 0., 1.), dvec3(0., 1., 1.));
        let els: Vec<ElementValue> = tri
            .subdivide(0.26)
            .into_iter()
            .map(|p| ElementValue {
                face: 3,
                polygon: p,
                radiosity: field(p.centroid()),
                open: 1.0,
            })
            .collect();
        let g = GouraudField::new(&els);
        for (e, el) in els.iter().enumerate() {
            let p = el.polygon.point_at(0.2, 0.3);
            let d = (g.at(e, p) - field(p)).abs().max_element();
            assert!(d < 1e-12, "triangle element {e}: {d}");
        }
    }

    #[test]
    fn continuous_across_element_edges_including_t_vertices() {
        // A 4 × 2 grid whose first element is split in four (T-vertices on its edges), arbitrary values.
        let mut els = grid(2, |p| Rgb::splat((7.0 * p.x).sin() + 2.0 + p.y * p.y));
        let first = els.remove(0);
        for (k, c) in first.polygon.split4().into_iter().enumerate() {
            els.push(ElementValue {
                face: 0,
                polygon: c,
                radiosity: Rgb::splat(1.0 + k as f64),
                open: 1.0,
            });
        }
        let g = GouraudField::new(&els);
        // Along every edge of every element, the value from that element equals the value from any other
        // element containing the same edge point.
        let mut checked = 0;
        for (e, el) in els.iter().enumerate() {
            let v = el.polygon.vertices();
            for k in 0..v.len() {
                for t in [0.0, 0.25, 0.5, 0.75, 1.0] {
                    let p = v[k].lerp(v[(k + 1) % v.len()], t);
                    for (e2, el2) in els.iter().enumerate() {
                        if e2 != e && el2.polygon.distance_to(p) < 1e-12 {
                            let d = (g.at(e, p) - g.at(e2, p)).abs().max_element();
                            assert!(d < 1e-12, "elements {e} and {e2} at {p}: {d}");
                            checked += 1;
                        }
                    }
                }
            }
        }
        assert!(checked > 50, "{checked}");
    }

    #[test]
    fn one_element_face_is_constant() {
        let els = grid(1, |_| Rgb::new(0.5, 1.0, 2.0));
        let g = GouraudField::new(&els);
        for (e, el) in els.iter().enumerate() {
            assert_eq!(g.at(e, el.polygon.centroid()), Rgb::new(0.5, 1.0, 2.0));
        }
    }
}

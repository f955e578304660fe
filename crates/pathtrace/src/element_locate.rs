//! Constant-time location of the element of an [`ElementMesh`] that contains a point on a face, for
//! depositing particles. The mesh (`Polygon::subdivide`) cuts a quad into an nu × nv grid of its bilinear
//! parameterisation p(s, t) (row-major, t outer) and a triangle into m² lattice triangles; inverting the
//! parameterisation (Newton's method for the bilinear map, exact barycentrics for the triangle) gives the
//! cell. Each face's grid shape is read from the mesh and checked once (cell centroids must map back to their
//! own index); a face whose layout does not match falls back to `ElementMesh::locate` (a scan), so answers
//! stay right even if the mesh's layout changes, only slower (the unit test below fails in that case).

use glam::{DVec2, DVec3};
use radlab_scene::{ElementMesh, FaceId, Polygon, Scene, sampling};

#[derive(Clone, Copy, Debug)]
enum Layout {
    Grid { nu: u32, nv: u32 },
    Lattice { m: u32 },
    Scan,
}

/// Per-face layouts of an element mesh.
#[derive(Clone, Debug)]
pub(crate) struct ElementLocator {
    layouts: Vec<Layout>,
}

/// Coordinates of `p` in the face's plane, relative to `origin`.
fn planar(p: DVec3, origin: DVec3, t: DVec3, b: DVec3) -> DVec2 {
    let d = p - origin;
    DVec2::new(d.dot(t), d.dot(b))
}

/// (s, t) with `poly.point_at(s, t)` closest to p, for a planar convex quad.
fn inverse_bilinear(poly: &Polygon, p: DVec3) -> (f64, f64) {
    let v = poly.vertices();
    let (tu, tv) = sampling::basis(poly.normal());
    let e = planar(v[1], v[0], tu, tv);
    let f = planar(v[3], v[0], tu, tv);
    let g = planar(v[2], v[0], tu, tv) - e - f;
    let h = planar(p, v[0], tu, tv);
    // p(s,t) − v0 = s e + t f + s t g; Newton from the centre (one step for a parallelogram).
    let (mut s, mut t) = (0.5, 0.5);
    for _ in 0..12 {
        let r = e * s + f * t + g * (s * t) - h;
        let js = e + g * t;
        let jt = f + g * s;
        let det = js.x * jt.y - js.y * jt.x;
        if det == 0.0 || det.is_nan() {
            break;
        }
        let ds = (r.x * jt.y - r.y * jt.x) / det;
        let dt = (js.x * r.y - js.y * r.x) / det;
        s -= ds;
        t -= dt;
        if ds.abs() + dt.abs() < 1e-13 {
            break;
        }
    }
    (s, t)
}

fn lattice_index(poly: &Polygon, p: DVec3, m: u32) -> usize {
    let v = poly.vertices();
    let (tu, tv) = sampling::basis(poly.normal());
    let e = planar(v[1], v[0], tu, tv);
    let f = planar(v[2], v[0], tu, tv);
    let h = planar(p, v[0], tu, tv);
    let det = e.x * f.y - e.y * f.x;
    let (l1, l2) = if det.abs() > 0.0 {
        ((h.x * f.y - h.y * f.x) / det, (e.x * h.y - e.y * h.x) / det)
    } else {
        (0.0, 0.0)
    };
    let m = m as i64;
    let (x, y) = (l1 * m as f64, l2 * m as f64);
    let j = (y.floor() as i64).clamp(0, m - 1);
    let i = (x.floor() as i64).clamp(0, m - 1 - j);
    let upper = (x - i as f64) + (y - j as f64) > 1.0 && i + j + 1 < m;
    (2 * j * m - j * j + 2 * i + upper as i64) as usize
}

impl ElementLocator {
    /// Works out and checks the layout of every face of `mesh` (built over `scene`). The grid's shape is read
    /// from the mesh itself (a triangle's m² pieces; a quad's first cell spans s ∈ [0, 1/nu]), not from the
    /// element size, so it does not depend on how the mesh picks its resolution.
    pub(crate) fn new(scene: &Scene, mesh: &ElementMesh) -> Self {
        let layouts = (0..scene.faces.len())
            .map(|f| {
                let poly = scene.polygon(f);
                let range = mesh.elements_of(f);
                let n = range.len();
                if n == 0 {
                    return Layout::Scan;
                }
                let layout = if poly.len() == 4 {
                    let corner = mesh.elements[range.start].polygon.vertices()[1];
                    let s1 = inverse_bilinear(&poly, corner).0;
                    let nu = if s1 > 0.0 { (1.0 / s1).round() } else { 0.0 };
                    if !(1.0..=n as f64).contains(&nu) || !n.is_multiple_of(nu as usize) {
                        return Layout::Scan;
                    }
                    Layout::Grid {
                        nu: nu as u32,
                        nv: (n / nu as usize) as u32,
                    }
                } else {
                    let m = (n as f64).sqrt().round() as usize;
                    if m * m != n {
                        return Layout::Scan;
                    }
                    Layout::Lattice { m: m as u32 }
                };
                let probes = [0, 1, n / 2, n.saturating_sub(2), n - 1];
                let ok = probes.iter().all(|&k| {
                    let k = k.min(n - 1);
                    Self::guess(&poly, layout, mesh.elements[range.start + k].centroid) == Some(k)
                });
                if ok { layout } else { Layout::Scan }
            })
            .collect();
        Self { layouts }
    }

    fn guess(poly: &Polygon, layout: Layout, p: DVec3) -> Option<usize> {
        match layout {
            Layout::Grid { nu, nv } => {
                let (s, t) = inverse_bilinear(poly, p);
                let cell = |x: f64, n: u32| ((x * n as f64).floor().max(0.0) as u32).min(n - 1);
                Some(cell(t, nv) as usize * nu as usize + cell(s, nu) as usize)
            }
            Layout::Lattice { m } => Some(lattice_index(poly, p, m)),
            Layout::Scan => None,
        }
    }

    /// The element of face `f` containing `p` (the nearest for a point slightly outside the face).
    pub(crate) fn locate(&self, scene: &Scene, mesh: &ElementMesh, f: FaceId, p: DVec3) -> usize {
        match Self::guess(&scene.polygon(f), self.layouts[f], p) {
            Some(k) => mesh.elements_of(f).start + k,
            None => mesh.locate(f, p),
        }
    }

    /// Faces that fall back to scanning (for tests and diagnostics).
    #[cfg(test)]
    pub(crate) fn scanned_faces(&self) -> usize {
        self.layouts
            .iter()
            .filter(|l| matches!(l, Layout::Scan))
            .count()
    }

    /// Approximate heap bytes held.
    pub(crate) fn bytes(&self) -> usize {
        self.layouts.len() * size_of::<Layout>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::dvec3;
    use radlab_scene::{Material, SceneBuilder};

    #[test]
    fn agrees_with_the_mesh_scan_on_quads_and_triangles() {
        let mut b = SceneBuilder::new("shapes");
        let m = b
            .add_material(Material::new("m", DVec3::splat(0.5), DVec3::ZERO).expect("material"))
            .expect("add");
        // A trapezoid, a skewed parallelogram, a long thin rectangle, a triangle, a tilted triangle.
        let polys: Vec<Vec<DVec3>> = vec![
            vec![
                dvec3(0., 0., 0.),
                dvec3(4., 0., 0.),
                dvec3(3., 2., 0.),
                dvec3(1., 2., 0.),
            ],
            vec![
                dvec3(0., 0., 1.),
                dvec3(2., 0.5, 1.),
                dvec3(2.7, 2.5, 1.),
                dvec3(0.7, 2., 1.),
            ],
            vec![
                dvec3(0., 0., 2.),
                dvec3(0., 0.1, 2.),
                dvec3(-5., 0.1, 2.),
                dvec3(-5., 0., 2.),
            ],
            vec![dvec3(0., 0., 3.), dvec3(3., 0.2, 3.), dvec3(1., 2.5, 3.)],
            vec![dvec3(0., 0., 0.), dvec3(1., 2., 3.), dvec3(-2., 1., 0.5)],
        ];
        for p in &polys {
            b.add_polygon_points(p, m, "test").expect("polygon");
        }
        let scene = b.build().expect("scene");
        for size in [0.05, 0.3, 1.0, 10.0] {
            let mesh = ElementMesh::new(&scene, size);
            let loc = ElementLocator::new(&scene, &mesh);
            assert_eq!(
                loc.scanned_faces(),
                0,
                "size {size}: a face fell back to scanning"
            );
            let mut rng = sampling::rng(3, size.to_bits());
            for f in 0..scene.faces.len() {
                let poly = scene.polygon(f);
                for _ in 0..300 {
                    let p = poly
                        .sample_uniform(sampling::uniform(&mut rng), sampling::uniform(&mut rng));
                    let fast = loc.locate(&scene, &mesh, f, p);
                    assert!(
                        mesh.elements[fast].polygon.contains(p, 1e-9),
                        "face {f} size {size}: {p:?} not in element {fast}"
                    );
                }
            }
        }
    }
}

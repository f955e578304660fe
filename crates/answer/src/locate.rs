//! Point location in an element mesh: which leaf element of a face contains a surface point. One locator for
//! every method's mesh: a fixed [`crate::ElementMesh`], progressive radiosity's patches and element quadtrees,
//! hierarchical radiosity's quadtrees. A mesh shows its shape through [`ElementTree`] (the top-level elements
//! of each face and the children of each element).
//!
//! [`ElementLocator`] puts a uniform 2-D grid over each face's top-level elements (in the face's plane, about
//! one cell per element, each cell listing the elements whose bounding boxes overlap it; a bucket grid, Akman,
//! Franklin, Kankanhalli & Narayanaswami 1989), then [`descend`] follows the quadtree from the top-level
//! element containing the point to the leaf. Containment is [`radlab_scene::Polygon::contains`] at the relative
//! tolerance [`CONTAINS_TOL`]; a point slightly off every element (rounding on a shared edge, or just outside
//! the face) goes to the nearest one. Expected cost per query: O(1 + depth), whatever the mesh's scale.

use std::ops::Range;

use glam::{DVec2, DVec3};

use radlab_scene::{FaceId, Polygon, Scene, sampling};

/// Relative tolerance of the containment tests (a fraction of the element's longest edge).
pub const CONTAINS_TOL: f64 = 1e-9;

/// An element mesh as the locator sees it: top-level elements per face, each the root of a tree of elements
/// (children partition their parent).
pub trait ElementTree {
    /// The top-level elements of face `face` (empty for a face without elements or out of range).
    fn roots(&self, face: FaceId) -> Range<u32>;
    /// The geometry of element `e` (`None`: not a surface element; skipped).
    fn polygon(&self, e: u32) -> Option<&Polygon>;
    /// The children of element `e` (empty for a leaf).
    fn children(&self, e: u32) -> Range<u32>;
}

/// The element among `candidates` that contains `point`, else the nearest one; `None` if there are none.
fn nearest(
    tree: &impl ElementTree,
    candidates: impl Iterator<Item = u32>,
    point: DVec3,
) -> Option<u32> {
    let mut best = None;
    let mut best_d = f64::INFINITY;
    for e in candidates {
        let Some(poly) = tree.polygon(e) else {
            continue;
        };
        if poly.contains(point, CONTAINS_TOL) {
            return Some(e);
        }
        let d = poly.distance_to(point);
        if d < best_d {
            best_d = d;
            best = Some(e);
        }
    }
    best
}

/// The leaf below element `e` that contains `point` (the nearest child at each level for a point slightly
/// outside), descending the tree.
pub fn descend(tree: &impl ElementTree, mut e: u32, point: DVec3) -> u32 {
    loop {
        let children = tree.children(e);
        if children.is_empty() {
            return e;
        }
        match nearest(tree, children, point) {
            Some(c) => e = c,
            None => return e,
        }
    }
}

#[derive(Clone, Copy, Debug)]
struct FaceGrid {
    origin: DVec3,
    u: DVec3,
    v: DVec3,
    lo: DVec2,
    inv_cell: DVec2,
    nx: u32,
    ny: u32,
    first_cell: u32,
}

/// Per-face bucket grids over the top-level elements of an [`ElementTree`]. Elements created later below
/// the top level (adaptive subdivision) are found by [`descend`]; the top level must not change.
#[derive(Clone, Debug)]
pub struct ElementLocator {
    grids: Vec<FaceGrid>,
    cell_start: Vec<u32>,
    items: Vec<u32>,
}

impl ElementLocator {
    /// Builds the grids of every face of `scene` over `tree`'s top-level elements.
    pub fn new(scene: &Scene, tree: &impl ElementTree) -> Self {
        let mut grids = Vec::with_capacity(scene.face_count());
        let mut cell_start = vec![0u32];
        let mut items = Vec::new();
        for f in 0..scene.face_count() {
            let roots = tree.roots(f);
            let (u, v) = sampling::basis(scene.faces[f].normal);
            let origin = scene.faces[f].centroid;
            let to2 = |p: DVec3| DVec2::new((p - origin).dot(u), (p - origin).dot(v));
            let boxes: Vec<(u32, DVec2, DVec2)> = roots
                .filter_map(|r| {
                    let poly = tree.polygon(r)?;
                    let mut lo = DVec2::splat(f64::INFINITY);
                    let mut hi = DVec2::splat(f64::NEG_INFINITY);
                    for &p in poly.vertices() {
                        lo = lo.min(to2(p));
                        hi = hi.max(to2(p));
                    }
                    Some((r, lo, hi))
                })
                .collect();
            let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
            for b in &boxes {
                lo = lo.min(b.1);
                hi = hi.max(b.2);
            }
            if boxes.is_empty() {
                (lo, hi) = (DVec2::ZERO, DVec2::ONE);
            }
            let k = boxes.len().max(1) as f64;
            let ext = (hi - lo).max(DVec2::splat(f64::MIN_POSITIVE));
            let nx = ((k * ext.x / ext.y).sqrt().round()).clamp(1.0, k) as u32;
            let ny = (k / nx as f64).ceil().clamp(1.0, k) as u32;
            // Pad the grid a little so points on the face's boundary fall inside it.
            let pad = 1e-9 * ext.max_element();
            let (glo, ghi) = (lo - DVec2::splat(pad), hi + DVec2::splat(pad));
            let inv_cell = DVec2::new(nx as f64, ny as f64) / (ghi - glo);
            let first_cell = (cell_start.len() - 1) as u32;
            let grid = FaceGrid {
                origin,
                u,
                v,
                lo: glo,
                inv_cell,
                nx,
                ny,
                first_cell,
            };
            let mut per_cell: Vec<Vec<u32>> = vec![Vec::new(); (nx * ny) as usize];
            for &(r, blo, bhi) in &boxes {
                let (x0, y0) = grid.cell_of(blo);
                let (x1, y1) = grid.cell_of(bhi);
                for y in y0..=y1 {
                    for x in x0..=x1 {
                        per_cell[(y * nx + x) as usize].push(r);
                    }
                }
            }
            for c in per_cell {
                items.extend(c);
                cell_start.push(items.len() as u32);
            }
            grids.push(grid);
        }
        Self {
            grids,
            cell_start,
            items,
        }
    }

    /// The leaf element of face `face` that contains `point`, or the nearest one; `None` for a face without
    /// elements or an out-of-range face.
    pub fn locate(&self, tree: &impl ElementTree, face: FaceId, point: DVec3) -> Option<u32> {
        let g = self.grids.get(face)?;
        let d = point - g.origin;
        let (x, y) = g.cell_of(DVec2::new(d.dot(g.u), d.dot(g.v)));
        let cell = (g.first_cell + y * g.nx + x) as usize;
        let cand = &self.items[self.cell_start[cell] as usize..self.cell_start[cell + 1] as usize];
        let top = match nearest(tree, cand.iter().copied(), point) {
            Some(e) => e,
            None => nearest(tree, tree.roots(face), point)?,
        };
        Some(descend(tree, top, point))
    }

    /// Like [`ElementLocator::locate`], but only a leaf that really contains `point`.
    pub fn locate_containing(
        &self,
        tree: &impl ElementTree,
        face: FaceId,
        point: DVec3,
    ) -> Option<u32> {
        self.locate(tree, face, point).filter(|&e| {
            tree.polygon(e)
                .is_some_and(|p| p.contains(point, CONTAINS_TOL))
        })
    }

    /// Approximate heap bytes held.
    pub fn bytes(&self) -> usize {
        self.grids.capacity() * size_of::<FaceGrid>()
            + (self.cell_start.capacity() + self.items.capacity()) * 4
    }
}

impl FaceGrid {
    /// The cell holding in-plane coordinates `p` (clamped to the grid).
    fn cell_of(&self, p: DVec2) -> (u32, u32) {
        let c = ((p - self.lo) * self.inv_cell).floor();
        (
            (c.x.max(0.0) as u32).min(self.nx - 1),
            (c.y.max(0.0) as u32).min(self.ny - 1),
        )
    }
}

#[cfg(test)]
mod tests {
    use glam::dvec3;

    use super::*;

    use crate::ElementMesh;
    use radlab_scene::{Material, SceneBuilder, sampling};

    #[test]
    fn every_point_of_a_face_is_found_in_its_element() {
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
            let mut rng = sampling::rng(3, size.to_bits());
            for f in 0..scene.faces.len() {
                let poly = scene.polygon(f);
                for _ in 0..300 {
                    let p = poly
                        .sample_uniform(sampling::uniform(&mut rng), sampling::uniform(&mut rng));
                    let e = mesh.locate(f, p);
                    assert!(mesh.elements_of(f).contains(&e));
                    assert!(
                        mesh.elements[e].polygon.contains(p, CONTAINS_TOL),
                        "face {f} size {size}: {p:?} not in element {e}"
                    );
                }
                // A point just off the face goes to an element of that face.
                let v = poly.vertices()[0];
                let outside = v - 0.01 * (poly.centroid() - v);
                assert!(mesh.elements_of(f).contains(&mesh.locate(f, outside)));
            }
        }
    }
}

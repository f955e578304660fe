//! Point location among the elements of a face: which leaf element contains a surface point.
//!
//! After adaptive subdivision the elements are no longer a regular grid, so each face gets a uniform 2-D grid
//! over its top-level elements (in the face's plane, about one cell per element, each cell listing the
//! elements whose bounding boxes overlap it), and a point descends from the top-level element containing it
//! through the quadtree of [`radlab_scene::Polygon::split4`] children. Containment uses
//! [`radlab_scene::Polygon::contains`]; a point slightly off every element (rounding on a shared edge, or just
//! outside the face) goes to the nearest one. Expected cost per query: O(1 + depth).

use glam::{DVec2, DVec3};
use radlab_scene::{Scene, sampling};

use crate::substructuring::Mesh;

/// Relative tolerance of containment tests.
const CONTAINS_TOL: f64 = 1e-9;

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

/// Per-face grids over the top-level elements.
#[derive(Clone, Debug)]
pub(crate) struct ElementLocator {
    grids: Vec<FaceGrid>,
    cell_start: Vec<u32>,
    items: Vec<u32>,
}

impl ElementLocator {
    /// Builds the grids of every face of `scene` over `mesh`'s top-level elements.
    pub fn new(scene: &Scene, mesh: &Mesh) -> Self {
        let mut grids = Vec::with_capacity(scene.face_count());
        let mut cell_start = vec![0u32];
        let mut items = Vec::new();
        for f in 0..scene.face_count() {
            let roots = mesh.roots_of(f);
            let (u, v) = sampling::basis(scene.faces[f].normal);
            let origin = scene.faces[f].centroid;
            let to2 = |p: DVec3| DVec2::new((p - origin).dot(u), (p - origin).dot(v));
            let boxes: Vec<(DVec2, DVec2)> = roots
                .clone()
                .map(|r| {
                    let vs = mesh.elements[r].polygon.vertices();
                    let mut lo = DVec2::splat(f64::INFINITY);
                    let mut hi = DVec2::splat(f64::NEG_INFINITY);
                    for &p in vs {
                        lo = lo.min(to2(p));
                        hi = hi.max(to2(p));
                    }
                    (lo, hi)
                })
                .collect();
            let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
            for b in &boxes {
                lo = lo.min(b.0);
                hi = hi.max(b.1);
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
            let cell_of = |p: DVec2| {
                let c = ((p - glo) * inv_cell).floor();
                (
                    (c.x.max(0.0) as u32).min(nx - 1),
                    (c.y.max(0.0) as u32).min(ny - 1),
                )
            };
            let mut per_cell: Vec<Vec<u32>> = vec![Vec::new(); (nx * ny) as usize];
            for (r, b) in roots.zip(&boxes) {
                let (x0, y0) = cell_of(b.0);
                let (x1, y1) = cell_of(b.1);
                for y in y0..=y1 {
                    for x in x0..=x1 {
                        per_cell[(y * nx + x) as usize].push(r as u32);
                    }
                }
            }
            for c in per_cell {
                items.extend(c);
                cell_start.push(items.len() as u32);
            }
            grids.push(FaceGrid {
                origin,
                u,
                v,
                lo: glo,
                inv_cell,
                nx,
                ny,
                first_cell,
            });
        }
        Self {
            grids,
            cell_start,
            items,
        }
    }

    /// The leaf element of face `face` that contains `point`, or the nearest one; `None` for a face without
    /// elements or an out-of-range face.
    pub fn locate(&self, mesh: &Mesh, face: usize, point: DVec3) -> Option<u32> {
        let g = self.grids.get(face)?;
        let d = point - g.origin;
        let c = ((DVec2::new(d.dot(g.u), d.dot(g.v)) - g.lo) * g.inv_cell).floor();
        let (x, y) = (
            (c.x.max(0.0) as u32).min(g.nx - 1),
            (c.y.max(0.0) as u32).min(g.ny - 1),
        );
        let cell = (g.first_cell + y * g.nx + x) as usize;
        let cand = &self.items[self.cell_start[cell] as usize..self.cell_start[cell + 1] as usize];
        let nearest = |it: &mut dyn Iterator<Item = u32>| -> Option<u32> {
            let mut best = None;
            let mut best_d = f64::INFINITY;
            for e in it {
                let poly = &mesh.elements[e as usize].polygon;
                if poly.contains(point, CONTAINS_TOL) {
                    return Some(e);
                }
                let dist = poly.distance_to(point);
                if dist < best_d {
                    best_d = dist;
                    best = Some(e);
                }
            }
            best
        };
        let mut e = match nearest(&mut cand.iter().copied()) {
            Some(e) => e,
            None => nearest(&mut mesh.roots_of(face).map(|r| r as u32))?,
        };
        loop {
            let el = &mesh.elements[e as usize];
            if el.is_leaf() {
                return Some(e);
            }
            e = nearest(&mut (el.first_child..el.first_child + 4))?;
        }
    }

    /// Like [`ElementLocator::locate`], but only a leaf that really contains `point`.
    pub fn locate_containing(&self, mesh: &Mesh, face: usize, point: DVec3) -> Option<u32> {
        self.locate(mesh, face, point).filter(|&e| {
            mesh.elements[e as usize]
                .polygon
                .contains(point, CONTAINS_TOL)
        })
    }

    /// Approximate heap bytes held.
    pub fn bytes(&self) -> usize {
        self.grids.capacity() * size_of::<FaceGrid>()
            + (self.cell_start.capacity() + self.items.capacity()) * 4
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::substructuring::{Element, LEAF};

    #[test]
    fn every_leaf_is_found_from_its_own_points() {
        let scene = radlab_scene::builtin("furnace-cube?tessellation=3&size=7").expect("scene");
        let mut mesh = Mesh::new(&scene, 1.2, 0.5, 1e9).expect("mesh");
        // Split a few elements twice to make a mixed-depth quadtree.
        for e in [0u32, 5, 17, 40] {
            for _ in 0..2 {
                let target = {
                    let mut l = Vec::new();
                    mesh.leaves_below(e, &mut l);
                    l[l.len() / 2]
                };
                let parent = mesh.elements[target as usize];
                let first = mesh.elements.len() as u32;
                for polygon in parent.polygon.split4() {
                    mesh.elements.push(Element {
                        polygon,
                        area: polygon.area(),
                        first_child: LEAF,
                        ..parent
                    });
                }
                mesh.elements[target as usize].first_child = first;
            }
        }
        let loc = ElementLocator::new(&scene, &mesh);
        let mut leaves = Vec::new();
        for f in 0..scene.face_count() {
            for r in mesh.roots_of(f) {
                mesh.leaves_below(r as u32, &mut leaves);
            }
        }
        assert!(leaves.len() > mesh.face_roots[scene.face_count()] as usize);
        for &e in &leaves {
            let el = &mesh.elements[e as usize];
            for (s, t) in [(0.5, 0.5), (0.1, 0.2), (0.9, 0.7)] {
                let p = el.polygon.point_at(s, t);
                assert_eq!(loc.locate(&mesh, el.face as usize, p), Some(e));
            }
        }
        // A point just off the face still finds an element; locate_containing refuses it.
        let f = 0;
        let corner = scene.polygon(f).vertices()[0];
        let outside = corner - 0.01 * (scene.faces[f].centroid - corner);
        assert!(loc.locate(&mesh, f, outside).is_some());
        assert!(loc.locate_containing(&mesh, f, outside).is_none());
        assert!(loc.locate(&mesh, scene.face_count(), corner).is_none());
    }
}

//! Point location among the elements of a face: progressive radiosity's mesh (top-level elements per face,
//! each the root of a quadtree of [`radlab_scene::Polygon::split4`] children) seen as an
//! [`radlab_answer::ElementTree`], so the shared [`radlab_answer::ElementLocator`] finds the leaf containing a
//! surface point in O(1 + depth).

use std::ops::Range;

use radlab_answer::ElementTree;
use radlab_scene::{FaceId, Polygon};

use crate::substructuring::Mesh;

pub(crate) use radlab_answer::ElementLocator;

impl ElementTree for Mesh {
    fn roots(&self, face: FaceId) -> Range<u32> {
        match (self.face_roots.get(face), self.face_roots.get(face + 1)) {
            (Some(&a), Some(&b)) => a..b,
            _ => 0..0,
        }
    }

    fn polygon(&self, e: u32) -> Option<&Polygon> {
        self.elements.get(e as usize).map(|el| &el.polygon)
    }

    fn children(&self, e: u32) -> Range<u32> {
        match self.elements.get(e as usize) {
            Some(el) if !el.is_leaf() => el.first_child..el.first_child + 4,
            _ => 0..0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
                mesh.split_leaves(&[target]);
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

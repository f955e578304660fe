//! Locating a surface point in a face's quadtree, through radlab-scene's shared locator: the engine's nodes
//! seen as an [`ElementTree`] (one top-level element per face, the node that is the whole face), descended by
//! containment ([`radlab_answer::locate::descend`]). For interpolation within an element, a point's coordinates
//! in the face's parameter space ([`radlab_scene::Polygon::param_coords`]), where every element is a lattice
//! polygon (see [`crate::node::Patch::uv`]).

use std::ops::Range;

use glam::{DVec2, DVec3};
use radlab_answer::ElementTree;
use radlab_scene::{FaceId, Polygon};

use crate::hierarchy::Engine;
use crate::node::{LATTICE, NodeKind, Patch};
use crate::transport::Transport;

/// Parameter coordinates of `p` (a point on or near the polygon) in the polygon's own map, clamped to it.
pub fn param_coords(poly: &Polygon, p: DVec3) -> DVec2 {
    let q = poly.param_coords(p);
    if poly.is_triangle() {
        let q = q.max(DVec2::ZERO);
        let s = q.x + q.y;
        if s > 1.0 { q / s } else { q }
    } else {
        q.clamp(DVec2::ZERO, DVec2::ONE)
    }
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

/// An engine's quadtrees as the shared locator sees them.
pub(crate) struct Quadtrees<'a, N: NodeKind, T: Transport<N>>(pub &'a Engine<N, T>);

impl<N: NodeKind, T: Transport<N>> ElementTree for Quadtrees<'_, N, T> {
    fn roots(&self, face: FaceId) -> Range<u32> {
        match self.0.face_node(face) {
            Some(i) => i..i + 1,
            None => 0..0,
        }
    }

    fn polygon(&self, e: u32) -> Option<&Polygon> {
        self.0.nodes().get(e as usize)?.patch().map(|p| &p.polygon)
    }

    fn children(&self, e: u32) -> Range<u32> {
        self.0.children(e)
    }
}

//! Locating a surface point in a face's quadtree, through radlab-answer's shared locator: the engine's nodes
//! seen as an [`ElementTree`] (one top-level element per face, the node that is the whole face), descended by
//! containment ([`radlab_answer::locate::descend`]).

use std::ops::Range;

use radlab_answer::ElementTree;
use radlab_scene::{FaceId, Polygon};

use crate::hierarchy::Engine;
use crate::node::NodeKind;
use crate::transport::Transport;

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

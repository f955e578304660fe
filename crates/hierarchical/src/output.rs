//! The output layer, for any node kind whose hierarchy reaches the input faces: locating a surface point in
//! the hierarchy (from the node that is the whole face down through its quadtree by containment, the shared
//! [`radlab_answer::locate::descend`]) and answering radiosity there through the shared answering layer
//! ([`Reconstructor`]), as every element method does: constant per leaf, vertex-interpolated over each face's
//! leaves (radlab-answer's Gouraud: least-squares vertex values, T-vertices anchored to the coarser edge), or
//! by a final gather from every leaf (B(x) = E(x) + ρ(x) Σ_j F_{x→j} V_xj B_j; Lischinski, Tampieri &
//! Greenberg 1993). Solvers built on the engine (patches, volume clusters) share it.

use glam::DVec3;
use radlab_answer::{AnswerParams, Reconstruction, Reconstructor, gouraud::ElementValue};
use radlab_scene::{FaceId, Rgb, Scene};
use radlab_visibility::Accel;

use crate::hierarchy::Engine;
use crate::locate::Quadtrees;
use crate::node::NodeKind;
use crate::transport::Transport;

/// Radiosity at surface points from an engine's solution, answered through the shared answering layer.
#[derive(Debug)]
pub struct SurfaceOutput {
    /// Constant, Gouraud or final-gather answers from the leaves, and the data they build.
    answer: Reconstructor,
    /// Per node id, its index among the Gouraud elements ([`leaf_elements`] with sealed leaves), or `u32::MAX` for a node
    /// that is not a quadtree leaf (Gouraud only; empty otherwise).
    element_index: Vec<u32>,
}

impl SurfaceOutput {
    /// Output answering as `params` ask (a final gather at their opening: radlab-answer's
    /// [`radlab_answer::final_gather::FinalGather::with_opening`]; 0 gathers every leaf); a final gather draws
    /// its rays from `seed`.
    pub fn new(params: &AnswerParams, seed: u64) -> Self {
        Self {
            answer: Reconstructor::of(params, seed),
            element_index: Vec::new(),
        }
    }

    /// How points are answered.
    pub fn reconstruction(&self) -> Reconstruction {
        self.answer.kind()
    }

    /// Rays and kernel evaluations the final gather has spent answering so far (charged to answering, not
    /// to the steps).
    pub fn gather_work(&self) -> (u64, u64) {
        self.answer.gather_work()
    }

    /// Forgets what the reconstruction built from the previous solution; for Gouraud answers, numbers the
    /// quadtree leaves of the engine's current hierarchy.
    pub fn update<N: NodeKind, T: Transport<N>>(&mut self, engine: &Engine<N, T>) {
        self.answer.invalidate();
        if self.answer.kind() != Reconstruction::Gouraud {
            return;
        }
        let mut next = 0;
        self.element_index = (0..engine.nodes().len() as u32)
            .map(|i| {
                if engine.is_leaf(i) && engine.nodes()[i as usize].patch().is_some() {
                    next += 1;
                    next - 1
                } else {
                    u32::MAX
                }
            })
            .collect();
    }

    /// Bytes held.
    pub fn bytes(&self) -> u64 {
        (self.element_index.capacity() * size_of::<u32>() + self.answer.bytes()) as u64
    }

    /// Radiosity of `face` at `point` (of `scene`, rays through `accel` for a final gather): zero for a face
    /// the hierarchy does not reach.
    pub fn radiosity_at<N: NodeKind, T: Transport<N>>(
        &self,
        engine: &Engine<N, T>,
        scene: &Scene,
        accel: &Accel,
        face: FaceId,
        point: DVec3,
    ) -> Rgb {
        let Some(i) = locate(engine, face, point) else {
            return Rgb::ZERO;
        };
        let gouraud = self.answer.kind() == Reconstruction::Gouraud;
        self.answer.radiosity_at(
            scene,
            accel,
            face,
            point,
            || engine.radiosity_at_leaf(i, point),
            || {
                self.element_index
                    .get(i as usize)
                    .filter(|&&e| e != u32::MAX)
                    .map(|&e| e as usize)
            },
            || leaf_elements(engine, gouraud),
        )
    }
}

/// The leaf of `face` containing `point` (the nearest one for points slightly outside), descending from the
/// node that is the whole face; `None` if the hierarchy has no node for the face.
pub fn locate<N: NodeKind, T: Transport<N>>(
    engine: &Engine<N, T>,
    face: FaceId,
    point: DVec3,
) -> Option<u32> {
    let i = engine.face_node(face)?;
    if engine.nodes()[i as usize].patch().is_none() {
        return Some(i);
    }
    Some(radlab_answer::locate::descend(&Quadtrees(engine), i, point))
}

/// Every leaf that is a quadtree element, in node order, as the shared reconstructions see it, with its open
/// share. Gouraud interpolation takes them all (a vertex's value comes from every leaf around it); a final
/// gather (`sealed = false`) leaves out wholly sealed leaves (o = 0), which send nothing, and samples the
/// visibility of a source with o < 1 over its area.
fn leaf_elements<N: NodeKind, T: Transport<N>>(
    engine: &Engine<N, T>,
    sealed: bool,
) -> Vec<ElementValue> {
    (0..engine.nodes().len() as u32)
        .filter(|&i| engine.is_leaf(i) && (sealed || engine.open_shares()[i as usize] > 0.0))
        .filter_map(|i| {
            let p = engine.nodes()[i as usize].patch()?;
            Some(ElementValue {
                face: p.face,
                polygon: p.polygon,
                radiosity: engine.radiosity()[i as usize],
                open: engine.open_shares()[i as usize],
            })
        })
        .collect()
}

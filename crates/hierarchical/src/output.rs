//! The output layer, for any node kind whose hierarchy reaches the input faces: locating a surface point in
//! the hierarchy (from the node that is the whole face down through its quadtree by containment, radlab-scene's
//! shared [`radlab_scene::locate::descend`]) and answering radiosity there: constant per leaf,
//! vertex-interpolated (the crate's `gouraud` module), or by a final gather from every leaf
//! (B(x) = E(x) + ρ(x) Σ_j F_{x→j} V_xj B_j; Lischinski, Tampieri & Greenberg 1993, through radlab-scene's
//! shared [`Reconstructor`]). Solvers built on the engine (patches, volume clusters) share it.

use glam::DVec3;
use radlab_scene::{
    Accel, FaceId, Reconstruction, Reconstructor, Rgb, Scene, gouraud::ElementValue,
};
use rayon::prelude::*;

use crate::gouraud::{face_corner_values, interpolate};
use crate::hierarchy::Engine;
use crate::locate::{Quadtrees, param_coords, param_corners};
use crate::node::NodeKind;
use crate::transport::Transport;

/// Radiosity at surface points from an engine's solution.
#[derive(Debug)]
pub struct SurfaceOutput {
    reconstruction: Reconstruction,
    /// Corner values per node id (Gouraud only; empty otherwise).
    corner_values: Vec<[Rgb; 4]>,
    /// The final gather's data, rebuilt at the first query after each update.
    gather: Reconstructor,
}

impl SurfaceOutput {
    /// Output with the given reconstruction; a final gather draws its rays from `seed`.
    pub fn new(reconstruction: Reconstruction, seed: u64) -> Self {
        Self {
            reconstruction,
            corner_values: Vec::new(),
            gather: Reconstructor::new(reconstruction, seed),
        }
    }

    /// Rays and kernel evaluations the final gather has spent answering so far (charged to answering, not
    /// to the steps).
    pub fn gather_work(&self) -> (u64, u64) {
        self.gather.gather_work()
    }

    /// Recomputes what the reconstruction needs from the engine's current solution.
    pub fn update<N: NodeKind, T: Transport<N>>(&mut self, engine: &Engine<N, T>, faces: usize) {
        self.gather.invalidate();
        if self.reconstruction != Reconstruction::Gouraud {
            return;
        }
        let per_face: Vec<Vec<(u32, [Rgb; 4])>> = (0..faces)
            .into_par_iter()
            .filter_map(|f| engine.face_node(f))
            .map(|r| face_corner_values(engine, r))
            .collect();
        let mut values = vec![[Rgb::ZERO; 4]; engine.nodes().len()];
        for list in per_face {
            for (i, v) in list {
                values[i as usize] = v;
            }
        }
        self.corner_values = values;
    }

    /// Bytes held.
    pub fn bytes(&self) -> u64 {
        (self.corner_values.capacity() * size_of::<[Rgb; 4]>() + self.gather.bytes()) as u64
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
        if self.reconstruction == Reconstruction::FinalGather {
            return self.gather.radiosity_at(
                scene,
                accel,
                face,
                point,
                || engine.radiosity_at_leaf(i, point),
                || None,
                || leaf_elements(engine),
            );
        }
        if self.reconstruction == Reconstruction::Gouraud
            && let (Some(node), Some(root)) = (
                engine.nodes()[i as usize].patch(),
                engine
                    .face_node(face)
                    .and_then(|r| engine.nodes()[r as usize].patch()),
            )
            && let Some(values) = self.corner_values.get(i as usize)
        {
            let (corners, n) = param_corners(node);
            let q = param_coords(&root.polygon, point);
            return interpolate(&corners[..n], values, q);
        }
        engine.radiosity_at_leaf(i, point)
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
    Some(radlab_scene::locate::descend(&Quadtrees(engine), i, point))
}

/// Every leaf that is a quadtree element, as the shared reconstructions see it, with its open share (a
/// final gather samples the visibility of a source with o < 1 over its area); wholly sealed leaves (o = 0)
/// send nothing and are left out.
fn leaf_elements<N: NodeKind, T: Transport<N>>(engine: &Engine<N, T>) -> Vec<ElementValue> {
    (0..engine.nodes().len() as u32)
        .filter(|&i| engine.is_leaf(i) && engine.open_shares()[i as usize] > 0.0)
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

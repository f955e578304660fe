//! The output layer, for any node kind whose hierarchy reaches the input faces: locating a surface point in
//! the hierarchy (from the node that is the whole face down through its quadtree, in the face's parameter
//! space) and answering radiosity there, constant per leaf or vertex-interpolated ([`crate::gouraud`]).
//! Solvers built on the engine (patches, volume clusters) share it.

use glam::DVec3;
use radlab_scene::{FaceId, Rgb};
use rayon::prelude::*;

use crate::gouraud::{face_corner_values, interpolate};
use crate::hierarchy::Engine;
use crate::locate::{insideness, param_coords, param_corners};
use crate::node::NodeKind;
use crate::params::Interpolation;
use crate::transport::Transport;

/// Radiosity at surface points from an engine's solution.
#[derive(Clone, Debug, Default)]
pub struct SurfaceOutput {
    interpolation: Interpolation,
    /// Corner values per node id (Gouraud only; empty otherwise).
    corner_values: Vec<[Rgb; 4]>,
}

impl SurfaceOutput {
    /// Output with the given reconstruction.
    pub fn new(interpolation: Interpolation) -> Self {
        Self {
            interpolation,
            corner_values: Vec::new(),
        }
    }

    /// Recomputes what the reconstruction needs from the engine's current solution.
    pub fn update<N: NodeKind, T: Transport<N>>(&mut self, engine: &Engine<N, T>, faces: usize) {
        if self.interpolation != Interpolation::Gouraud {
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
        (self.corner_values.capacity() * size_of::<[Rgb; 4]>()) as u64
    }

    /// Radiosity of `face` at `point`: zero for a face the hierarchy does not reach.
    pub fn radiosity_at<N: NodeKind, T: Transport<N>>(
        &self,
        engine: &Engine<N, T>,
        face: FaceId,
        point: DVec3,
    ) -> Rgb {
        let Some(i) = locate(engine, face, point) else {
            return Rgb::ZERO;
        };
        if self.interpolation == Interpolation::Gouraud
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
        engine.radiosity()[i as usize]
    }
}

/// The leaf of `face` containing `point` (the nearest one for points slightly outside), descending from the
/// node that is the whole face; `None` if the hierarchy has no node for the face.
pub fn locate<N: NodeKind, T: Transport<N>>(
    engine: &Engine<N, T>,
    face: FaceId,
    point: DVec3,
) -> Option<u32> {
    let mut i = engine.face_node(face)?;
    let Some(root) = engine.nodes()[i as usize].patch() else {
        return Some(i);
    };
    let q = param_coords(&root.polygon, point);
    while !engine.is_leaf(i) {
        let mut best = (f64::NEG_INFINITY, i);
        for c in engine.children(i) {
            let Some(p) = engine.nodes()[c as usize].patch() else {
                continue;
            };
            let (corners, n) = param_corners(p);
            let d = insideness(&corners[..n], q);
            if d > best.0 {
                best = (d, c);
            }
        }
        if best.1 == i {
            break;
        }
        i = best.1;
    }
    Some(i)
}

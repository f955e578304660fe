//! # radlab-scene
//!
//! The ground every radlab method stands on: scenes (geometry in f64, diffuse reflectance and emission per
//! face, an optional camera), their file formats and builtin generators, the shared visibility engine
//! ([`Accel`], an obvhs BVH), form factors, sampling, evaluation points, element meshes, the [`Solver`] and
//! [`Solution`] traits, and primary-ray rendering of any solution.
//!
//! Units: radiosity B and emission E are radiant exitance in W/m²; radiance L = B/π; RGB channels are
//! independent. Reflectance lies in [0, 1). Nothing in this crate prints or writes files.

pub mod accel;
pub mod builtin;
pub mod camera;
mod cwbvh_convert;
pub mod edge_adjacency;
pub mod elements;
pub mod error;
pub mod error_metric;
pub mod eval_points;
pub mod final_gather;
pub mod form_factor;
pub mod gouraud;
pub mod io;
pub mod locate;
pub mod open_fraction;
pub mod params;
pub mod polygon;
pub mod reconstruction;
pub mod sampling;
pub mod scene;
pub mod solver;
pub mod test_scenes;
pub mod vertex_adjacency;
mod wide_node_test;

pub use accel::{Accel, AccelPreset, Hit, NodeTestKind, PACKET_SEGMENTS, Ray, Segment};
pub use camera::{Camera, CameraFrame, Image, render_solution};
pub use edge_adjacency::{EdgeAdjacency, MeshEdge};
pub use elements::{Element, ElementMesh, default_element_size};
pub use error::{SceneError, SolveError};
pub use eval_points::{EvalPoint, evaluation_points};
pub use io::load_scene;
pub use locate::{ElementLocator, ElementTree};
pub use params::MethodParams;
pub use polygon::{AreaSampler, FACING_TOL_REL, Polygon, facing_away};
pub use reconstruction::{Reconstruction, Reconstructor};
pub use scene::{Face, FaceId, Material, Scene, SceneBuilder, SceneWarnings};
pub use solver::{PerFaceSolution, Solution, Solver, Stats, Step};
pub use vertex_adjacency::VertexAdjacency;

/// Linear RGB triple (f64 per channel): radiosity, emission, reflectance.
pub type Rgb = glam::DVec3;

pub use builtin::builtin;
pub use glam;

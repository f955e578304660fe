//! # radlab-scene
//!
//! The scene every radlab method stands on: geometry in f64 (faces as planar convex polygons, their areas,
//! normals and adjacency), diffuse reflectance and emission per face, an optional camera, the builtin
//! generators, and the seeded random streams every method draws from. The file formats are
//! `radlab-formats`, the visibility engine `radlab-visibility`, form factors `radlab-kernels`, the method
//! interface `radlab-method` and answering at points `radlab-answer`.
//!
//! Units: radiosity B and emission E are radiant exitance in W/m²; radiance L = B/π; RGB channels are
//! independent. Reflectance lies in [0, 1). Nothing in this crate prints or writes files.

pub mod builtin;
pub mod camera;
pub mod edge_adjacency;
pub mod error;
pub mod polygon;
pub mod ray;
pub mod sampling;
pub mod scene;
pub mod vertex_adjacency;

pub use camera::{Camera, CameraFrame};
pub use edge_adjacency::{EdgeAdjacency, MeshEdge};
pub use error::SceneError;
pub use polygon::{AreaSampler, FACING_TOL_REL, Polygon, facing_away};
pub use ray::Ray;
pub use scene::{Face, FaceId, Material, Scene, SceneBuilder, SceneWarnings};
pub use vertex_adjacency::VertexAdjacency;

/// Linear RGB triple (f64 per channel): radiosity, emission, reflectance.
pub type Rgb = glam::DVec3;

pub use builtin::builtin;
pub use glam;

//! # radlab-face-cluster
//!
//! Face-cluster hierarchies over polygonal meshes, the preprocess of face cluster radiosity (Willmott,
//! Heckbert & Garland, "Face Cluster Radiosity", EGWR 1999; Garland, Willmott & Heckbert, "Hierarchical Face
//! Clustering on Polygonal Surfaces", I3D 2001). Per dual-connected part of the scene's meshes, a binary tree
//! from greedy contraction of the dual graph, cheapest merge first ([`contraction`]); per node everything a
//! vector-radiosity solver needs without reading input faces ([`tree`]): area, vector area, normal cone,
//! oriented box and sphere, M = Σ ρ_i A_i n_i n_iᵀ and p_E = Σ E_i A_i n_i per channel, sample points for
//! visibility; faces permuted so every node's faces are a contiguous range.
//!
//! The build is O(k log k) for k faces and worth caching: [`FaceClusterTree::to_bytes`] and
//! [`FaceClusterTree::from_bytes`] make and read a bit-identical copy keyed by [`digest`] of the mesh and
//! parameters; the caller picks the file and times the build (this crate prints nothing, reads no clock and
//! writes no file).
//!
//! Parameters ([`FaceClusterParams`], kebab-case in experiment files):
//!
//! | parameter | default | meaning |
//! |---|---|---|
//! | `planarity-weight` | 1 | weight of E_fit (mean squared distance to the fitted plane over the mesh's mean face area) |
//! | `orientation-weight` | 1 | weight of E_dir (area-weighted (1 − n̄·n_f)²) |
//! | `shape-weight` | 1 | weight of E_shape (1 − max(γ₁, γ₂)/γ, γ = perimeter²/area) |
//! | `balance-weight` | 1 | weight of E_bal = \|A₁ − A₂\|/(A₁ + A₂) (radlab's addition: keeps the tree O(log k) deep) |
//! | `samples-per-node` | 4 | visibility sample points per node |
//! | `seed` | 1 | seed of the sample points |
//!
//! Where it does badly: a mesh without shared vertices (a triangle soup) has no dual edges, so every face
//! stays its own root; fix the input (the OBJ reader welds equal positions). Closed or strongly curved
//! nodes have a vector area near zero: their normal cones say so, and a solver must refine them.

pub mod bounds;
pub mod cache;
pub mod contraction;
mod error;
pub mod face_node;
pub mod moments;
mod params;
mod solver;
pub mod tree;
pub mod vector_transport;

pub use bounds::{NormalCone, OrientedBox, Sphere};
pub use cache::{Digest, digest, digest_hex};
pub use contraction::{ContractionStats, MergeCost};
pub use error::FaceClusterError;
pub use face_node::{ClusterRef, FaceContext, FaceNode};
pub use moments::{Moments, SymMat3};
pub use params::FaceClusterParams;
pub use solver::{DEFAULT_EPSILON, FaceClusterSolveParams, FaceClusterSolver};
pub use tree::{FaceClusterTree, Node};
pub use vector_transport::VectorTransport;

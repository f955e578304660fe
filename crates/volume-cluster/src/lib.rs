//! # radlab-volume-cluster
//!
//! Volume-clustered hierarchical radiosity (Smits, Arvo & Greenberg 1994; Sillion 1995; Christensen,
//! Lischinski, Stollnitz & Salesin 1997): a single-rooted hierarchy of volume clusters above the input faces
//! (a loose octree, [`loose_octree`]) lets light move between groups of faces as wholes, so the solve starts
//! from one root self-link instead of the k² initial links of plain hierarchical radiosity. Refinement splits
//! links until an oracle's bound on the power they carry falls below ε; below the faces the quadtree patches of
//! radlab-hierarchical take over, with the same kernels, gather and output. The whole method is a node kind
//! ([`ClusterNode`]) and a transport ([`ClusterTransport`]) on radlab-hierarchical's generic engine: refinement,
//! gather/push-pull, schedules and output are the engine's, not copies.
//!
//! ## Parameters ([`VolumeClusterParams`])
//!
//! | name | default | meaning |
//! |---|---|---|
//! | `transfer` | `alpha` | `isotropic` (A/4 clusters), `alpha` (per-face cosines), `directional` (spherical harmonics) |
//! | every parameter of `hierarchical` but `lazy_linking` | as there | ε, oracle, schedule, α, stages, minimum element, visibility rays per link (also for cluster links), quadrature, tolerance, gather (patch links), interpolation, memory budget |
//!
//! ## Transfers, side by side
//! - `isotropic`: a cluster is a sphere of projected area A/4; O(1) per link. Biased: a flat cluster facing a
//!   light receives a quarter of the truth, and a cluster's faces all get its mean irradiance.
//! - `alpha`: a cluster source sums Σ A_i max(0, n_i·d) B_i over its faces at every pass; a cluster receiver
//!   hands each face its own cosine share. O(faces) per link, every face below a cluster link touched each pass.
//! - `directional`: clusters keep order-2 spherical harmonics of what they send and receive; O(1) per link,
//!   faces reached through push. Chosen over irradiance vectors because a volume cluster is typically closed
//!   (Σ A_i n_i ≈ 0: a vector source would emit nothing) and over direction bins because both sides are
//!   clamped cosines, which order 2 represents within a few percent.
//!
//! ## Cost
//! Hierarchy O(k log k) (built by the constructor, reported apart from the steps). Links: one root
//! self-link, refined to a number that depends on ε and the lighting rather than on k². Visibility: `visibility`
//! rays per link between points on the two ends' faces.
//!
//! ## When it does badly
//! - Blocky, axis-aligned artefacts where links stop above the faces: every face of a receiving cluster gets
//!   one visibility fraction (and, for `isotropic`, one irradiance).
//! - Near ρ = 1: a cluster link's point approximation is not an exact partition of what a face sees (patch
//!   links are: their per-leaf gather sums to one), so its error is multiplied by about 1/(1 − ρ). Measured on
//!   `concentric-spheres?faces=600` at the defaults (area-mean error of B against E/(1 − ρ)): α −0.6%, −5.4%,
//!   −38%, −86% at ρ = 0.5, 0.9, 0.99, 0.999; directional −0.4%, −4.9%, −36%; isotropic −5.2%, −25%, −77%.
//!   Plain hierarchical radiosity on the same scene is −3.6% at ρ = 0.9 (its visibility fractions), so part of
//!   the defect is visibility, not clustering.
//! - `isotropic` loses energy wherever clusters are flat-ish (a cap of a sphere seen face-on is a quarter of
//!   its true projected area at each end).
//! - Occlusion inside a cluster is averaged into one number per link (Sillion & Drettakis 1995) for
//!   every transfer (`alpha` gives each receiving face its own cosine and distance, not its own visibility).
//!   A mean visibility times a mean source flux could carry light through walls into sealed interiors inside a
//!   receiving cluster; faces sealed off from every emitter are found once by 16 rays per face
//!   ([`enclosure`]) and receive nothing.

mod cluster_link;
mod cluster_node;
mod cluster_transport;
pub mod enclosure;
pub mod loose_octree;
mod params;
mod solver;
pub mod spherical_harmonics;
mod transfer_alpha;
mod transfer_directional;
mod transfer_isotropic;

pub use cluster_link::{box_distance, cluster_link};
pub use cluster_node::{ClusterNode, ClusterRef};
pub use cluster_transport::{ClusterTransport, TransferMode};
pub use loose_octree::{Cluster, ClusterTree, OctreeItem};
pub use params::{Transfer, VolumeClusterParams};
pub use solver::{ClusterSolver, VolumeClusterSolver};
pub use transfer_alpha::Alpha;
pub use transfer_directional::{Directional, DirectionalCoefficient, DirectionalIrradiance};
pub use transfer_isotropic::Isotropic;

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
//! ## The solve (method `face-cluster`, [`FaceClusterSolver`])
//! Vector radiosity (Willmott et al. 1999, section 4) on radlab-hierarchical's generic engine: nodes are
//! tree nodes ([`FaceNode::Cluster`]) and, below a tree leaf, quadtree patches of its face
//! ([`FaceNode::Patch`]); light moves by [`VectorTransport`] (irradiance vectors e and power vectors
//! p = Σ B_i A_i n_i per channel, p = p_E + M e at cluster leaves, the exact patch kernel between two patches,
//! and a near single-face source's exact polygon irradiance vector at a flat receiver).
//! Above the tree's roots, a loose octree of volumes (Christensen et al. 1997) over the roots' boxes; the solve
//! starts from the top volume's self-link, refined like a volume cluster's (Sillion 1995), so a scene of many
//! separate parts does not start from (roots)² links. A volume is a closed group of surfaces (Σ A_i n_i ≈ 0),
//! so its links use Sillion's isotropic transfer (projected area A/4 toward every direction, radiosity from
//! the engine's pulled area mean) rather than power vectors; the α alternative (Σ over the roots of
//! max(0, p_root·d)) would cost a pass over the roots below a volume per link and pass, and the oracle splits
//! volume links until their bound is below ε anyway. Parameters: those of
//! `hierarchical` (`lazy_linking` excepted) with `error_norm = power` and `epsilon = 7e-5` by default, and
//! volume clusters' `row_normalisation` (`off` by default; `closed-scenes` rescales each leaf's row to one in
//! a scene the enclosure rays find closed: the concentric spheres and a 192-face furnace sphere then hold
//! ρ = 0.999 within 1e-6, 10⁴-face concentric spheres within 0.8%).
//! Refinement, gather and push-pull never read an input face unless a link is refined below a tree leaf
//! ([`FaceClusterSolver::face_reads`] counts the faces read); radiosity at a point comes from the deepest node
//! holding its face. A leaf patch that straddles a contact (a floor patch partly under a block standing on
//! it) holds its radiosity over its open part: the patch kernel estimates its open share (radlab-kernels'
//! `open_fraction`, area-sampled visibility only) and the engine does the rest (radlab-hierarchical's
//! `open_share` module), so it no longer sends into the block's underside light its open part reflects (Baum,
//! Mann, Smith & Winget 1991's leak). Without it the Cornell box's points were 1.03% low against the path
//! tracer, 0.33% with it (docs/journal/methods.md, "Clusters across a contact").
//!
//! Besides those, `irradiance_field` (`linear` by default: each link also brings its kernel's Jacobian over a
//! cluster receiver, [`irradiance_gradient`], so a cluster's faces take the irradiance at their own
//! centroids; `constant` for one value per cluster) and `self_exchange` ([`self_exchange`]). Point answers
//! are by default one more gather over the tree (`reconstruction = "final-gather"`, [`cluster_gather`]: far
//! nodes by their power vectors, `gather_opening` 0.25 by default, near faces and emitters by exact
//! point-to-polygon factors, the near faces seen with a factor of at least 0.01 with their values gathered
//! once more at their centroids, `near_values = "regathered"` by default), the most accurate of the three at a
//! cost per point that grows as log k; at
//! `gather_opening = 0`, `near_field = "sub-polygons"` gathers through the shared final gather with its near
//! field, its far light from the tree gather. `reconstruction = "gouraud"` interpolates the faces' irradiance
//! rather than their radiosity so each face keeps its own orientation ([`FaceClusterSolver`]): no gather, but
//! light carried across shadow edges.
//!
//! Measured with Gouraud answers, the linear field and the traced exchange pushed down by where it lands (the
//! defaults then, 32 trace rays a face; release, `radlab run` with 1,024 points against 4,096-path references, idle machine,
//! 2026-12-01): direct light on a flat 10⁴-face floor at ε = 1e-4 / 1e-5 / 1e-6, 1.9 / 0.7 / 0.6% (one
//! irradiance per cluster: 11.0 / 4.0 / 1.8%; noise floor 0.53%); terrain 10⁴ faces 1.76 / 1.61 / 1.51%
//! (before these changes, constant answers: 4.4 / 3.1 / 2.4%; with 4 trace rays a face and one landing ratio
//! for all traced light, 1.84 / 1.84 / 1.98%), 10⁵ faces 2.60 / 2.21 / 1.95% (5.0 / 3.6 / 2.9%; 2.73 / 2.46 /
//! 2.39%); bumpy sphere 10⁴ faces 2.57 / 1.71 / 1.30% (3.5 / 2.4 / 1.7%; noise floor 1.21%).
//! The terrain's remaining error is in the light it sends onto itself: its direct light alone (ρ = 0.01)
//! is within 0.7% at 10⁵ faces (ε = 1e-8), and at ρ = 0.5 the error is spread over every part of the ground,
//! the light's footprint 0.2% too dark and the far ground 0.4% too bright (net, relative to the whole).
//! Since light a sibling sent keeps a channel of its own below its first level (handed down by where light
//! from beyond each node landed) and the answers hand traced light down to every face (same setup, one run,
//! 2026-12-01): terrain 10⁴ faces 1.50 / 1.40 / 1.33%, 10⁵ faces 2.08 / 1.72 / 1.60%, the bumpy sphere
//! unchanged. What is left is mostly the trace's noise and its even source: 1.13% at 10⁴ faces and ε = 1e-6
//! with 1,024 rays a face; refining every self-exchange to the faces' kernels instead (no traced links)
//! reaches 0.84% after 34 s, and volume clusters (directional) 0.80% after 32 s.
//! Landing ratios shrunk by their noise (concentric spheres 10⁴ / 10⁵: 0.59 / 1.11%; before the per-face
//! hand-down 0.73 / 1.09%, with it unshrunk 0.76 / 1.25%).
//! 10⁶ faces end to end with a cold cache, this build beside the previous session's alternately on the same
//! (slower) day: terrain 41.2 / 39.3 s against 39.7 / 38.9 s, 2.49 GiB peak; bumpy sphere 35.3 s, 2.47 GiB (before the shrinkage);
//! relative L1 at 10⁶ faces 3.42% (bumpy) and 2.54% (terrain) against 1,024-path references.
//! 10⁶ faces end to end with a cold cache (`/usr/bin/time -v radlab solve "builtin:bumpy-sphere?faces=1000000"
//! --method face-cluster --set cache_dir=EMPTY`): bumpy sphere 29.3 s wall, 2.47 GiB peak RSS, solve 1.32 s,
//! 2.65% relative L1 (1.77% at ε = 1e-5); terrain 31.6 s, 2.50 GiB, solve 0.29 s, 3.00% (2.63% at ε = 1e-5);
//! the trace's 32 rays a face are 32M of the rays and 7–9 s of the wall time (22.1 and 23.1 s with 4).
//! Solve time against k = 10³ … 10⁶ (`experiments/scaling-clusters.toml`'s scenes, face clusters alone,
//! 1,024-path references, evaluation between steps): bumpy sphere 0.63, 0.89, 1.22, 1.73 s (slope 0.14),
//! terrain 0.07, 0.11, 0.58, 0.46 s (0.32, above the 0.3 target; with `radlab solve` alone, no evaluation
//! between steps, 0.065, 0.105, 0.49, 0.28 s, slope 0.26), concentric spheres 0.65, 1.11, 2.31, 2.47 s
//! (0.20); memory slopes 0.55, 0.75, 0.55. Again with the traced light's own channel, its hand-down to the
//! faces and the shrunk ratios (2026-12-01): bumpy sphere 0.62, 0.88, 1.19, 1.82 s (0.15), terrain 0.069,
//! 0.10, 0.61, 0.51 s (0.34; 0.32 in a run before the shrinkage, the small sizes' times moving by 20%),
//! concentric spheres 0.67, 1.16, 2.12, 2.48 s (0.20); relative L1 3.4% (bumpy, all sizes), 1.6, 1.7, 2.3,
//! 2.5% (terrain), 1.2, 0.59, 1.1, 0.95% (concentric spheres). The terrain's links go 15k, 17k, 58k, 25k: its fractal has 8 octaves, the finest 256 cells
//! across, which 10⁴ faces (100 across) do not resolve and 10⁵ (316) do, so the scene itself gains detail up
//! to 10⁵ faces; with `octaves=4` (resolved at every k) the slope is 0.28 (0.086, 0.092, 0.29, 0.51 s; links
//! 15k, 16k, 30k, 31k; why they double from 10⁴ to 10⁵ there is not established: neither the traced
//! exchange's 32-face threshold (256 gives the same 30,013 links at 10⁵) nor `min_element_size` (0.14, 0.3:
//! unchanged) moves them). Both were found later the same day: the terrain's finest octave was finer than its
//! grid (aliased; octaves now stop at the grid, 4 / 6 / 7 / 8 at 10³ … 10⁶), and the links doubled because
//! stranded pairs and quads were taken into the last regions one at a time, a tree level each, which
//! refinement walked down (104 levels at 10⁵ faces; merged when stranded, 34). With both: solve 0.069, 0.066,
//! 0.14, 0.22 s (slope 0.18; links 15.8k, 15.2k, 19.1k, 16.1k), the 4-octave terrain 0.19, bumpy sphere 0.14,
//! concentric spheres 0.19 (`experiments/scaling-face-cluster.toml`).
//!
//! Measured before the volume hierarchy above the roots and the near-source vectors existed (release, 2 threads
//! on a 2-core machine shared with other builds, so ratios only; 2026-11-30),
//! solve wall time and links against k at the defaults: concentric spheres 1e3 → 1e4 → 1e5 faces:
//! 0.94 → 2.30 → 5.67 s (slope 0.39 per decade), 156k → 285k → 384k links (slopes 0.26, 0.13); bumpy
//! sphere: 0.43 → 0.65 → 0.89 s (slopes 0.18, 0.14), 48k → 59k → 59k links.
//!
//! Measured with the volume hierarchy and the per-leaf near links (release, `radlab solve
//! "builtin:bumpy-sphere?faces=K" --method face-cluster` with a cold cache directory, then again warm, on the
//! 2-core machine loaded by other builds: load average about 10, so CPU times are the steadier figures;
//! 2026-11-30): solve (steps) wall time at K = 10³, 10⁴, 10⁵, 10⁶: 1.11, 1.92, 2.84, 5.74 s (CPU 0.70, 1.29,
//! 1.85, 2.83 s; fitted log-log slope 0.23 wall, 0.20 CPU), 49k, 61k, 61k, 52k links; terrain 0.19, 0.29,
//! 1.72, 0.67 s (slope 0.25; its 10⁶ mesh converges with fewer elements than its 10⁵ one). At 10⁶ faces,
//! end to end with a cold cache: 38–69 s wall over repeated runs (bumpy sphere and terrain alike), 24–38 s of
//! CPU, peak RSS 2.5 GiB; warm, 17–26 s wall; the hierarchy build alone 17.5–18.8 s of CPU.
//!
//! Measured again after the clamped-cosine line and the visibility change below (release, 2-core machine
//! loaded by another build, load average 2.3–2.6; 2026-11-30): solve wall time at K = 10³ … 10⁶ 1.00, 1.39,
//! 1.80, 1.69 s (CPU 0.97, 1.39, 1.79, 2.35 s; fitted slope 0.08 wall, 0.13 CPU), 50k, 62k, 62k, 53k links. At
//! 10⁶ faces end to end with a cold cache (`/usr/bin/time radlab solve "builtin:bumpy-sphere?faces=1000000"
//! --method face-cluster --set cache_dir=EMPTY`): 23.8 s wall, 2.47 GiB peak RSS; against a 4,096-path
//! reference at 1,024 points (noise floor 1.2%) 3.60% relative L1 with constant answers and 2.82% with
//! Gouraud's (3.87% and 3.36% before).
//!
//! Measured again with the traced self-exchange as the default (release, idle machine, 2026-11-30; `radlab
//! run` on `experiments/scaling-clusters.toml`'s scenes with face clusters alone, 1,024 points, 1,024-path
//! references): solve wall time at K = 10³ … 10⁶, bumpy sphere 0.55, 0.75, 0.96, 1.19 s (fitted slope 0.11),
//! terrain 0.06, 0.09, 0.41, 0.21 s (0.24), concentric spheres 0.57, 1.02, 1.75, 1.97 s (0.18); peak memory
//! slopes 0.65, 0.78, 0.63 (2.4 GiB at 10⁶: the hierarchy and the scene, O(k)); links 50k–62k, 15k–58k,
//! 89k–154k; setup (hierarchy from the cache, the trace) 2.8–5.5 s at 10⁶; relative L1 4.0–4.1%, 4.2–5.2%,
//! 0.65–1.1% (noise floors 2.4%, 0.8–0.9%, 0). 10⁶ faces end to end with a cold cache: bumpy sphere 18.9 s
//! wall, 2.47 GiB peak RSS, the solve 1.17 s (52.8k links), 5.49M rays, 4.06M of them the trace (which adds
//! 0.7–0.8 s wall, 2.4 s CPU to the setup against `cap`, warm cache), 3.60% relative L1 constant and 2.82%
//! Gouraud against a 4,096-path reference, as before (the bumpy sphere's nodes exchange nothing within);
//! terrain 20.2 s, 2.50 GiB, the solve 0.21 s, 5.2% at the default ε and 3.9% at ε = 1e-5 (`cap`: 7.1%,
//! 6.2%).
//!
//! Where the solve does well and badly (measured on concentric spheres, a furnace with B = E/(1 − ρ), through
//! the operator's row sums: [`radlab_hierarchical::Engine::row_sums`], the irradiance each leaf gathers when
//! every leaf sends B = 1, one in a closed scene):
//! - At 600 faces, ρ = 0.5 and the defaults, the furnace's area mean is 0.16% low (0.14% with the traced
//!   self-exchange; the test
//!   `concentric_spheres_furnace_mean_within_one_percent`); the rows sum to 0.990 on the inner sphere and 1.000
//!   on the outer, so ρ = 0.9 is 1.9% low and ρ = 0.99 19% low. Two causes were found and removed. (1) A pair
//!   whose sampled visibility segments were all blocked was dropped, so a partly hidden source was lost whole
//!   (with one ray per link the mean was 3.2% low at ε = 1e-3 and 5.7% at 1e-4): such a pair is now split
//!   while it could carry more than ε. (2) Links that a curved end's normal cone straddles gave their
//!   irradiance (or power) vectors alone, counting faces that see them from behind negatively: they now carry
//!   the clamped-cosine line of [`clamped_irradiance`] (inner rows 0.980 → 0.990; on 10⁴-face spheres against
//!   the exact answer, relative L1 1.06% → 0.62%; on the bumpy sphere at 10⁴ and 10⁵ faces, against a
//!   path-traced reference with a 1.7% noise floor, 4.2% → 3.8% with constant answers and 3.6% → 3.0% with
//!   Gouraud's; links within 1%). What is left on the inner sphere, measured before (2) at ε = 1e-3 with one
//!   ray: links between clusters whose bounding spheres overlap though their surfaces are apart (a small
//!   inner cluster and a large outer one) transfer nothing, 1.2% of a row, and the point form between near,
//!   extended ends (1/r² at the centroids against its mean over the faces). On a 432-face furnace sphere the
//!   rows sum to 1.002–1.006 (the curvature excess), which diverges at ρ = 0.999 (so does the 192-face one at
//!   the default ε; the engine reports a solution that keeps growing as an error rather than stopping at its
//!   step cap; at ε = 1e-5 the 192-face sphere converges 4.6% high, at 1e-6 within 1e-9); the 48-face sphere
//!   of the conformance suite is refined to its faces and its rows sum to one.
//! - Terrain, with `self_exchange = "cap"` (2,048-path references): relative L1 stays at 6.7–7.2% on the
//!   10⁵-face terrain whatever ε (1e-4 … 1e-5), and at 4.2–5.3%
//!   on the 10⁴-face one even at the radiosity norm with ε = 1e-3 (3.5M links); volume clusters (α) reach
//!   1.2% on the 10⁵-face terrain and hierarchical radiosity 0.9% on the 10⁴-face one. The answers are 3–4%
//!   low at every brightness. Against
//!   hierarchical radiosity on 2,000 faces the ground's total power is 3.1% low at ρ = 0.5 (3.3% with 1.7M
//!   links) but 1.1% high at ρ = 0.01, so the loss is in the light the terrain sends onto itself. A curved
//!   node whose two children do not face each other (neither centroid in front of the other's plane: a ridge,
//!   or a rough, nearly flat patch of ground) gets no self-link, so its children never exchange light, though
//!   a heightfield's do. Refining such self-links instead (while their cap share could carry more than ε)
//!   brought the 2,000-face total to +0.3%, but cost 15–45× (10⁵ faces: 0.45 s → 19.9 s, 57k → 636k links):
//!   the pairs of touching children that refinement makes carry nothing while kept (their bound
//!   min(1, A_S/A_R) splits them along every shared boundary), and the concave nodes it reaches take the same
//!   path. The default `self_exchange = "traced"` ([`self_exchange`]) traces every node's F_NN before the
//!   solve; one-sided nodes (|Σ A_i n_i| ≥ A/2) of at least 32 faces carry it in their self-links, and their
//!   children the traced exchange between them, kept whole; smaller nodes, and the children of concave ones
//!   that follow the cap's rule, reach the faces' exact kernels where ε asks. `radlab run` on the terrain,
//!   1,024 points, 4,096-path reference, constant answers, ε = 1e-4 / 1e-5 / 1e-6, relative L1 `cap` →
//!   `traced`: 10⁴ faces 5.3 / 4.6 / 4.3% → 4.4 / 3.1 / 2.4%, 10⁵ faces 6.3 / 5.6 / 5.3% → 5.0 / 3.6 / 2.9%;
//!   median point −3.2 … −4.4% → +0.06 … +1.2%; at 10⁵ faces 57.3k → 58.0k links and 0.40 → 0.41 s at
//!   ε = 1e-4 (1.07 → 1.42 s at 1e-5, 3.9 → 5.9 s at 1e-6), the trace 0.4M rays (setup 0.17 → 0.29 s). The
//!   bumpy sphere answers bit for bit alike in both modes at 10⁴ and 10⁵ faces (3.75%, 3.77%), and so does
//!   the room of 4³ cubes; the 10⁴-face concentric spheres (ρ = 0.5) 0.62% → 0.65% in 1.96 → 0.97 s (285k →
//!   123k links). What the even spread costs: inside a 192-face furnace sphere (ρ = 0.5) faces lie
//!   1.981–2.036 against 2 (cap: 2.003–2.006), a facet beside a sibling receiving more of it than one across;
//!   the 48-face one is exact in both modes.
//! - Many closed parts: a room holding 4³ cubes (ρ = 0.5) is 2.5% low at the defaults and 1.1% low at
//!   ε = 1e-5 (`room_of_cubes_furnace`). Before (2) it was 16% low: links to a whole cube are kept below ε
//!   although its cone straddles every direction, and the vectors from opposite sides cancelled. Refusing
//!   such links whatever they carry, the other way out, refined the 10⁵-face bumpy sphere to its faces (61k →
//!   11.6M links, 0.89 s → 178 s of solve).
//! - A closed room around a curved mesh: the line of (2) was fitted over the whole range of cosines the
//!   cone allows, as if they were spread evenly; on the 10⁵-face bumpy sphere at ε = 1e-5 the sphere's rows
//!   summed to 1.0141 (its light from the walls 0.9969 against a traced form factor of 0.9830) and every
//!   answer in the room was high (+0.44%). Fitted over the spread of the faces' own cosines (their mean and
//!   variance, from Σ A_i n_i and Σ A_i n_i n_iᵀ, [`clamped_irradiance::CosineFit::of_node`]), with visibility
//!   sampled from the faces turned toward the link, the rows sum to 0.9982 on the sphere and 1.0004 on the
//!   walls (`a_closed_rooms_rows_sum_to_one_over_a_curved_mesh` at 10⁴ faces; the split by source is
//!   `examples/row_sums_by_source.rs`).
//! - The conformance suite's sliver in a furnace is 7.4% off: the sliver is a root of its own (1e-4 of the
//!   scene's area) that keeps links from volume clusters of flat wall quads, whose isotropic transfer
//!   (A/4) misjudges open groups of flat faces; its row sums to 0.918.
//!
//! Where the hierarchy does badly: a mesh without shared vertices (a triangle soup) has no dual edges, so every face
//! stays its own root; fix the input (the OBJ reader welds equal positions). Closed or strongly curved
//! nodes have a vector area near zero: their normal cones say so, and a solver must refine them.

pub mod bounds;
pub mod cache;
pub mod clamped_irradiance;
pub mod cluster_gather;
pub mod contraction;
mod error;
pub mod face_node;
pub mod irradiance_gradient;
pub mod moments;
mod params;
pub mod self_exchange;
mod solver;
pub mod tree;
pub mod vector_transport;

pub use bounds::{NormalCone, OrientedBox, Sphere};
pub use cache::{Digest, digest, digest_hex};
pub use cluster_gather::{
    ClusterGather, DEFAULT_OPENING, DEFAULT_VALUES_OPENING, GatherValues, NearField,
};
pub use contraction::{ContractionStats, MergeCost};
pub use error::FaceClusterError;
pub use face_node::{ClusterRef, FaceContext, FaceNode};
pub use irradiance_gradient::IrradianceField;
pub use moments::{Moments, SymMat3};
pub use params::FaceClusterParams;
pub use self_exchange::{Landing, SELF_RAYS, SelfExchange, SelfExchangeMode};
pub use solver::{DEFAULT_CACHE_DIR, DEFAULT_EPSILON, FaceClusterSolveParams, FaceClusterSolver};
pub use tree::{FaceClusterTree, Node};
pub use vector_transport::VectorTransport;

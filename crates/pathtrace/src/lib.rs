//! # radlab-pathtrace: Monte Carlo methods
//!
//! Three methods built on one path estimator, all on radlab-visibility's shared engine ([`Accel`]),
//! sampling streams and conventions (radiosity B and emission E in W/m²; radiance L = B/π; one-sided faces
//! that emit and reflect from their front; reflectance ρ < 1).
//!
//! ## 1. Per-point radiosity estimator — the reference ([`estimate_points`])
//!
//! At a surface point x: B(x) = E(x) + ρ(x) H(x), with the irradiance H estimated by paths: at each vertex,
//! next-event estimation toward the emitters (area sampling, emitters chosen by power) combined with
//! cosine-weighted hemisphere sampling by multiple importance sampling (Veach 1997, power heuristic), then the
//! walk continues along the hemisphere ray, ended by Russian roulette (unbiased for any ρ < 1, including
//! ρ → 0.999). Returns the mean and the standard error per point and channel. Unbiased, mesh-free.
//!
//! | parameter | default | meaning |
//! |---|---|---|
//! | `samples` | 1024 | paths per point; standard error ∝ 1/√samples |
//! | `max_depth` | 100000 | cap on path segments (a safety net; bias ≤ ρ_max^max_depth) |
//! | `direct` | `mis` | `mis`, `next-event` (emitter sampling only) or `hemisphere` (no shadow rays) |
//!
//! **Cost**: about 2/(1 − ρ̄) rays per path (a shadow ray and a continuation ray per vertex), so at ρ = 0.999 a
//! path costs ~2000 rays; time ∝ points × samples × that × log(faces). **Does badly**: in scenes lit mostly
//! indirectly (light through a gap, an emitter facing a wall) the next-event rays rarely see the emitter and
//! the noise is that of plain path tracing; near-white enclosures make paths long; the standard error of a
//! heavy-tailed estimate (small bright emitters seen by a few paths) is itself uncertain at low sample counts.
//!
//! ### Path tracing as a method ([`PathTraceSolver`])
//!
//! The same estimator stepped at a given set of query points (the experiment's evaluation points, or `probe`'s):
//! each step adds paths to every point, `initial_samples` (default 16) then doubling up to `samples` (default
//! 1024), so its error against time can be traced beside the finite-element methods'. Its cost is per point:
//! time and rays grow linearly with the number of points answered. Its streams are keyed by its own seed mixed
//! with [`METHOD_STREAM_TAG`], never the reference's.
//!
//! ## 2. Camera path tracing ([`render`])
//!
//! The same estimator through the pixels of a pinhole [`Camera`]: radiance B/π of the surface each jittered
//! primary ray hits, with a per-pixel standard error image. Parameters: `samples_per_pixel` (default 64),
//! `max_depth`, `direct` as above. Cost: pixels × samples_per_pixel paths; noise is visible as grain until a few
//! hundred paths per pixel in diffuse scenes.
//!
//! ## 3. Mesh-based Monte Carlo radiosity ([`McRadiositySolver`])
//!
//! A view-independent solution over a fixed element mesh (the same `element_size` meshing as matrix
//! radiosity): particles shot from the emitters are tallied on the elements they land on
//! (Shirley 1991, Neumann et al. 1995, Bekaert 1999). Each `step()` shoots a batch; the solution is the mean over
//! all particles so far, unbiased for the given mesh, error ∝ 1/√particles; `stats().residual` is the
//! estimated relative standard error.
//!
//! | parameter | default | meaning |
//! |---|---|---|
//! | `element_size` | diagonal/25 | element edge length (scene units) |
//! | `particles_per_step` | 100000 | particles shot from the emitters per step |
//! | `max_steps` | 100 | steps before `Converged` |
//! | `method` | `random-walk` | `random-walk` (collision-shooting walks) or `stochastic-jacobi` |
//! | `max_depth` | 100000 | cap on bounces (walks) or generations (Jacobi) |
//! | `reconstruction` | `final-gather` | point answers: `constant`, `gouraud` or `final-gather` (radlab_answer::reconstruction) |
//! | `gather_opening` | 0.25 | final-gather only: far groups of elements through one drawn element each (radlab_answer::AnswerParams, DEFAULT_GATHER_OPENING); 0 gathers every element |
//! | `near_values` | solution | final-gather only: regathered reads each element taken one by one with a factor of at least 0.01 from the point (and seen from it) at its value gathered once more at its centroid (radlab_answer::NearValues) |
//!
//! **Cost**: O(particles × 1/(1 − ρ̄)) rays, independent of the number of element pairs (no form factors);
//! memory O(elements). **Does badly**: small or dimly lit elements receive few particles and stay noisy
//! (relative error ∝ 1/√(particles landing there)); the mesh's discretisation error stays as with any
//! constant-element method; per-element noise shows as a dappled look.
//!
//! ## Common ground
//!
//! - **Determinism**: every random stream is derived from (seed, work item) — point and chunk of
//!   [`SAMPLES_PER_CHUNK`] paths, pixel, particle, or (step, generation) — and partial results are combined in
//!   a fixed order, so the output is bit-identical for any number of rayon threads.
//! - **Progress**: [`estimate_points_with_progress`] calls `progress(points_done, points_total)` and
//!   [`render`] calls `progress(pixels_done, pixels_total)`, from worker threads; the solver advances by
//!   `step()`. Nothing here prints, writes files or reads the clock.
//! - **Rays**: every ray goes through the shared [`Accel`], whose `rays_cast()` counter gives the rays of an
//!   estimate or a render; [`McRadiositySolver`] reports its own in `stats().rays`.
//! - **Query points**: every per-point method (this crate's, the irradiance cache, photon maps, bidirectional
//!   path tracing) holds its points as [`QueryPoints`] (validated, indexed by exact coordinates; streams of
//!   other points from [`coordinate_stream`]), and the stepped samplers share [`SteppedPoints`] (the doubling
//!   schedule, streams, running statistics and counts over [`sample_points`]).
//! - **Particles from the emitters**: [`trace_photons`] (photon_tracing.rs) traces power-carrying particles
//!   with Russian roulette for every light-tracing method (photon maps, density estimation, radiosity
//!   textures): one tracer, one stream numbering, the same result for any thread count.
//! - **One-sided faces**: a face emits and reflects from its front only; light reaching a back is absorbed and
//!   a back is black, as in every radlab method (and as the point-to-polygon form factor assumes).

mod camera_render;
mod discrete_distribution;
mod emitter_sampling;
mod mesh_radiosity;
mod path_estimator;
mod photon_tracing;
mod point_estimator;
mod point_solver;
mod query_points;
mod random_walk;
mod running_stats;
mod stochastic_jacobi;

pub use camera_render::{RenderParams, render};
pub use emitter_sampling::{EmitterSampler, LightSample};
pub use mesh_radiosity::{McMethod, McRadiosityParams, McRadiositySolver};
pub use path_estimator::{DirectSampling, PathEstimator};
pub use photon_tracing::{CHUNK, EMPTY_CHUNKS, Photon, PhotonBatch, trace_photons};
pub use point_estimator::{
    DEFAULT_MAX_DEPTH, PointEstimate, PointParams, PointSampler, SAMPLES_PER_CHUNK, SurfacePoint,
    estimate_points, estimate_points_with_progress, sample_points, surface_points,
};
pub use point_solver::{METHOD_STREAM_TAG, PathTraceParams, PathTraceSolver, SteppedPoints};
pub use query_points::{QueryPoints, coordinate_hash, coordinate_stream};
pub use running_stats::RunningStats;

#[doc(no_inline)]
pub use radlab_scene::Camera;
pub use radlab_visibility::Accel;

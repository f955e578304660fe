//! # radlab-density-estimation: density estimation
//!
//! Shirley, Wade, Hubbard, Zareski, Walter & Greenberg 1995 ("Global illumination via density estimation",
//! Eurographics Rendering Workshop) and Walter, Hubbard, Shirley & Greenberg 1997 ("Global illumination using
//! local linear density estimation", ACM TOG 16(3)). Particles leave the emitters and are reflected by Russian
//! roulette (radlab-pathtrace's `trace_photons`, shared with the photon map); every landing is kept on its
//! surface, a group of edge-connected faces of one material within a normal cone (surfaces.rs); the
//! irradiance H on a surface is a kernel density estimate of the landings in the surface's own plane, with the
//! boundary bias removed by local linear estimation (local_linear.rs); B(x) = E(x) + ρ(x) H(x) is answered at
//! the point, over a Gouraud display mesh, by a final gather or as the per-face histogram
//! ([`DensityEstimationSolver`], density_estimation.rs).
//!
//! | parameter | default | meaning |
//! |---|---|---|
//! | `particles` | 100000 | landings stored per step |
//! | `steps` | 4 | steps; the estimate is over all landings so far |
//! | `bandwidth` | 0.5 | c in h_s = c √A_s n_s^(−1/6) (A_s the surface's area, n_s its landings) |
//! | `bandwidth_size` | unset | a fixed h (scene units) for every surface instead |
//! | `boundary` | local-linear | `local-linear`, `renormalized` or `none` (the plain kernel) |
//! | `group_angle` | 30 | largest angle (degrees) between a face's normal and its surface seed's |
//! | `reconstruction` | density | `density` (at the point), `mesh`, `final-gather` or `constant` (histogram) |
//! | `element_size` | diagonal / 20 | display-mesh element edge (mesh and final-gather answers) |
//! | `max_depth` | 100000 | particle reflections cap |
//!
//! **Cost**: particles × about 1/(1 − ρ̄) flights (a ray each) and nothing else while solving (no shadow
//! rays, no gathers); answering a point costs one k-d tree range query and its kernel evaluations (counted),
//! plus, within h of a surface's boundary, the kernel's moments over the clipped faces; a final gather adds
//! its rays. Memory: about 64 bytes per landing (position, power, tree). Counters: landings in
//! `Stats::elements`, and [`DensityEstimationSolver::counts`] (emitted, landings, surfaces, kernel
//! evaluations). **Does badly**: the estimate blurs over h (shadow edges and the light's footprint spread, bias
//! O(h²) ∇²H; the bandwidth rule knows nothing of where H changes), noise falls only as n^(−1/3) in
//! mean squared error; surfaces with few landings (small, dark, or each triangle of a scanned mesh on its own)
//! get wide kernels; and it stores every landing.
//!
//! Nothing here prints, writes files or reads the clock; results are bit-identical for any thread count.

mod density_estimation;
pub mod local_linear;
mod params;
pub mod surfaces;

pub use density_estimation::{DensityCounts, DensityEstimationSolver};
pub use local_linear::{BoundaryCorrection, Domain};
pub use params::{DensityEstimationParams, DensityReconstruction};

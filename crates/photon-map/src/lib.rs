//! # radlab-photon-map: photon maps
//!
//! Jensen 1996 ("Global illumination using photon maps"), Jensen 2001 (*Realistic Image Synthesis Using
//! Photon Mapping*), Christensen 1999 (precomputed irradiance for the final gather) and progressive photon
//! mapping at fixed points (Hachisuka, Ogaki & Jensen 2008). Photons leave the emitters and are reflected by
//! Russian roulette (radlab-pathtrace's `trace_photons`); irradiance is a k-nearest-neighbour density estimate over a kiddo
//! k-d tree with a cone or Epanechnikov filter (density_estimate.rs); [`PhotonMapSolver`] (photon_map.rs)
//! answers at query points by a final gather or progressively. Direct light is next-event estimation at the
//! query points in both modes (radlab-pathtrace's estimator).
//!
//! | parameter | default | meaning |
//! |---|---|---|
//! | `mode` | final-gather | `final-gather` or `progressive` |
//! | `photons` | 200000 | photons stored (final gather) / stored per pass (progressive) |
//! | `nearest` | 50 | k of the density estimate |
//! | `filter` | cone | `cone` (k_c = 1) or `epanechnikov` |
//! | `gather_samples` | 64 | final-gather rays per query point |
//! | `precompute_stride` | 4 | irradiance precomputed at every n-th photon |
//! | `direct_samples` | 64 | direct-light samples per query point |
//! | `passes`, `alpha`, `initial_radius` | 16, 0.7, 0.02 | progressive: passes, α, R₀ / scene diagonal |
//! | `leak_test` | true | one ray per photon (progressive) or irradiance point (gather) used |
//! | `max_depth`, `direct` | 100000, mis | photon reflections cap; direct-light sampling |
//!
//! **Cost**: photons × about 1/(1 − ρ̄) flights (a ray each); final gather: points × (`gather_samples` +
//! leak rays + direct rays); progressive: per pass, the photons plus one leak ray per photon found near a
//! point. Memory: about 100 bytes per stored photon. Counters: stored photons in `Stats::elements`, and
//! [`PhotonMapSolver::counts`]. **Does badly**: the density estimate assumes a flat disk wholly on the surface,
//! so it is biased near edges and corners and on detailed relief (the final gather hides this only one bounce
//! deep: in a furnace it shows); a fixed photon count leaves that bias (final gather is not consistent; the
//! progressive mode is, slowly: error ~ passes^(−1/3)); leak tests cost a ray per photon used.
//!
//! Nothing here prints, writes files or reads the clock; results are bit-identical for any thread count.

mod density_estimate;
mod params;
mod photon_map;

pub use density_estimate::{DensityFilter, PhotonMap};
pub use params::{PhotonMapParams, PhotonMode};
pub use photon_map::{PhotonCounts, PhotonMapSolver};

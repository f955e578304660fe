//! # radlab-irradiance-cache: Ward's irradiance cache
//!
//! Ward, Rubinstein & Clear 1988 ("A ray tracing solution for diffuse interreflection"), with Ward &
//! Heckbert's 1992 gradients ("Irradiance gradients"), record radii clamped to world-space bounds
//! (Tabellion & Lamorlette 2004) and neighbour clamping (Křivánek, Bouatouch, Pattanaik & Žára 2006,
//! "Making radiance and irradiance caching practical: adaptive caching and neighbor clamping"): the method
//! the survey (Willmott's Table 1, §2.2.5) names as the most stable Monte Carlo method for complex scenes.
//!
//! B(x) = E(x) + ρ(x) (H_d(x) + H_i(x)): direct irradiance H_d by next-event estimation at every answered
//! point; indirect irradiance H_i from records gathered by stratified hemisphere sampling (each ray continued
//! to termination by Russian roulette), interpolated with Ward's weights and the gradients. See
//! [`IrradianceCacheSolver`] (irradiance_cache.rs) for the formulas, the deterministic build in passes, and
//! how points off the query set are answered (the cache is read, never extended there).
//!
//! | parameter | default | meaning |
//! |---|---|---|
//! | `accuracy` | 0.15 | Radiance's -aa: a record serves x while ε = ‖x − x_i‖/R_i + √(1 − n·n_i) < a; 0 = no cache |
//! | `samples` | 512 | Radiance's -ad: hemisphere directions per record (M × N cells, M ≈ √(samples/π)) |
//! | `min_radius` | 0.005 | smallest R, fraction of the scene diagonal (Radiance: size/-ar) |
//! | `max_radius` | 0.25 | largest R, fraction of the scene diagonal |
//! | `direct_samples` | 64 | shadow rays per answered point |
//! | `gradients` | true | Ward & Heckbert gradients in the interpolation |
//! | `neighbour_clamp` | true | R_i ≤ R_j + ‖x_i − x_j‖ both ways on insertion |
//! | `leak_test` | true | a ray from each record used to the point it serves |
//! | `max_depth`, `direct` | 100000, mis | the continuation paths (radlab-pathtrace's estimator) |
//!
//! **Cost**: records × samples gather rays, each continued by a path of about 2/(1 − ρ̄) rays; plus, per
//! answered point, `direct_samples` shadow rays and one leak-test ray per record consulted. Records grow as
//! area/(a R)², so the cache pays when the query points are many (an image, a dense grid) and not at a few
//! dozen scattered points, where nearly every point gathers its own record. Counters: records in
//! `Stats::elements`, and [`IrradianceCacheSolver::counts`] (records, query points, points answered by
//! interpolation, passes). **Does badly**: record noise is smeared over the record's area (blotches that
//! averaging over points does not remove; they fall only with `samples`); interpolation is biased (about a
//! relative to the split-sphere model, less with gradients); bumpy detailed meshes drive R to `min_radius`
//! and the records up; only the first indirect bounce is cached (deeper ones are path traced).
//!
//! Nothing here prints, writes files or reads the clock; results are bit-identical for any thread count.

mod hemisphere_gather;
mod irradiance_cache;
mod params;
mod record_octree;

pub use hemisphere_gather::{Gather, gather, strata};
pub use irradiance_cache::{CacheCounts, GATHER_STREAM_TAG, IrradianceCacheSolver, Record};
pub use params::IrradianceCacheParams;
pub use record_octree::RecordOctree;

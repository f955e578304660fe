//! # radlab-radiosity-texture: adaptive radiosity textures
//!
//! Heckbert 1990 ("Adaptive radiosity textures for bidirectional ray tracing", SIGGRAPH 90): the light pass of
//! his method as a view-independent solution. Particles leave the emitters and are reflected on by Russian
//! roulette (radlab-pathtrace's `trace_photons`, every bounce kept); each landing's power goes into the "rex"
//! of the face it lands on, an adaptive quadtree over the face's own parameter domain whose leaves are
//! histogram bins (rex.rs). A leaf splits into four when it holds more than `split_threshold` particles and
//! is not yet at `min_cell`, so leaves are small where light is dense and, under `split = "contrast"`, only
//! where the density changes (shadow edges). A leaf of area A holding power Φ after N_e emitted particles has
//!
//! B = E + ρ Φ / (N_e A),
//!
//! and points read the leaves through radlab-answer: constant, Gouraud, or a final gather
//! ([`RadiosityTextureSolver`], radiosity_texture.rs). Heckbert's size pass (eye rays setting each surface's
//! texture resolution) has no counterpart: radlab answers at points, and `min_cell` stands for it.
//!
//! | parameter | default | meaning |
//! |---|---|---|
//! | `particles` | 1000000 | landings deposited, over all passes |
//! | `passes` | 4 | steps, each depositing particles/passes more |
//! | `split_threshold` | 100 | particles above which a leaf splits |
//! | `split` | count | `count` (Heckbert) or `contrast` (children's densities must differ, χ² test) |
//! | `min_cell` | 1/256 of the diagonal | smallest leaf (scene units): splits stop at half an edge below it |
//! | `max_depth` | 100000 | reflections cap per particle |
//! | `reconstruction` | gouraud | `constant`, `gouraud` or `final-gather` |
//! | `gather_opening` | 0.25 | final-gather only: far groups of leaves through one drawn leaf each (radlab_answer::AnswerParams); 0 gathers every leaf |
//! | `near_values` | solution | final-gather only: regathered reads each leaf taken one by one with a factor of at least 0.01 from the point (and seen from it) at its value gathered once more at its centroid (radlab_answer::NearValues) |
//!
//! **Cost**: particles × about 1/(1 − ρ̄) flights (a ray each); rebuilding the rexes after each pass is
//! O(landings × depth). Memory: 40 bytes per kept landing (its face parameters and power) and about 140 per
//! cell, with vector slack about 70 bytes per landing in all on the Cornell box. Counters: leaves in `Stats::elements`; [`TextureCounts`] (particles emitted, landings, kept, leaves,
//! cells, depth) through `Solver::counters`. **Does badly**: every leaf is noisy at 1/√split_threshold
//! relative, so a constant or Gouraud read shows blotches unless the threshold is large, and a large threshold
//! keeps leaves coarse (bias across shadow edges and near corners); the count rule refines where light is
//! bright, not where it changes (the contrast rule does, but misses structure that does not unbalance a
//! leaf's four quadrants); dim regions stay coarse, lit only by a few particles; memory grows with every
//! landing kept.
//!
//! Nothing here prints, writes files or reads the clock; results are bit-identical for any thread count.

mod params;
mod radiosity_texture;
pub mod rex;

pub use params::{DEFAULT_MIN_CELL_REL, RadiosityTextureParams, SplitRule};
pub use radiosity_texture::{RadiosityTextureSolver, TextureCounts};

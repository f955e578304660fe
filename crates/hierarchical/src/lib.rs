//! # radlab-hierarchical
//!
//! Hierarchical radiosity (Hanrahan, Salzman & Aupperle 1991): each input face is the
//! root of a quadtree of elements (quads split into four at edge midpoints and centre, triangles into four at
//! edge midpoints), built lazily as links need it. Light moves along *links* between elements at whatever
//! level of their quadtrees the refinement oracle accepts: coarse between distant or dim pairs, fine between
//! near or bright ones. A link's transfer is the receiver-side Gauss quadrature of the exact point-to-polygon
//! form factor times a visibility fraction from rays. The solution gathers over links, pushes irradiance down
//! the quadtrees and pulls area-mean radiosity up.
//!
//! ## Parameters ([`HierarchicalParams`]; presets [`HierarchicalParams::coarse`], [`HierarchicalParams::reference`])
//!
//! | name | default | meaning |
//! |---|---|---|
//! | `epsilon` | 0.0075 | refinement threshold on the oracle's estimate (dimensionless; `params::DEFAULT_EPSILON`) |
//! | `oracle` | `variation` | `f` (max(F_rs, F_sr)), `bf` (ρ_r B_s/B̄ × that, B̄ the area-mean radiosity), `variation` (spread of kernel samples × ρ_r B_s/B̄) |
//! | `error_norm` | `radiosity` | `radiosity` (the estimate as is) or `power` (× A_r / A_scene: the power a link brings) |
//! | `schedule` | `scheduled` | `two-stage`, `interleaved`, `scheduled` (Willmott 2000, §2.4.3) |
//! | `alpha` | 2 | scheduled: ε_{i+1} = ε_i/α, from ε·α^(stages−1) down to ε |
//! | `stages` | 3 | scheduled: stages over which ε falls |
//! | `lazy_linking` | true | interleaved/scheduled: link from a face only once it carries light |
//! | `min_element_size` | diagonal/150 | no element is split into children shorter than this |
//! | `visibility` | `jittered4x4` | rays per link: `unoccluded`, `centre` (1), `jittered2x2`, `jittered4x4` (16), `jittered8x8`; area-sampled settings also give each leaf its open share (128 rays per leaf) |
//! | `leaf_visibility` | `jittered2x2` | gather = leaf: a leaf below a partly visible link's receiver casts its own rays to the source (`centre`, `jittered2x2`, `jittered4x4`) or takes the link's fraction (`link`) |
//! | `quadrature` | 2 | Gauss points per side of the receiver quadrature |
//! | `tolerance` | 1e-4 | estimated relative error at which solving stops |
//! | `max_steps` | 100000 | hard stop, reported as `Step::Capped` (a cap, not a convergence) |
//! | `gather` | `leaf` | `leaf` (kernel integrated at each leaf for every link above it; exact form-factor sums) or `link` (classic per-link mean, pushed) |
//! | `reconstruction` | `final-gather` | `constant` per leaf, `gouraud` (vertex-interpolated, T-vertices resolved), or `final-gather` (one more gather from every leaf; radlab_answer::reconstruction); the default chosen by measurement ([`DEFAULT_RECONSTRUCTION`]) |
//! | `gather_opening` | 0.25 | final-gather only: far groups of leaves through one drawn leaf each (radlab_answer::AnswerParams, DEFAULT_GATHER_OPENING); 0 gathers every leaf |
//! | `near_values` | solution | final-gather only: regathered reads each leaf taken one by one with a factor of at least 0.01 from the point (and seen from it) at its value gathered once more at its centroid (radlab_answer::NearValues) |
//! | `memory_budget_mib` | 4096 | refuse to hold more |
//!
//! Every quantity is relative (ε, tolerance) or relative to the scene's size (the default minimum element), so
//! a scene scaled by any factor gets the same elements and the same answer.
//!
//! ## What a leaf holds: radiosity over its open part
//! Each leaf's open share o ∈ [0, 1] is estimated when it is first solved as a leaf (radlab-kernels'
//! [`radlab_kernels::open_fraction`]: 16 stratified points × 8 cosine rays, a point sealed when every ray meets
//! the back of a face; 0 for a leaf wholly under a floor covering or behind a lamp mounted on the ceiling),
//! with area-sampled visibility only (the default; with `centre` or `unoccluded` o = 1). A leaf's radiosity B
//! ([`Engine::radiosity`], [`HierarchicalSolver::leaves`]) is then that of its open part, B = E + ρ H' with H'
//! the irradiance over its open part, and it sends o A B: a leaf straddling a contact no longer sends into the
//! covering's back light its open part should send (Baum, Mann, Smith & Winget 1991's light leaks), which cost
//! this method 4% of the light of a room with a floor covering. Inner nodes hold the mean over their
//! children's open areas. Where nothing is sealed, o = 1 everywhere and B is the area mean, bit for bit as
//! without open shares. Details: the `open_share` module ([`Engine::open_shares`]). A point answer
//! (`constant`, `gouraud`) inside a leaf reads that leaf's open radiosity (a constant element cannot tell where
//! its sealed part is; a point there is hidden from every viewer but the covering's back), and a wholly sealed
//! leaf's is its emission E (it receives nothing); the final gather answers every point by its own gather, so
//! a sealed point gets E there too, and it leaves wholly sealed leaves out of its sources.
//!
//! ## Steps
//! Each [`radlab_method::Solver::step`] is one unit of work: creating initial links, one refinement pass (each
//! link examined at most once: one that a pass at the same threshold kept, with no solve pass since, is kept
//! again without asking the oracle) or one gather/push-pull pass. The solution is usable after any step.
//!
//! ## Cost
//! O(k² + n) links and time for k input faces and n elements (Hanrahan, Salzman & Aupperle 1991): every pair of mutually visible
//! input faces gets an initial link (16 rays each by default), and the refined links number a bounded
//! multiple of the elements for a fixed ε (about 1/ε with the `f` oracle: Hanrahan, Salzman & Aupperle 1991, §4.2). Memory: about 250
//! bytes per element, 32 per link, 16 per (link, leaf below its source) and, with `gather = leaf`, 16 per
//! (leaf, link above it).
//!
//! ## When it does badly
//! - Many input faces (detailed meshes): the k² initial links dominate time and memory; volume clustering
//!   (radlab-volume-cluster) removes that term.
//! - `gather = link` (classic HSA91) near ρ = 1: a link's coefficient is its receiver's mean, so leaves near a
//!   grazing source (every edge of a room) get form-factor sums far from one — on the furnace cube at ε = 0.05
//!   up to 1.9 instead of 1 — and the error is magnified by 1/(1 − ρ); at ρ = 0.999 the iteration diverges.
//!   The default `gather = leaf` integrates the kernel at each leaf and is exact there, at the price of
//!   memory proportional to elements × links on a leaf's path to its root.
//! - Source-side weighting costs like the leaf gather: a link from an inner node sends its leaves' radiosity
//!   weighted by how much each sees the receiver (A_y F_{y→r}), one kernel evaluation and 16 bytes per (link,
//!   leaf below its source). With the area mean instead, a face seen through links at several levels (near
//!   receivers through small elements, far ones through the whole face) lost energy: its dark corners sent
//!   more than they see and its bright centre less (1.2% of the emitted power in a room lit by a small lamp
//!   under the default schedule and oracle). Energy is now conserved up to the two quadratures of each link
//!   (about 1e-5 relative on a closed box) and the sampled visibility.
//! - Visibility is one fraction per link: a coarse link across a shadow boundary blurs the shadow until the
//!   oracle refines it; sharp shadows from small occluders need many levels, and elements stop at
//!   `min_element_size`.
//! - `two-stage` with the `bf` or `variation` oracle refines for direct light only (it sees emission before
//!   solving); on a small shadowed box its answer differs by about 10% from the other schedules'.
//! - The `variation` oracle sees variation only through its samples; with `quadrature = 1` it would see none
//!   (refused).

//! ## Extending: node kinds and bases
//! The machinery is generic: [`Engine`] refines, gathers, pushes, pulls and schedules over any [`NodeKind`]
//! (area, bound, orientation, projected area, reflectance, emission, split) with light moved by any
//! [`Transport`]. The transport owns the physics and the basis; the engine owns the hierarchy and its state
//! (tree, links, gather cache, schedule, solve state). A transport says
//!
//! - what a link carries ([`Transport::Link`], a [`LinkPayload`]: its source, whether its ends overlap, its
//!   error estimate) and how it is made ([`Transport::link`]); patches and clusters carry the form-factor
//!   [`Link`];
//! - how the refinement estimates a link's error ([`Transport::link_error`]; by default the payload's own,
//!   for [`Link`] the `f`, `bf` and `variation` oracles);
//! - what a source sends ([`Transport::Flux`], [`Transport::emit`]; a constant basis sends one radiosity per
//!   channel), where the link is evaluated ([`GatherAt`]: at the receiver, at each input face below it, or
//!   at each leaf), its coefficient there and how a target receives it ([`Transport::deliver`]), and whether
//!   an inner source sends its leaves' radiosity weighted by how much each sees the receiver
//!   ([`Transport::source_leaf_weight`]);
//! - how a child inherits its parent's irradiance ([`Transport::push`]), how a leaf reflects it
//!   ([`Transport::reflect`]) and how a parent is pulled from its children ([`Transport::pull`]; by
//!   default the area mean of radiosity and the sum of the exitance state);
//! - how a leaf is evaluated at a point ([`Transport::radiosity_at`], read through
//!   [`Engine::radiosity_at_leaf`]; by default its mean, a constant element).
//!
//! A higher-order basis (M² coefficients per element, M⁴ per link) chooses its payload, flux, irradiance
//! and exitance types and overrides pull and point evaluation; the crate's test
//! `tests/transport_contract.rs` shows a new node kind on the default hooks and a piecewise-linear basis
//! with a four-coefficient link, both against closed forms. The patch solver is [`HierarchicalSolver`] =
//! `Engine<Patch, PatchKernel>` (the patch physics, kernel quadrature and source weights, in
//! [`PatchKernel`]) plus the shared output layer ([`SurfaceOutput`]); radlab-volume-cluster supplies cluster
//! nodes and three cluster transfers, starts the engine from one root self-link ([`Engine::add_link`]) and
//! reuses the same refinement, gather, schedules and output.
//!
//! ## Linkless shooting
//! [`Engine::set_linkless`] switches an engine to shooting without stored links (Stamminger, Schirmacher,
//! Slusallek & Seidel 1998; the `shooting` module): each step is a sweep over the roots shooting their unshot
//! radiosity, each shot refining its links top down with the same oracle and ε, delivering through them and
//! dropping them, with an optional bounded link cache ([`LinkCache`]) and the coarse correction sent through
//! the same links. radlab-wavelet exposes it (`linkless`, `link_cache_mib`); this crate's patch solver does
//! not yet: its links weigh their source's leaves, which the shots do not.

mod gather_rows;
mod hierarchy;
mod link;
mod locate;
mod node;
mod open_share;
mod oracle;
pub mod output;
mod params;
mod patch_transport;
mod push_pull;
mod refine;
mod schedule;
mod shooting;
mod solver;
pub mod transport;

pub use hierarchy::Engine;
pub use link::{Link, link_stream};
pub use node::{Bound, LATTICE, MAX_LEVEL, NodeKind, Patch};
pub use oracle::{Action, decide, estimate, light_weight};
pub use output::SurfaceOutput;
pub use params::{
    DEFAULT_RECONSTRUCTION, ErrorNorm, Gather, HierarchicalParams, LeafVisibility,
    MIN_ELEMENT_SIZE_REL, Oracle, Schedule,
};
pub use patch_transport::{PatchKernel, pair_visibility, reflect_scalar};
pub use push_pull::LinkFilter;
/// The answering parameters the engine's [`HierarchicalParams`] flatten in (radlab-answer's).
pub use radlab_answer::AnswerParams;
pub use shooting::{LinkCache, SHOOT_SHARE};
pub use solver::HierarchicalSolver;
pub use transport::{
    GatherAt, LinearState, LinkError, LinkPayload, NodeView, SourceFlux, SourceLight, Transport,
};

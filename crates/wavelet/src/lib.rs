//! # radlab-wavelet
//!
//! Wavelet radiosity (Gortler, Schröder, Cohen & Hanrahan 1993): hierarchical radiosity with a higher-order
//! basis per element. Radiosity on each quadtree element is B(x) = Σ_α b_α φ_α(x) with M² functions
//! ([`basis`]: Haar, flatlets F2/F3, Alpert multiwavelets M2/M3), and a link R ← S carries the M⁴ tensor
//! T_αβ = (1/A_R) ∫_R ∫_S φ_α(x) G(x, y) φ_β(y) dy dx of the radiosity equation's kernel
//! G = cos θ cos θ' V / (π r²) ([`link_tensor`]), so the Galerkin system b^R = E^R + ρ_R Σ_links T b^S is
//! solved by gather, push and pull through the basis' two-scale relations ([`transport`]) on
//! radlab-hierarchical's engine, which refines links until an oracle's estimate is below ε (Bekaert &
//! Willems 1996's by default).
//!
//! ## Parameters ([`WaveletParams`])
//!
//! | name | default | meaning |
//! |---|---|---|
//! | `basis` | `m2` | `haar`, `f2`, `f3`, `m2`, `m3` |
//! | `epsilon` | 0.003 | refinement threshold (dimensionless; chosen on the defaults suite, docs/defaults.md) |
//! | `oracle` | `bekaert-willems` | `bekaert-willems`, `f`, `bf` |
//! | `visibility` | `per-pair` | `per-pair` (a ray per pair of quadrature nodes) or `per-link` (one fraction scaling the tensor) |
//! | `gather` | `leaf` | `leaf` (each link's tensor re-integrated at every leaf below its receiver with the link's visibility: exact form-factor sums) or `receiver` (the classic wavelet gather, pushed down by the two-scale relation) |
//! | `leaf_visibility` | `jittered2x2` | gather = leaf: a leaf below a partly visible link's receiver scales its tensor by its own rays' visibility of the source (`centre`, `jittered2x2`, `jittered4x4`) or by the link's (`link`); as for hierarchical radiosity |
//! | `quadrature` | per basis | Gauss points per side (per sub-square for flatlets): haar 2, f2/f3 2, m2 3, m3 4 |
//! | `min_element_size` | diagonal/150 | no element is split into children shorter than this |
//! | `schedule` | `scheduled` | as for hierarchical radiosity |
//! | `reconstruction` | `final-gather` | `final-gather` (one more gather), `basis` (the leaf's functions), `smoothed` (vertex-averaged means) |
//! | `tolerance`, `max_steps`, `memory_budget_mib` | 1e-4, 100000, 4096 | as for hierarchical radiosity |
//! | `linkless` | false | shoot unshot radiosity without storing links (Stamminger, Schirmacher, Slusallek & Seidel 1998; the engine's `set_linkless`); `schedule` is then not used |
//! | `link_cache_mib` | 0 | linkless only: a least-recently-used cache of computed links (tensors and leaf coefficients) of at most this many MiB; 0 = none; results bit-identical with and without |
//!
//! ## Triangles and other non-parallelogram faces
//! The tensor functions are orthonormal under an element's area mean only where its parameter map has a
//! constant Jacobian: parallelograms. Quads within 5% of one ([`link_tensor::MAX_TWIST`]; the published
//! Cornell box's floor is 0.6% off) carry the tensor too, with the Jacobian in their rule, so their mean is
//! exact and their other functions orthonormal to O(twist). Triangles and other quads hold their mean only (a
//! constant element in a basis of any order); their links still carry the tensor toward the others. An
//! orthonormal basis of the same order on triangles (total degree, as RenderPark has) would give them the
//! same order, but the quadtree's middle child is reflected, so push and pull need two relations; it is
//! left for later. The scenes of the 1997 study are built of quads.
//!
//! ## Cost
//! A link costs n_R n_S kernel evaluations and, with per-pair visibility, as many rays (n² nodes per element:
//! 16 for Haar and F2, 81 for M2 and F3, 256 for M3 at the default quadrature), plus an exact
//! point-to-polygon factor per receiver node; the engine counts each link once as a kernel evaluation, as it
//! does for hierarchical radiosity, and every ray through the accelerator. It holds M⁴ numbers (f32) per link
//! twice (the link and the engine's gather row) and M² per element and channel for radiosity, exitance and
//! irradiance.
//!
//! ## Linkless
//! With `linkless = true` each step is a sweep that shoots the faces' unshot coefficients; each shot refines
//! its links top down with the same oracle and ε, delivers through them at the leaves and drops them
//! (radlab-hierarchical's `shooting` module: the invariant, the coarse correction through the same links, the
//! cache). Memory is the elements' coefficients, the shooting state, the cache and the largest set of links
//! one shot held at once; every link is computed again (kernel evaluations and rays counted again) at every
//! shot that needs it unless the cache holds it. [`radlab_method::Solver::counters`] reports shots, sweeps,
//! corrections, transient links, cache hits, misses and evictions and the peak transient bytes.
//!
//! ## Open shares at contacts
//! A floor element part of which lies under a block standing on it receives light only on its open part
//! (Baum, Mann, Smith & Winget 1991's light and shadow leaks). The linked solver estimates each leaf's open
//! share o (at its receiver quadrature nodes, 8 probe rays each at most, counted) and the engine holds every leaf's coefficients
//! over its open part, as it does for hierarchical radiosity: a link's delivery is credited to its
//! receiver's open part (gain 1/ō on all M² coefficients, ō weighted by the targets' T_00), a wholly sealed
//! leaf receives and sends nothing, and inner nodes pull means over open areas; the power delivered is
//! unchanged (the share enters per leaf: [`transport`]). A point answer first tests the point
//! ([`radlab_kernels::open_fraction::point_sealed`], up to 128 rays, charged to answering; the basis and
//! smoothed answers inside leaves with o < 1, the final gather at every point, as it does for every method):
//! a point under the block answers its emission, as the exact solution does, whatever the reconstruction.
//!
//! ## Not done
//! Linkless shooting does not estimate open shares (every leaf open; its shots deliver without the
//! engine's per-link gains). Linkless: an
//! element split after it received light keeps that light as its parent's, pushed (the receiver gather's
//! approximation), where the linked leaf gather re-integrates every link at the new leaves, so the two differ
//! by about ε (tests/linkless.rs) and a furnace refined at mixed levels is off by up to a few 1e-3 at
//! ρ = 0.999 (0.24% measured with Haar, ε = 0.05 under the F oracle, elements down to an eighth of a side).

pub mod basis;
pub mod link_tensor;
mod params;
mod solver;
pub mod transport;

pub use basis::Basis;
pub use link_tensor::Visibility;
pub use params::{WaveletParams, WaveletReconstruction};
pub use solver::{Engines, Run, WaveletSolver};
pub use transport::{Coeffs, WaveletGather, WaveletLink, WaveletOracle, WaveletTransport};

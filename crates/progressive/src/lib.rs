//! # radlab-progressive: progressive refinement radiosity
//!
//! Solves the diffuse radiosity equation B = E + ρ F B over a piecewise-constant mesh by *shooting*
//! (Cohen, Chen, Wallace & Greenberg 1988), Southwell's relaxation: every patch keeps the radiosity it has
//! received but not yet passed on (its *unshot* radiosity ΔB); each shot takes the patch with the most unshot
//! power A ΔB and distributes it to every receiving element,
//!
//! ΔB_e = ρ_e ΔB_j F_{e→j},
//!
//! with F_{e→j} evaluated from the receiver's own points toward the shooter (the exact point-to-polygon factor,
//! times a visibility fraction from rays). Only one column of the form-factor matrix exists at a time, so memory
//! is O(n) and an incomplete solution is always available — direct light first, then the brightest
//! interreflections.
//!
//! Around the shooting loop:
//! - **Substructuring** (Cohen, Greenberg, Immel & Brock 1986): coarse *patches* shoot, finer *elements*
//!   receive; a patch's radiosity is the area-weighted mean of its elements. By default a patch is one element
//!   of `element_size`, and only the elements adaptive subdivision makes are finer than their patch.
//! - **Adaptive subdivision**: after each step, neighbouring elements of a face whose radiosities differ by more
//!   than a relative threshold are split in four (down to a minimum size); new elements re-gather from every
//!   patch shot so far, so they hold what they would have held had they existed from the start.
//! - **Ambient term** (Cohen et al. 1988): an estimate of the light not yet shot, added to displayed radiosity
//!   only when asked for.
//! - **Overshooting** (Feda & Purgathofer 1992; Gortler, Cohen & Slusallek 1993): by default a patch light has
//!   reached shoots its unshot radiosity plus the ambient estimate of what it will still receive, ρ_j B_amb,
//!   with the interreflection factor measured from the shots so far; unshot radiosity may go negative and later
//!   shots correct it. The fixed point is that of plain shooting (`overshoot = none`), and the unshot radiosity
//!   stays the residual of the linear system, so the stopping rule keeps its meaning.
//! - **Stopping rule**: stop when the unshot power is a given fraction of the emitted power. In a closed scene
//!   of reflectance ρ the radiosity is then short by about ρ times that fraction.
//!
//! Results are deterministic: every random choice is a function of (seed, element, patch), and sums are taken
//! in a fixed order, so a run is bit-identical for any rayon thread count.
//!
//! ## Parameters ([`ProgressiveParams`])
//!
//! | name | default | meaning |
//! |---|---|---|
//! | `element_size` | 1/30 of the scene's bounding diagonal (`params::DEFAULT_ELEMENT_SIZE_REL`) | receiving element size (longest edge, scene units) |
//! | `patch_size` | `element_size` | shooting patch size; larger shoots from patches of several elements (substructuring) |
//! | `shots_per_step` | 1 | shots per `step()`; changes only the granularity, never the answer |
//! | `visibility` | `jittered4x4` | visibility between element and an emitting shooter (direct light): `unoccluded`, `centre`, `jittered2x2`, `jittered4x4` (16 rays), `jittered8x8` |
//! | `indirect_visibility` | `jittered2x2` | the same for shooters that do not emit (interreflected light) |
//! | `quadrature` | 2 | m × m receiver points per element (1 = centroid) |
//! | `stop_unshot_fraction` | 2e-3 | stop when unshot power ≤ this fraction of emitted power |
//! | `max_shots` | none | stop after this many shots |
//! | `adaptive` | true | adaptive subdivision on/off |
//! | `adaptive_threshold` | 0.3 | relative contrast \|B_a − B_b\| / max(B_a, B_b) that splits neighbours |
//! | `min_element_size` | `element_size` / 4 | smallest edge subdivision creates |
//! | `ambient` | false | add the ambient term to displayed radiosity (keep off when measuring error) |
//! | `memory_budget_mib` | 2048 | refuse meshes and refinements needing more |
//! | `overshoot` | `ambient` | `none` (plain Southwell shooting) or `ambient` (overshooting, see above) |
//! | `reconstruction` | `final-gather` | point answers: `constant`, `gouraud` or `final-gather` (see below) |
//! | `gather_opening` | 0.25 | final-gather only: far groups of elements through one drawn element each (radlab_answer::AnswerParams, DEFAULT_GATHER_OPENING); 0 gathers every element |
//! | `near_values` | solution | final-gather only: regathered reads each element taken one by one with a factor of at least 0.01 from the point (and seen from it) at its value gathered once more at its centroid (radlab_answer::NearValues) |
//!
//! **Point answers** (`reconstruction`, radlab_answer::reconstruction): `constant` is the element's value (plus the
//! ambient term when on); `gouraud` interpolates vertex values over each face's leaf elements, anchoring the
//! T-vertices adaptive subdivision creates so the field stays continuous; `final-gather` recomputes
//! B(x) = E(x) + ρ(x) Σ_j F_{x→j} V_xj B_j from every leaf element (Lischinski, Tampieri & Greenberg 1993). The data is rebuilt at the
//! first query after a step; a gather's rays and kernel evaluations are reported by
//! [`ProgressiveSolver::gather_work`], not in `stats()` (answering is charged by whoever asks, per query pass).
//!
//! Every default length is relative to the scene's size, the threshold is a relative contrast and the stopping
//! rule a fraction of emitted power, so the defaults behave the same at any scene scale and light level.
//! [`ProgressiveParams::fixed_mesh`] gives the settings under which the method solves the matrix method's
//! discretisation (same regular mesh, kernel and visibility) for cross-checks; the matrix method also
//! symmetrises each pair, so the two agree to within the receiver quadrature's reciprocity error (1.9e-3 at
//! 2 × 2 points and 3e-5 at 4 × 4 on a room meshed on one grid).
//!
//! ## Cost
//!
//! A shot costs one form factor (and its `visibility` or `indirect_visibility` rays) per receiving element: O(n) for n elements. The number
//! of shots grows with the number of patches N and with the reflectance: for a closed scene of reflectance ρ,
//! plain shooting needs about N ln(1/ε) / (1 − ρ) shots to bring the unshot fraction to ε, so the whole
//! solution costs O(N n ln(1/ε) / (1 − ρ)) — quadratic in the mesh, like the matrix method, but with O(n) memory
//! and a usable picture after the first few shots. Overshooting takes the slow uniform mode out of the 1/(1 − ρ)
//! factor: a few shots per patch at any ρ in a furnace (measured below). A split element re-gathers from every patch shot so far (one matrix row).
//! Memory: O(n + N).
//!
//! Measured on the Cornell box (`builtin:cornell`, 2 cores, `cargo bench -p radlab-progressive --bench
//! measure`): the defaults make 288 patches and 1,152 elements, refined to 3,606, and stop after 1,181 shots
//! in 1.7–3.4 s with an area-weighted relative L1 error of 6.0 % against the path-traced reference (noise
//! floor 1.7 %), holding 1.7 MB; matrix radiosity at its defaults reaches 7.2 % with 1,087 elements in about
//! 1 s, holding 9.7 MB. At equal element counts (no substructuring) the memory ratio is 13× at 1,087
//! elements and 47× at 4,100. Time against element count without substructuring fits a log-log slope of
//! 1.7–1.9. Those figures are for plain shooting (`overshoot = none`); with the default overshooting the same
//! run stops after 700 shots instead of 1,181 (3,624 elements), at the same unshot fraction, and differs from a
//! plain solution converged to 1e-5 by 0.20 % (relative L1 at the 2,000 evaluation points; plain shooting at its
//! stop: 0.12 %); step times of the two were within the noise of a loaded machine (ratio 0.87 and 1.3 in two
//! runs; `cargo bench -p radlab-progressive --bench measure -- cornell-overshoot`).
//!
//! ## When it does badly
//!
//! - **High reflectance in closed scenes** (ρ → 1), with `overshoot = none`: the shot count grows as 1/(1 − ρ);
//!   at ρ = 0.999 a furnace needs thousands of shots per patch. Overshooting (the default) removes most of
//!   that: on the furnace cube's default mesh (384 patches; `cargo bench -p radlab-progressive --bench measure
//!   -- high-albedo`, one run on a loaded 2-core machine) a relative L1 error of 1 % took 383 shots at ρ = 0.5
//!   and 1,078 at ρ = 0.999 (step time 2.1 times that at ρ = 0.5), where plain shooting took 1,299 shots at
//!   ρ = 0.5 and was still 95 % short after 120 s at ρ = 0.999. Its transients (early shots send several
//!   times their final radiosity) raise contrasts, so adaptive subdivision splits more: 3,081 elements instead
//!   of 1,536 there.
//! - **Large meshes**: time grows roughly quadratically with the element count (every shot visits every
//!   element); hierarchical methods scale better.
//! - **Piecewise-constant elements** show their edges: adaptive subdivision refines shadow boundaries but only
//!   where a neighbour's contrast reveals them, and an element smaller than `min_element_size` is never made.
//! - **Substructuring** (`patch_size` above `element_size`) shoots a patch's mean radiosity uniformly:
//!   receivers very close to a patch with a strong gradient across it see a smoothed source. It is off by
//!   default since 2026-12-06: with 2 × 2-element patches the floor under the furnished room's ball answered
//!   21% bright at its worst point, 8% with every element shooting (docs/defaults.md).
//! - **Visibility noise**: `jittered4x4` estimates each visibility fraction from 16 rays; penumbrae carry that
//!   noise, and contrast from it can trigger subdivision.

mod adaptive_subdivision;
mod ambient;
mod element_location;
pub mod params;
mod shooting;
mod solver;
mod substructuring;

pub use params::{DEFAULT_RECONSTRUCTION, Overshoot, ProgressiveParams};
pub use solver::{ElementView, ProgressiveSolution, ProgressiveSolver, StopReason};

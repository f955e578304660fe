//! # radlab-matrix: matrix radiosity
//!
//! The classic finite-element radiosity method (Goral et al. 1984; Cohen & Greenberg 1985):
//! mesh every face into constant elements, compute the form factor between **every** pair of elements, and
//! solve the linear system B_i = E_i + ρ_i Σ_j F_ij B_j per RGB channel. It is the reference point the
//! progressive, hierarchical and clustering methods improve on: exact in its own discretisation, but
//! quadratic in the number of elements.
//!
//! ## How
//! - **Mesh**: `ElementMesh::new(scene, element_size)`, quads into bilinear grids and triangles into m².
//! - **Form factors** (`assembly.rs`): receiver quadrature (`quadrature`² points) of the exact point-to-polygon
//!   kernel times a visibility fraction from `visibility` rays per pair, computed once per unordered pair.
//!   The two directions of a pair are averaged into the symmetric area-weighted matrix
//!   G_ij = ½(A_i F_ij + A_j F_ji), and the row's difference is kept on the diagonal so every row sum stays
//!   that of its own quadrature. This enforces reciprocity A_i F_ij = A_j F_ji exactly (conjugate gradient
//!   and energy conservation need it) and keeps the furnace exact up to ρ = 0.999.
//! - **Solution** (`jacobi.rs`, `gauss_seidel.rs`, `conjugate_gradient.rs`): one iteration per step. Conjugate
//!   gradient works on the symmetric form (A_i/ρ_i) B_i − Σ_j A_i F_ij B_j = A_i E_i/ρ_i with ρ = 0 elements
//!   fixed at B = E. All three stop on the same rule (`linear_system.rs`): relative residual (area-weighted
//!   L1) below `tolerance × (1 − ρ_max)`, which bounds the relative error of B by `tolerance`.
//! - **Steps**: assembly takes the first steps (blocks of whole rows holding at least max(65,536, 16 n)
//!   element pairs each; 7 steps for ~940 elements), then one step per iteration; [`Solver::step`](radlab_method::Solver::step) returns `Converged` once the rule is met or
//!   `max_iterations` is reached ([`MatrixSolver::hit_iteration_cap`] tells which).
//! - **Solution queries** (`reconstruction`, radlab_answer::reconstruction): `constant` answers B of the element
//!   containing the point; `gouraud` interpolates vertex values (least-squares fits to the surrounding
//!   elements) over each face's elements; `final-gather` recomputes B(x) = E(x) + ρ(x) Σ_j F_{x→j} V_xj B_j
//!   from every element with the exact point-to-polygon factor and visibility rays (Lischinski, Tampieri & Greenberg 1993). The gather's
//!   rays and kernel evaluations are counted by [`MatrixSolver::gather_work`], not in `stats()`, which counts
//!   solving: answering is charged by whoever asks, once per set of queries (the runner times each evaluation
//!   pass and adds it to the run's time and rays). A gather costs one kernel evaluation and one to sixteen rays
//!   per element per query point, so it suits answers at hundreds or thousands of points, not every pixel of a
//!   large image.
//!
//! ## Parameters ([`MatrixParams`])
//! | name | default | meaning |
//! |---|---|---|
//! | `element_size` | 1/25 of the bounding-box diagonal | longest element edge (scene units) |
//! | `iteration` | `gauss-seidel` | `jacobi`, `gauss-seidel` or `conjugate-gradient` |
//! | `tolerance` | 1e-4 | target relative error of B (area-weighted L1) |
//! | `max_iterations` | 100000 | cap on iterations |
//! | `visibility` | `jittered4x4` | rays per element pair: `unoccluded`, `centre`, `jittered2x2`, `jittered4x4`, `jittered8x8` |
//! | `quadrature` | 2 | receiver points per axis (1..=16) |
//! | `memory_budget_mib` | 2048 | refuse problems whose matrix and vectors exceed this |
//! | `reconstruction` | `final-gather` | point answers: `constant`, `gouraud` or `final-gather` |
//! | `gather_opening` | 0.25 | final-gather only: far groups of elements through one drawn element each (radlab_answer::AnswerParams, DEFAULT_GATHER_OPENING); 0 gathers every element |
//! | `near_values` | solution | final-gather only: regathered reads each element taken one by one with a factor of at least 0.01 from the point (and seen from it) at its value gathered once more at its centroid (radlab_answer::NearValues) |
//!
//! ## Cost
//! n elements: **O(n²) memory** (8 n² bytes: about 8 MB at n = 1,000, 800 MB at n = 10,000) and **O(n²)
//! time** for assembly (n²/2 pairs, each 2·quadrature² kernel evaluations and up to `visibility` rays) and per
//! iteration. Iterations: Jacobi and Gauss–Seidel about log(tolerance·(1 − ρ_max))/log(λ), λ ≤ ρ_max the
//! spectral radius of ρF', growing like 1/(1 − ρ); conjugate gradient like 1/√(1 − ρ). Measured (release,
//! one core): the builtin Cornell box at the default element size has 1,377 elements and assembles in about
//! 2.3 s of CPU time (10.7 M rays, 1.3 M receiver quadratures; half of it ray casting, the rest the kernel);
//! then Jacobi / Gauss–Seidel / conjugate gradient take 16 / 10 / 7 iterations of a few milliseconds each. Assembly and Jacobi / conjugate-gradient iterations run in parallel
//! over rows; Gauss–Seidel is sequential. Results are bit-identical for any thread count: visibility rays
//! for pair (i, j) come from the stream i·n + j of `seed`, and every sum runs in a fixed order.
//!
//! ## When it does badly
//! - Large or finely meshed scenes: memory and time grow with the square of the element count (refused
//!   beyond `memory_budget_mib` with the bytes needed), and a uniform mesh wastes elements where radiosity is
//!   smooth (hierarchical radiosity links at the right level instead).
//! - Sharp shadows and contact: a uniform mesh with constant elements blurs shadow boundaries and staircases
//!   them at element size. Where elements touch or interpenetrate (a block standing on the floor), the
//!   2 × 2-point receiver quadrature is least accurate, the two directions of a pair disagree most and the
//!   reciprocity correction on the diagonal is largest (up to a few per cent of the row there; raise
//!   `quadrature` to shrink it). Kernel × visibility-fraction is not exact for partly occluded pairs, so the
//!   rows of a closed occluded scene sum to 1 only within about 1e-3 on walls and 5e-3 on the blocks of a
//!   Cornell box, and energy is conserved only to that accuracy (unoccluded scenes conserve it exactly).
//! - Reflectance near 1 with Jacobi or Gauss–Seidel: iterations grow like 1/(1 − ρ); use conjugate gradient.
//!
//! Nothing here prints, writes files or reads the clock.

mod assembly;
mod conjugate_gradient;
mod gauss_seidel;
mod jacobi;
mod linear_system;
mod params;
mod solver;

pub use assembly::{PAIRS_PER_STEP, predicted_element_count, required_bytes};
pub use params::{
    DEFAULT_MAX_ITERATIONS, DEFAULT_MEMORY_BUDGET_MIB, DEFAULT_QUADRATURE, DEFAULT_RECONSTRUCTION,
    DEFAULT_TOLERANCE, Iteration, MAX_QUADRATURE, MatrixParams,
};
pub use radlab_kernels::form_factor::VisibilitySampling;
pub use solver::MatrixSolver;

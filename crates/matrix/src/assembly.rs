//! Assembly of the reciprocal form-factor matrix, stored area-weighted and symmetric:
//!
//! G_ij = ½ (A_i F_ij + A_j F_ji) for i ≠ j,   G_ii = ½ Σ_j (A_i F_ij − A_j F_ji),
//!
//! where each F_ij is the receiver-side quadrature of the exact point-to-polygon kernel over element i times a
//! visibility fraction V_ij (Wallace, Elmquist & Haines 1989 split kernel and
//! visibility the same way). The discrete equation is B_i = E_i + ρ_i Σ_j F'_ij B_j with F'_ij = G_ij / A_i
//! (the radiosity equation of Goral et al. 1984 discretised with constant elements).
//!
//! Why this form: the quadratures A_i F_ij and A_j F_ji estimate the same quantity ∫∫ G V dA dA but differ by
//! their quadrature errors, so the raw matrix is only approximately reciprocal. Averaging them makes
//! A_i F'_ij = A_j F'_ji exact, which the symmetric form of conjugate gradient (see
//! conjugate_gradient.rs) and energy conservation (emitted = absorbed + escaped) both need. The diagonal term puts the
//! difference back on the row, so every row keeps the sum of its own receiver quadrature:
//! Σ_j F'_ij = Σ_j F_ij, which the exact point kernel makes 1 to rounding in a closed unoccluded scene (the
//! furnace stays exact at ρ → 1). The correction is local: it changes nothing where neighbouring radiosities
//! are equal.
//!
//! Visibility V_ij = V_ji is sampled once per unordered pair from the stream i·n + j (i < j), so each pair's
//! rays are cast once and the result does not depend on the thread count. Pairs where neither element lies in
//! front of the other's plane, and pairs on the same (planar) face, cost no kernel evaluation and no ray.

use std::ops::Range;

use glam::DVec3;
use radlab_answer::ElementMesh;
use radlab_kernels::form_factor::{
    VisibilitySampling, polygon_polygon_unoccluded, visibility_fraction,
};
use radlab_method::SolveError;
use radlab_scene::{Scene, facing_away};
use radlab_visibility::Accel;
use rayon::prelude::*;

/// Unordered pairs assembled per step at least (about a million rays with 4 × 4 visibility), so steps are
/// short enough to trace and long enough to keep both cores busy.
pub const PAIRS_PER_STEP: usize = 1 << 16;

/// Fewest pairs of a row computed by one rayon task.
const PAIRS_PER_TASK: usize = 64;

/// Side of the square tiles the symmetrisation pass walks, for cache locality on large matrices.
const TILE: usize = 64;

/// Bytes held per element besides the matrix row: area, ρ, E, B and up to six solver vectors (RGB f64),
/// plus the element itself in the mesh.
pub fn bytes_per_element() -> u64 {
    (8 + 10 * 24 + size_of::<radlab_answer::Element>() + 8) as u64
}

/// Bytes the solver needs for `n` elements: the dense n × n matrix of f64 plus per-element data.
pub fn required_bytes(n: u64) -> u64 {
    n.saturating_mul(n)
        .saturating_mul(8)
        .saturating_add(n.saturating_mul(bytes_per_element()))
}

/// The number of elements `ElementMesh::new(scene, size)` will make ([`radlab_scene::Polygon::subdivision`]
/// of every face), computed without meshing so a refusal costs nothing.
pub fn predicted_element_count(scene: &Scene, size: f64) -> u64 {
    (0..scene.faces.len())
        .map(|f| {
            let (nu, nv) = scene.polygon(f).subdivision(size);
            (nu * nv) as u64
        })
        .sum()
}

/// Per-element geometry the pair loop reads.
#[derive(Clone)]
struct Geometry {
    normal: DVec3,
    centroid: DVec3,
}

/// The matrix being assembled, row block by row block.
#[derive(Clone)]
pub struct Assembly {
    n: usize,
    geometry: Vec<Geometry>,
    /// Row-major n × n. During assembly: A_i F_ij above the diagonal (row i), A_j F_ji below it (row j);
    /// after the last block (symmetrised): G.
    pub matrix: Vec<f64>,
    next_row: usize,
    /// Receiver quadratures computed (two per pair that is not culled).
    pub form_factors: u64,
    /// Rays requested from the visibility estimator.
    pub rays: u64,
    /// Nonzero entries of the finished matrix.
    pub nonzero: u64,
    finished: bool,
}

/// What one pair computation needs.
pub struct PairSettings {
    /// Receiver quadrature points per axis.
    pub quadrature: u32,
    /// Visibility estimate.
    pub visibility: VisibilitySampling,
    /// Seed of the visibility streams.
    pub seed: u64,
}

impl Assembly {
    /// Allocates the zeroed matrix. The caller has checked the memory budget; an allocation the system
    /// cannot satisfy is an over-budget error rather than an abort.
    pub fn new(mesh: &ElementMesh, budget_bytes: u64) -> Result<Self, SolveError> {
        let n = mesh.len();
        let entries = n.checked_mul(n);
        let mut matrix = Vec::new();
        if entries.is_none_or(|e| matrix.try_reserve_exact(e).is_err()) {
            let needed = required_bytes(n as u64);
            return Err(SolveError::over_budget(
                &format!("the {n} × {n} form-factor matrix"),
                needed,
                budget_bytes,
                "the system could not allocate it; use a larger element_size",
            ));
        }
        matrix.resize(n * n, 0.0);
        let geometry = mesh
            .elements
            .iter()
            .map(|e| Geometry {
                normal: e.polygon.normal(),
                centroid: e.centroid,
            })
            .collect();
        Ok(Self {
            n,
            geometry,
            matrix,
            next_row: 0,
            form_factors: 0,
            rays: 0,
            nonzero: 0,
            finished: false,
        })
    }

    /// Whether every row has been assembled and symmetrised.
    pub fn is_finished(&self) -> bool {
        self.finished
    }

    /// The next block of rows: whole rows holding at least [`PAIRS_PER_STEP`] (and 16 n) pairs.
    fn next_block(&self) -> Range<usize> {
        let target = PAIRS_PER_STEP.max(16 * self.n);
        let start = self.next_row;
        let mut end = start;
        let mut pairs = 0;
        while end < self.n && pairs < target {
            pairs += self.n - 1 - end;
            end += 1;
        }
        start..end
    }

    /// Assembles the next block of rows in parallel; after the last block, symmetrises. Returns whether the
    /// matrix is complete.
    pub fn step(&mut self, mesh: &ElementMesh, accel: &Accel, settings: &PairSettings) -> bool {
        if self.finished {
            return true;
        }
        let n = self.n;
        let rows = self.next_block();
        let geometry = &self.geometry;
        let block = &mut self.matrix[rows.start * n..rows.end * n];
        // Row i computes the pairs (i, j > i): A_i F_ij goes to its own row, A_j F_ji is returned and
        // scattered below the diagonal afterwards (row j is not this task's to write).
        let results: Vec<(Vec<f64>, u64, u64)> = block
            .par_chunks_mut(n)
            .enumerate()
            .map(|(k, row)| {
                let i = rows.start + k;
                // A row's pairs are split further when a thread runs out of rows (the last rows of a block
                // would otherwise leave one thread idle while the other finishes a whole row).
                let pairs: Vec<(f64, f64, u64, u64)> = (i + 1..n)
                    .into_par_iter()
                    .with_min_len(PAIRS_PER_TASK)
                    .map(|j| pair(mesh, geometry, accel, settings, n, i, j))
                    .collect();
                let mut lower = Vec::with_capacity(n - 1 - i);
                let (mut ff, mut rays) = (0u64, 0u64);
                for (slot, (a, b, f, r)) in row[i + 1..].iter_mut().zip(pairs) {
                    *slot = a;
                    lower.push(b);
                    ff += f;
                    rays += r;
                }
                (lower, ff, rays)
            })
            .collect();
        // Scatter A_j F_ji below the diagonal, each row j on its own task (plain stores: any order).
        self.matrix[(rows.start + 1) * n..]
            .par_chunks_mut(n)
            .enumerate()
            .for_each(|(k, row)| {
                let j = rows.start + 1 + k;
                for (i, (lower, _, _)) in (rows.start..rows.end.min(j)).zip(&results) {
                    row[i] = lower[j - i - 1];
                }
            });
        for (_, ff, rays) in results {
            self.form_factors += ff;
            self.rays += rays;
        }
        self.next_row = rows.end;
        if self.next_row >= n {
            self.symmetrise();
            self.finished = true;
        }
        self.finished
    }

    /// G_ij = G_ji = ½(a + b) with a = A_i F_ij, b = A_j F_ji; the halved differences go on the diagonal so
    /// each row keeps its own quadrature's sum. Sequential, in a fixed tile order: deterministic.
    fn symmetrise(&mut self) {
        let n = self.n;
        let mut diag = vec![0.0; n];
        let m = &mut self.matrix;
        for bi in (0..n).step_by(TILE) {
            for bj in (bi..n).step_by(TILE) {
                for i in bi..(bi + TILE).min(n) {
                    for j in bj.max(i + 1)..(bj + TILE).min(n) {
                        let a = m[i * n + j];
                        let b = m[j * n + i];
                        let s = 0.5 * (a + b);
                        m[i * n + j] = s;
                        m[j * n + i] = s;
                        let d = 0.5 * (a - b);
                        diag[i] += d;
                        diag[j] -= d;
                    }
                }
            }
        }
        for (i, d) in diag.into_iter().enumerate() {
            m[i * n + i] = d;
        }
        self.nonzero = m.par_iter().filter(|&&g| g != 0.0).count() as u64;
    }
}

/// One unordered pair: (A_i F_ij, A_j F_ji, receiver quadratures computed, rays requested).
fn pair(
    mesh: &ElementMesh,
    geometry: &[Geometry],
    accel: &Accel,
    s: &PairSettings,
    n: usize,
    i: usize,
    j: usize,
) -> (f64, f64, u64, u64) {
    let (ei, ej) = (&mesh.elements[i], &mesh.elements[j]);
    if ei.face == ej.face {
        return (0.0, 0.0, 0, 0);
    }
    let (gi, gj) = (&geometry[i], &geometry[j]);
    if facing_away(
        &ei.polygon,
        gi.centroid,
        gi.normal,
        &ej.polygon,
        gj.centroid,
        gj.normal,
    ) {
        return (0.0, 0.0, 0, 0);
    }
    let uij = polygon_polygon_unoccluded(&ei.polygon, &ej.polygon, s.quadrature);
    let uji = polygon_polygon_unoccluded(&ej.polygon, &ei.polygon, s.quadrature);
    if !(uij > 0.0 || uji > 0.0) {
        return (0.0, 0.0, 2, 0);
    }
    let stream = (i as u64) * (n as u64) + j as u64;
    let v = visibility_fraction(
        accel,
        &ei.polygon,
        ei.face as usize,
        &ej.polygon,
        ej.face as usize,
        s.visibility,
        s.seed,
        stream,
    );
    (
        ei.area * uij * v,
        ej.area * uji * v,
        2,
        u64::from(s.visibility.rays()),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use radlab_scene::builtin;

    fn assemble(scene: &Scene, size: f64, q: u32) -> (ElementMesh, Assembly) {
        let mesh = ElementMesh::new(scene, size);
        let accel = Accel::new(scene);
        let mut a = Assembly::new(&mesh, u64::MAX).expect("small matrix");
        let s = PairSettings {
            quadrature: q,
            visibility: VisibilitySampling::Jittered4x4,
            seed: 1,
        };
        while !a.step(&mesh, &accel, &s) {}
        (mesh, a)
    }

    #[test]
    fn prediction_matches_the_mesh() {
        let scene = builtin("furnace-cube?tessellation=3&size=2").expect("scene");
        for size in [0.1, 0.3, 0.7, 5.0] {
            let mesh = ElementMesh::new(&scene, size);
            assert_eq!(predicted_element_count(&scene, size), mesh.len() as u64);
        }
    }

    #[test]
    fn matrix_is_symmetric_and_rows_keep_unit_sums_in_a_closed_convex_scene() {
        let scene = builtin("furnace-cube?tessellation=2").expect("scene");
        let (mesh, a) = assemble(&scene, 0.25, 2);
        let n = mesh.len();
        assert_eq!(n, 6 * 16);
        assert!(a.is_finished());
        for i in 0..n {
            let row = &a.matrix[i * n..(i + 1) * n];
            let sum: f64 = row.iter().sum::<f64>() / mesh.elements[i].area;
            // The exact point kernel sums to 1 over a closed convex enclosure at every quadrature point.
            assert!((sum - 1.0).abs() < 1e-12, "row {i}: {sum}");
            for (j, &g) in row.iter().enumerate() {
                assert_eq!(g, a.matrix[j * n + i]);
            }
        }
        // Entries within one face are zero, off-face entries positive.
        assert_eq!(a.matrix[1], 0.0);
        assert!(a.matrix[n - 1] > 0.0);
    }
}

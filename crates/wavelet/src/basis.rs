//! Bases of one element: Alpert's multiwavelet scaling functions (tensor products of orthonormal scaled
//! Legendre polynomials; Alpert 1993, used for radiosity by Gortler, Schröder, Cohen & Hanrahan 1993) and
//! flatlets (piecewise constant on M × M sub-squares; Gortler et al. 1993), on the unit square (s, t).
//!
//! In one dimension the M functions φ_i on [0, 1] are orthonormal, ∫₀¹ φ_i φ_j = δ_ij, with φ_0 = 1:
//! Legendre φ_1 = √3 (2t − 1), φ_2 = √5 (6t² − 6t + 1); flatlets the discrete Legendre vectors on M equal
//! cells (F2: ±1; F3: √(3/2) (−1, 0, 1) and (1, −2, 1)/√2). On an element of area A with parameter map of
//! constant Jacobian (a parallelogram), the functions φ_{iM+j}(s, t) = φ_i(s) φ_j(t) are orthonormal under
//! the element's mean, (1/A) ∫ φ_α φ_β dA = δ_αβ, so a function's coefficients b_α = (1/A) ∫ f φ_α dA are
//! average-normalised: b_0 is the mean of f.
//!
//! Two-scale relation: the quadtree splits an element into four at its midpoints, child c = (c_s, c_t) ∈
//! {0, 1}² covering s ∈ [c_s/2, (c_s + 1)/2] and t likewise. In one dimension
//! H^c_ij = ∫₀¹ φ_i((u + c)/2) φ_j(u) du (i of the parent, j of the child), computed here by exact composite
//! Gauss–Legendre quadrature (six pieces of four points: every break of a flatlet or of its parent falls on a
//! multiple of 1/6 of the child), not typed in. Push (the parent's function restricted to a child, exact
//! since the parent's space lies in the child's): b^c_j = Σ_i H^c_ij b_i; pull (the L² projection of the
//! children onto the parent): b_i = ¼ Σ_c Σ_j H^c_ij b^c_j; in two dimensions H^{c_s} ⊗ H^{c_t}. Pull after
//! push is the identity.

use radlab_kernels::form_factor::gauss_legendre;
use serde::{Deserialize, Serialize};

/// √3.
const SQRT3: f64 = 1.732_050_807_568_877_2;
/// √5.
const SQRT5: f64 = 2.236_067_977_499_79;

/// The basis of an element (Gortler, Schröder, Cohen & Hanrahan 1993; Alpert 1993).
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum Basis {
    /// Constant per element (one coefficient): the Haar basis of hierarchical radiosity.
    #[default]
    Haar,
    /// Flatlets F2: constant on 2 × 2 sub-squares (4 coefficients).
    F2,
    /// Flatlets F3: constant on 3 × 3 sub-squares (9 coefficients).
    F3,
    /// Multiwavelets M2: bilinear, tensor Legendre of degree ≤ 1 per side (4 coefficients).
    M2,
    /// Multiwavelets M3: biquadratic, tensor Legendre of degree ≤ 2 per side (9 coefficients).
    M3,
}

impl Basis {
    /// Every basis, in order of coefficients.
    pub const ALL: [Basis; 5] = [Basis::Haar, Basis::F2, Basis::F3, Basis::M2, Basis::M3];

    /// Functions per side, M (1, 2 or 3).
    pub fn side(self) -> usize {
        match self {
            Basis::Haar => 1,
            Basis::F2 | Basis::M2 => 2,
            Basis::F3 | Basis::M3 => 3,
        }
    }

    /// Functions per element, M².
    pub fn len(self) -> usize {
        self.side() * self.side()
    }

    /// Always false: an element has at least one function.
    pub fn is_empty(self) -> bool {
        false
    }

    /// Whether the functions are piecewise constant on sub-squares (flatlets, and Haar's one square).
    pub fn is_flatlet(self) -> bool {
        matches!(self, Basis::Haar | Basis::F2 | Basis::F3)
    }

    /// Order of approximation: the L² projection error falls as h^order (M for multiwavelets, 1 for
    /// flatlets, whose space is piecewise constant).
    pub fn order(self) -> u32 {
        if self.is_flatlet() {
            1
        } else {
            self.side() as u32
        }
    }

    /// Cells per side of the element's quadrature: M for flatlets (one Gauss rule per sub-square, exact for
    /// piecewise constants), 1 for polynomials.
    pub fn cells(self) -> usize {
        if self.is_flatlet() { self.side() } else { 1 }
    }

    /// Gauss points per cell and side by default: M + 1 for multiwavelets (a rule of degree 2M + 1, as
    /// Bekaert & Willems 1996 ask for error estimates), 2 for Haar and 2 per sub-square for flatlets: one more
    /// per side than the functions on a cell. With one point per sub-square a flatlet link reproduces the
    /// kernel at the receiver's nodes exactly by construction (M² nodes, M² functions), so Bekaert &
    /// Willems's residual is identically zero and no link was ever refined (a long tube lit at one end: F2
    /// 79.8% relative L1 with 6 elements; 3.5% at ε = 0.005 with two points, experiments/empirical-1997.toml).
    pub fn default_points(self) -> usize {
        match self {
            Basis::Haar | Basis::F2 | Basis::F3 => 2,
            Basis::M2 => 3,
            Basis::M3 => 4,
        }
    }

    /// The smallest number of Gauss points per cell and side that integrates φ_i φ_j exactly (orthonormal
    /// under the rule): M for multiwavelets, 1 for flatlets.
    pub fn min_points(self) -> usize {
        if self.is_flatlet() { 1 } else { self.side() }
    }

    /// The 1-D function φ_i at t ∈ [0, 1].
    pub fn phi1(self, i: usize, t: f64) -> f64 {
        match (self, i) {
            (_, 0) => 1.0,
            (Basis::M2 | Basis::M3, 1) => SQRT3 * (2.0 * t - 1.0),
            (Basis::M3, 2) => SQRT5 * (6.0 * t * t - 6.0 * t + 1.0),
            (Basis::F2, 1) => {
                if t < 0.5 {
                    -1.0
                } else {
                    1.0
                }
            }
            (Basis::F3, _) => {
                let cell = ((t * 3.0).floor() as i64).clamp(0, 2) as usize;
                const A: f64 = 1.224_744_871_391_589; // √(3/2)
                const B: f64 = std::f64::consts::FRAC_1_SQRT_2;
                match i {
                    1 => [-A, 0.0, A][cell],
                    _ => [B, -2.0 * B, B][cell],
                }
            }
            _ => 0.0,
        }
    }

    /// All M² functions at (s, t), φ_{iM+j}(s, t) = φ_i(s) φ_j(t), into `out` (length at least M²).
    pub fn eval(self, s: f64, t: f64, out: &mut [f64]) {
        let m = self.side();
        let mut ps = [0.0; 3];
        let mut pt = [0.0; 3];
        for i in 0..m {
            ps[i] = self.phi1(i, s);
            pt[i] = self.phi1(i, t);
        }
        for i in 0..m {
            for j in 0..m {
                out[i * m + j] = ps[i] * pt[j];
            }
        }
    }

    /// The element rule in one dimension: `points` Gauss–Legendre points in each of the basis' cells
    /// ([`Basis::cells`]), as (node, weight) on [0, 1] with weights summing to 1.
    pub fn rule1(self, points: usize) -> Vec<(f64, f64)> {
        composite_rule(self.cells(), points)
    }

    /// The two-scale matrix of child `c` ∈ {0, 1} in one dimension, H^c_ij (row-major, M × M), by exact
    /// composite quadrature.
    pub fn two_scale1(self, c: usize) -> Vec<f64> {
        let m = self.side();
        let rule = composite_rule(6, 4);
        let mut h = vec![0.0; m * m];
        for i in 0..m {
            for j in 0..m {
                h[i * m + j] = rule
                    .iter()
                    .map(|&(u, w)| w * self.phi1(i, (u + c as f64) / 2.0) * self.phi1(j, u))
                    .sum();
            }
        }
        h
    }

    /// The two-scale operator of the quadtree's child (c_s, c_t) in two dimensions, H^{c_s} ⊗ H^{c_t}:
    /// entry (α, β) of the M² × M² row-major result is the parent's α against the child's β.
    pub fn two_scale(self, cs: usize, ct: usize) -> Vec<f64> {
        let m = self.side();
        let (hs, ht) = (self.two_scale1(cs), self.two_scale1(ct));
        let k = m * m;
        let mut h = vec![0.0; k * k];
        for i in 0..m {
            for j in 0..m {
                for p in 0..m {
                    for q in 0..m {
                        h[(i * m + j) * k + p * m + q] = hs[i * m + p] * ht[j * m + q];
                    }
                }
            }
        }
        h
    }
}

/// `cells` equal pieces of [0, 1], each with the `points`-point Gauss–Legendre rule; weights sum to 1.
pub fn composite_rule(cells: usize, points: usize) -> Vec<(f64, f64)> {
    let g = gauss_legendre::rule(points.max(1));
    let w = 1.0 / cells as f64;
    (0..cells)
        .flat_map(|c| g.iter().map(move |&(x, wx)| ((c as f64 + x) * w, wx * w)))
        .collect()
}

/// The two-scale operators of a basis for the four quadtree children, in the order of
/// [`radlab_scene::Polygon::split4`]'s children of a quad: (s, t) low-low, high-low, high-high, low-high.
#[derive(Clone, Debug)]
pub struct TwoScale {
    /// Functions per element.
    pub k: usize,
    /// H per child, row-major k × k (parent α, child β).
    pub h: [Vec<f64>; 4],
}

/// The child (c_s, c_t) of each quadtree child index of a quad.
pub const CHILD_CELLS: [(usize, usize); 4] = [(0, 0), (1, 0), (1, 1), (0, 1)];

impl TwoScale {
    /// The operators of `basis`.
    pub fn new(basis: Basis) -> Self {
        let h = CHILD_CELLS.map(|(cs, ct)| basis.two_scale(cs, ct));
        Self { k: basis.len(), h }
    }

    /// Push: the coefficients of the parent's function on child `c`, b^c_β = Σ_α H_αβ b_α.
    pub fn push(&self, c: usize, parent: &[f64], child: &mut [f64]) {
        let (k, h) = (self.k, &self.h[c]);
        for (b, out) in child.iter_mut().enumerate().take(k) {
            *out = (0..k).map(|a| h[a * k + b] * parent[a]).sum();
        }
    }

    /// Pull: the parent's coefficients from its four children's (L² projection),
    /// b_α = ¼ Σ_c Σ_β H^c_αβ b^c_β.
    pub fn pull(&self, children: [&[f64]; 4], parent: &mut [f64]) {
        let k = self.k;
        for (a, out) in parent.iter_mut().enumerate().take(k) {
            *out = 0.25
                * (0..4)
                    .map(|c| {
                        (0..k)
                            .map(|b| self.h[c][a * k + b] * children[c][b])
                            .sum::<f64>()
                    })
                    .sum::<f64>();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fixed pseudo-random sequence in [−1, 1) (no seed needed: any numbers will do).
    fn numbers(n: usize) -> Vec<f64> {
        let mut x = 0x9E37_79B9_7F4A_7C15_u64;
        (0..n)
            .map(|_| {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                (x >> 11) as f64 / (1u64 << 52) as f64 - 1.0
            })
            .collect()
    }

    /// (1/A) ∫ φ_α φ_β dA = δ_αβ on the unit square, by a fine composite rule (not the element rule).
    #[test]
    fn functions_are_orthonormal_under_the_mean() {
        for basis in Basis::ALL {
            let k = basis.len();
            let rule = composite_rule(6, 5);
            let mut gram = vec![0.0; k * k];
            let mut f = vec![0.0; k];
            for &(s, ws) in &rule {
                for &(t, wt) in &rule {
                    basis.eval(s, t, &mut f);
                    for a in 0..k {
                        for b in 0..k {
                            gram[a * k + b] += ws * wt * f[a] * f[b];
                        }
                    }
                }
            }
            for a in 0..k {
                for b in 0..k {
                    let want = if a == b { 1.0 } else { 0.0 };
                    assert!(
                        (gram[a * k + b] - want).abs() < 1e-13,
                        "{basis:?}: <{a},{b}> = {}",
                        gram[a * k + b]
                    );
                }
            }
            // The element rule at its minimum size is exact too.
            let r1 = basis.rule1(basis.min_points());
            for a in 0..k {
                let mut g = 0.0;
                for &(s, ws) in &r1 {
                    for &(t, wt) in &r1 {
                        basis.eval(s, t, &mut f);
                        g += ws * wt * f[a] * f[a];
                    }
                }
                assert!(
                    (g - 1.0).abs() < 1e-13,
                    "{basis:?} element rule: |φ_{a}|² = {g}"
                );
            }
        }
    }

    /// Push reproduces the parent's function on each child exactly at random points, the children's means
    /// average to the parent's mean, and pull after push returns the parent.
    #[test]
    fn push_reproduces_the_parent_and_pull_undoes_it() {
        for basis in Basis::ALL {
            let k = basis.len();
            let ts = TwoScale::new(basis);
            let parent = numbers(k);
            let mut kids = [vec![0.0; k], vec![0.0; k], vec![0.0; k], vec![0.0; k]];
            for (c, kid) in kids.iter_mut().enumerate() {
                ts.push(c, &parent, kid);
            }
            let pts = numbers(40);
            let (mut fp, mut fc) = (vec![0.0; k], vec![0.0; k]);
            for p in pts.chunks(2) {
                let (s, t) = (0.5 * (p[0] + 1.0), 0.5 * (p[1] + 1.0));
                let c = CHILD_CELLS
                    .iter()
                    .position(|&(cs, ct)| cs == (s >= 0.5) as usize && ct == (t >= 0.5) as usize)
                    .expect("a child");
                let (cs, ct) = CHILD_CELLS[c];
                basis.eval(s, t, &mut fp);
                basis.eval(2.0 * s - cs as f64, 2.0 * t - ct as f64, &mut fc);
                let vp: f64 = (0..k).map(|a| parent[a] * fp[a]).sum();
                let vc: f64 = (0..k).map(|a| kids[c][a] * fc[a]).sum();
                assert!(
                    (vp - vc).abs() < 1e-12,
                    "{basis:?} at ({s}, {t}): {vp} vs {vc}"
                );
            }
            let mean: f64 = kids.iter().map(|kid| kid[0]).sum::<f64>() / 4.0;
            assert!((mean - parent[0]).abs() < 1e-13);
            let mut back = vec![0.0; k];
            ts.pull([&kids[0], &kids[1], &kids[2], &kids[3]], &mut back);
            for a in 0..k {
                assert!(
                    (back[a] - parent[a]).abs() < 1e-13,
                    "{basis:?} pull∘push at {a}"
                );
            }
        }
    }

    /// The 1-D M3 relation has the closed form of the literature: row 2 of H⁰ is (0, −√15/4, ¼).
    #[test]
    fn m3_two_scale_matches_its_closed_form() {
        let h0 = Basis::M3.two_scale1(0);
        let want = [
            1.0,
            0.0,
            0.0,
            -SQRT3 / 2.0,
            0.5,
            0.0,
            0.0,
            -15f64.sqrt() / 4.0,
            0.25,
        ];
        for (a, b) in h0.iter().zip(want) {
            assert!((a - b).abs() < 1e-14, "{h0:?}");
        }
    }

    /// The irradiance on a plane from a parallel differential emitter at height d above (x₀, y₀), per unit
    /// intensity: E(x, y) = d² / (π (d² + r²)²) (the closed form of a differential area to a parallel
    /// differential area; Siegel & Howell).
    fn emitter(x: f64, y: f64) -> f64 {
        let (d, x0, y0) = (0.6, 0.3, 0.45);
        let r2 = (x - x0).powi(2) + (y - y0).powi(2);
        d * d / (std::f64::consts::PI * (d * d + r2).powi(2))
    }

    /// L² error of the projection of [`emitter`] onto `n` × `n` elements of the unit square.
    fn projection_error(basis: Basis, n: usize) -> f64 {
        let k = basis.len();
        let h = 1.0 / n as f64;
        // Coefficients by a rule exact for the basis and far finer than its order (composite per cell).
        let fine = composite_rule(6 * basis.cells(), 6);
        let (mut f, mut err2) = (vec![0.0; k], 0.0);
        for ex in 0..n {
            for ey in 0..n {
                let mut b = vec![0.0; k];
                for &(s, ws) in &fine {
                    for &(t, wt) in &fine {
                        basis.eval(s, t, &mut f);
                        let v = emitter((ex as f64 + s) * h, (ey as f64 + t) * h);
                        for a in 0..k {
                            b[a] += ws * wt * v * f[a];
                        }
                    }
                }
                for &(s, ws) in &fine {
                    for &(t, wt) in &fine {
                        basis.eval(s, t, &mut f);
                        let v = emitter((ex as f64 + s) * h, (ey as f64 + t) * h);
                        let p: f64 = (0..k).map(|a| b[a] * f[a]).sum();
                        err2 += ws * wt * h * h * (v - p).powi(2);
                    }
                }
            }
        }
        err2.sqrt()
    }

    /// The projection error of a smooth closed-form irradiance falls by 2^order per halving of the
    /// element: 2× for Haar and the flatlets, 4× for M2, 8× for M3 (Alpert 1993; Schröder & Hanrahan 1994
    /// observed the same rates). Measured from 16 to 32 to 64 elements per side; the rate must be within
    /// 10% of 2^order on the last halving (the asymptotic regime) and the first.
    #[test]
    fn projection_error_falls_at_the_basis_order() {
        for basis in Basis::ALL {
            let e: Vec<f64> = [8, 16, 32]
                .iter()
                .map(|&n| projection_error(basis, n))
                .collect();
            let want = 2f64.powi(basis.order() as i32);
            for w in e.windows(2) {
                let rate = w[0] / w[1];
                assert!(
                    (rate / want - 1.0).abs() < 0.1,
                    "{basis:?}: errors {e:?}, rate {rate}, want {want}"
                );
            }
        }
    }
}

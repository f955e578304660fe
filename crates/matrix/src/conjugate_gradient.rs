//! Preconditioned conjugate gradient (Hestenes & Stiefel 1952; Saad 2003, Algorithm 9.1) on the symmetric
//! form of the radiosity system (Cohen & Wallace 1993, ch. 5): row i multiplied by A_i/ρ_i,
//!
//! K B = b,   K_ij = (A_i/ρ_i) δ_ij − G_ij,   b_i = A_i E_i/ρ_i + Σ_{j fixed} G_ij E_j,
//!
//! over the free elements of each channel (ρ_i > 0); elements with ρ_i = 0 are fixed at B_i = E_i and moved to
//! the right-hand side. K is symmetric because G is (reciprocity, enforced by [`crate::assembly`]), and
//! positive definite for ρ < 1 by Gershgorin's theorem when rows of F' sum to at most 1:
//! K_ii − Σ_{j≠i} |K_ij| = A_i/ρ_i − Σ_j G_ij ≥ A_i (1/ρ_i − 1) > 0. The preconditioner is K's diagonal.
//!
//! The three channels run as three independent CG recurrences sharing each pass over G. The residual is
//! reported unscaled, r_i ρ_i / A_i = E_i + ρ_i Σ_j F'_ij B_j − B_i, in the area-weighted L1 norm of
//! [`crate::linear_system`]; when the recursively updated residual meets the stopping rule it is recomputed
//! from B before convergence is declared (and the recurrence restarted from it if it no longer does).

use radlab_method::SolveError;
use radlab_scene::Rgb;
use rayon::prelude::*;

use crate::linear_system::{StopRule, System, area_l1, gather};

/// The recurrence's vectors, per element and channel (zero in fixed channels).
#[derive(Clone)]
pub struct ConjugateGradient {
    mask: Vec<Rgb>,
    scale: Vec<Rgb>,
    inv_diag: Vec<Rgb>,
    r: Vec<Rgb>,
    p: Vec<Rgb>,
    q: Vec<Rgb>,
    rz: Rgb,
}

/// Per channel Σ_i u_i v_i.
fn dot(u: &[Rgb], v: &[Rgb]) -> Rgb {
    u.iter().zip(v).fold(Rgb::ZERO, |s, (&a, &b)| s + a * b)
}

/// Per channel a / b with 0 where b is 0.
fn ratio(a: Rgb, b: Rgb) -> Rgb {
    let f = |x: f64, y: f64| if y != 0.0 { x / y } else { 0.0 };
    Rgb::new(f(a.x, b.x), f(a.y, b.y), f(a.z, b.z))
}

impl ConjugateGradient {
    /// Starts from `x` (fixed channels must already hold E).
    pub fn new(sys: &System, x: &[Rgb]) -> Self {
        let n = sys.n;
        let mut mask = Vec::with_capacity(n);
        let mut scale = Vec::with_capacity(n);
        let mut inv_diag = Vec::with_capacity(n);
        for i in 0..n {
            let (a, rho, gii) = (sys.area[i], sys.rho[i], sys.diag(i));
            let per = |r: f64| -> (f64, f64, f64) {
                if r > 0.0 {
                    (1.0, a / r, 1.0 / (a / r - gii))
                } else {
                    (0.0, 0.0, 0.0)
                }
            };
            let (cx, cy, cz) = (per(rho.x), per(rho.y), per(rho.z));
            mask.push(Rgb::new(cx.0, cy.0, cz.0));
            scale.push(Rgb::new(cx.1, cy.1, cz.1));
            inv_diag.push(Rgb::new(cx.2, cy.2, cz.2));
        }
        let mut cg = Self {
            mask,
            scale,
            inv_diag,
            r: vec![Rgb::ZERO; n],
            p: vec![Rgb::ZERO; n],
            q: vec![Rgb::ZERO; n],
            rz: Rgb::ZERO,
        };
        cg.restart(sys, x);
        cg
    }

    /// r = b − K x from scratch, then p = M⁻¹ r.
    fn restart(&mut self, sys: &System, x: &[Rgb]) {
        let (mask, scale) = (&self.mask, &self.scale);
        self.r.par_iter_mut().enumerate().for_each(|(i, r)| {
            *r = mask[i] * (scale[i] * (sys.emission[i] - x[i]) + gather(sys.row(i), x));
        });
        for ((p, &r), &m) in self.p.iter_mut().zip(&self.r).zip(&self.inv_diag) {
            *p = m * r;
        }
        self.rz = dot(&self.r, &self.p);
    }

    /// Per channel (Σ_i A_i |unscaled residual_i|, Σ_i A_i |x_i|).
    fn residual(&self, sys: &System, x: &[Rgb]) -> (Rgb, Rgb) {
        let num = self
            .r
            .iter()
            .zip(sys.rho)
            .fold(Rgb::ZERO, |s, (&r, &rho)| s + rho * r.abs());
        (num, area_l1(sys.area, x))
    }

    /// One CG iteration on `x`. Returns the per-channel relative residual and whether `rule` is met by the
    /// recomputed (not only the recursive) residual.
    pub fn iterate(
        &mut self,
        sys: &System,
        x: &mut [Rgb],
        rule: &StopRule,
    ) -> Result<(Rgb, bool), SolveError> {
        let (mask, scale, p) = (&self.mask, &self.scale, &self.p);
        self.q.par_iter_mut().enumerate().for_each(|(i, q)| {
            *q = mask[i] * (scale[i] * p[i] - gather(sys.row(i), p));
        });
        let pq = dot(&self.p, &self.q);
        if pq.cmplt(Rgb::ZERO).any() || !pq.is_finite() {
            return Err(SolveError::Numerical(format!(
                "conjugate gradient found p·Kp = {pq} < 0: the symmetric system is not positive definite \
                 (a row of the form-factor matrix sums above 1/ρ); use iteration=gauss-seidel or finer \
                 visibility sampling"
            )));
        }
        let alpha = ratio(self.rz, pq);
        for ((xi, ri), (&pi, &qi)) in x
            .iter_mut()
            .zip(self.r.iter_mut())
            .zip(self.p.iter().zip(&self.q))
        {
            *xi += alpha * pi;
            *ri -= alpha * qi;
        }
        let (num, den) = self.residual(sys, x);
        let mut res = crate::linear_system::relative(num, den);
        let mut met = rule.met(res);
        if met {
            // Confirm with the true residual; restart the recurrence from it if rounding had drifted.
            self.restart(sys, x);
            let (num, den) = self.residual(sys, x);
            res = crate::linear_system::relative(num, den);
            met = rule.met(res);
            return Ok((res, met));
        }
        let rz_new = self
            .r
            .iter()
            .zip(&self.inv_diag)
            .fold(Rgb::ZERO, |s, (&r, &m)| s + r * m * r);
        let beta = ratio(rz_new, self.rz);
        for ((p, &r), &m) in self.p.iter_mut().zip(&self.r).zip(&self.inv_diag) {
            *p = m * r + beta * *p;
        }
        self.rz = rz_new;
        Ok((res, met))
    }
}

//! The discrete radiosity system every iteration solves, per RGB channel:
//!
//! (I − ρF') B = E,   F'_ij = G_ij / A_i,
//!
//! with G the symmetric area-weighted matrix of [`crate::assembly`] (the radiosity equation of Goral et al. 1984 with constant elements), and
//! the stopping rule shared by the three iterations. Norms are area-weighted L1, ‖v‖ = Σ_i A_i |v_i| per
//! channel (the power norm, and the norm of radlab's error metric). Because A_i F'_ij = A_j F'_ji and rows sum
//! to at most 1, ‖ρF'‖ ≤ ρ_max in this norm, so the error of any iterate is bounded by its residual:
//! ‖B − B*‖ ≤ ‖E + ρF'B − B‖ / (1 − ρ_max). The iteration therefore stops when the relative residual is below
//! `tolerance × (1 − ρ_max)`, which makes `tolerance` a bound on the relative error of B whatever the
//! reflectance.

use glam::DVec3;
use radlab_scene::Rgb;

/// The system's data, borrowed from the solver.
#[derive(Clone, Copy)]
pub struct System<'m> {
    /// Number of elements.
    pub n: usize,
    /// Row-major symmetric n × n matrix G.
    pub g: &'m [f64],
    /// Element areas.
    pub area: &'m [f64],
    /// Element reflectances.
    pub rho: &'m [Rgb],
    /// Element emissions.
    pub emission: &'m [Rgb],
}

impl System<'_> {
    /// Row i of G.
    pub fn row(&self, i: usize) -> &[f64] {
        &self.g[i * self.n..(i + 1) * self.n]
    }

    /// G_ii, the diagonal (reciprocity correction) term.
    pub fn diag(&self, i: usize) -> f64 {
        self.g[i * self.n + i]
    }
}

/// Σ_j G_ij B_j for one row: A_i times the irradiance at element i.
pub fn gather(row: &[f64], b: &[Rgb]) -> Rgb {
    row.iter()
        .zip(b)
        .fold(DVec3::ZERO, |s, (&g, &bj)| s + g * bj)
}

/// Per channel Σ_i A_i |v_i|.
pub fn area_l1(area: &[f64], v: &[Rgb]) -> Rgb {
    area.iter()
        .zip(v)
        .fold(DVec3::ZERO, |s, (&a, &x)| s + a * x.abs())
}

/// Per channel num / den, with 0/0 = 0 (a channel with no light has nothing to converge).
pub fn relative(num: Rgb, den: Rgb) -> Rgb {
    let r = |n: f64, d: f64| {
        if n == 0.0 {
            0.0
        } else if d > 0.0 {
            n / d
        } else {
            f64::INFINITY
        }
    };
    DVec3::new(r(num.x, den.x), r(num.y, den.y), r(num.z, den.z))
}

/// When to stop: relative residual below `tolerance × (1 − ρ_max)` in every channel.
#[derive(Clone, Copy, Debug)]
pub struct StopRule {
    threshold: Rgb,
}

impl StopRule {
    /// From the target relative error and the element reflectances.
    pub fn new(tolerance: f64, rho: &[Rgb]) -> Self {
        let rho_max = rho.iter().fold(DVec3::ZERO, |m, &r| m.max(r));
        Self {
            threshold: tolerance * (DVec3::ONE - rho_max),
        }
    }

    /// Whether a per-channel relative residual meets the rule.
    pub fn met(&self, residual: Rgb) -> bool {
        residual.cmple(self.threshold).all()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_handles_dark_channels() {
        let r = relative(DVec3::new(0.0, 1.0, 2.0), DVec3::new(0.0, 4.0, 0.0));
        assert_eq!(r, DVec3::new(0.0, 0.25, f64::INFINITY));
    }

    #[test]
    fn stop_rule_scales_with_reflectance() {
        let rule = StopRule::new(1e-4, &[DVec3::new(0.0, 0.9, 0.99)]);
        // Thresholds 1e-4, 1e-5 and 1e-6 (up to rounding of 1 − ρ).
        assert!(rule.met(DVec3::new(1e-4, 0.99e-5, 0.99e-6)));
        assert!(!rule.met(DVec3::new(1e-4, 0.99e-5, 1.01e-6)));
        assert!(!rule.met(DVec3::new(1.01e-4, 0.0, 0.0)));
    }
}

//! The cheap form-factor estimate refinement oracles use (Wallace, Elmquist & Haines 1989, the disc
//! approximation):
//!
//! F_ij ≈ A_j cosθ_i cosθ_j / (π r² + A_j)
//!
//! the point-to-disk factor of a disk of area A_j seen head-on, which stays bounded (≤ 1) as r → 0
//! (Wallace, Elmquist & Haines 1989). Cosines are clamped at 0 (one-sided surfaces).

use glam::DVec3;

/// Estimate of the form factor from a receiver at `xi` (normal `ni`) to a source of area `aj` at `xj`
/// (normal `nj`).
pub fn form_factor_estimate(xi: DVec3, ni: DVec3, xj: DVec3, nj: DVec3, aj: f64) -> f64 {
    let d = xj - xi;
    let r2 = d.length_squared();
    if r2 == 0.0 {
        return 0.0;
    }
    let r = r2.sqrt();
    let ci = (ni.dot(d) / r).max(0.0);
    let cj = (-nj.dot(d) / r).max(0.0);
    aj * ci * cj / (std::f64::consts::PI * r2 + aj)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_disk_closed_form_head_on() {
        // Differential area to a coaxial disk of radius R at distance h: F = R²/(h² + R²) exactly.
        let (r, h) = (0.7f64, 1.3f64);
        let a = std::f64::consts::PI * r * r;
        let f = form_factor_estimate(DVec3::ZERO, DVec3::Z, DVec3::new(0., 0., h), -DVec3::Z, a);
        assert!((f - r * r / (h * h + r * r)).abs() < 1e-14);
    }
}

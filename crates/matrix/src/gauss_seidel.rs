//! One Gauss–Seidel sweep for (I − ρF') B = E (Saad 2003, §4.1; used for radiosity by Cohen & Greenberg 1985):
//! elements are visited in order and each gathers from the newest values,
//!
//! B_i ← (E_i + ρ_i Σ_{j≠i} F'_ij B_j) / (1 − ρ_i F'_ii).
//!
//! Sequential by nature. The returned change Σ_i A_i |ΔB_i| bounds the residual of the new iterate: that
//! residual is ρ U ΔB (U the strict upper part of F'), and by reciprocity ‖ρU‖ ≤ ρ_max in the area-weighted
//! L1 norm.

use radlab_scene::Rgb;

use crate::linear_system::{System, area_l1, gather};

/// Sweeps `b` in place. Returns (Σ A |ΔB|, Σ A |B|) per channel, for the new iterate.
pub fn iterate(sys: &System, b: &mut [Rgb]) -> (Rgb, Rgb) {
    let mut change = Rgb::ZERO;
    for i in 0..sys.n {
        let a = sys.area[i];
        let gii = sys.diag(i);
        let off = gather(sys.row(i), b) - gii * b[i];
        let rho = sys.rho[i];
        let new = (sys.emission[i] + rho * off / a) / (Rgb::ONE - rho * (gii / a));
        change += a * (new - b[i]).abs();
        b[i] = new;
    }
    (change, area_l1(sys.area, b))
}

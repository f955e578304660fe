//! One Jacobi iteration for (I − ρF') B = E (Saad 2003, §4.1), every element gathering from the previous
//! iterate, with the small diagonal term of F' solved exactly:
//!
//! B_i^{k+1} = (E_i + ρ_i Σ_{j≠i} F'_ij B_j^k) / (1 − ρ_i F'_ii).
//!
//! Rows are independent, so they run in parallel; each row's sum runs in a fixed order, so the result does not
//! depend on the thread count. The returned change Σ_i A_i |B^{k+1} − B^k| is, up to the factor
//! (1 − ρ_i F'_ii) ≈ 1, the residual of B^k, and bounds the residual of B^{k+1} by ρ_max times itself.

use radlab_scene::Rgb;
use rayon::prelude::*;

use crate::linear_system::{System, area_l1, gather};

/// Replaces `b` by the next Jacobi iterate (using `next` as scratch). Returns (Σ A |ΔB|, Σ A |B|) per
/// channel, for the new iterate.
pub fn iterate(sys: &System, b: &mut Vec<Rgb>, next: &mut Vec<Rgb>) -> (Rgb, Rgb) {
    next.resize(sys.n, Rgb::ZERO);
    next.par_iter_mut().enumerate().for_each(|(i, out)| {
        let a = sys.area[i];
        let gii = sys.diag(i);
        let off = gather(sys.row(i), b) - gii * b[i];
        let rho = sys.rho[i];
        *out = (sys.emission[i] + rho * off / a) / (Rgb::ONE - rho * (gii / a));
    });
    let change: Rgb = sys
        .area
        .iter()
        .zip(next.iter().zip(b.iter()))
        .fold(Rgb::ZERO, |s, (&a, (&x, &y))| s + a * (x - y).abs());
    std::mem::swap(b, next);
    (change, area_l1(sys.area, b))
}

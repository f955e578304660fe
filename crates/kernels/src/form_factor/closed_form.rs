//! Closed-form form factors from Howell's catalogue (J. R. Howell, *A Catalog of Radiation Heat Transfer
//! Configuration Factors*, thermalradiation.net; also Siegel & Howell, *Thermal Radiation Heat Transfer*,
//! appendix C), the analytic references every quadrature and solver in radlab is tested against.
//!
//! Finite area to finite area (F from surface 1 to surface 2):
//! - **C-11**, parallel, directly opposed a × b rectangles at distance c, X = a/c, Y = b/c:
//!   F = 2/(πXY) · { ½ ln[(1+X²)(1+Y²)/(1+X²+Y²)] + X√(1+Y²) atan(X/√(1+Y²)) + Y√(1+X²) atan(Y/√(1+X²))
//!   − X atan X − Y atan Y }.
//! - **C-14**, perpendicular rectangles sharing an edge of length l, from the w × l one to the h × l one,
//!   W = w/l, H = h/l:
//!   F = 1/(πW) · { W atan(1/W) + H atan(1/H) − √(H²+W²) atan(1/√(H²+W²)) +
//!   ¼ ln( [(1+W²)(1+H²)/(1+W²+H²)] · [W²(1+W²+H²)/((1+W²)(W²+H²))]^{W²} ·
//!   [H²(1+W²+H²)/((1+H²)(W²+H²))]^{H²} ) }.
//! - **C-41**, coaxial parallel disks of radii r₁, r₂ at distance h, R_i = r_i/h, X = 1 + (1+R₂²)/R₁²:
//!   F = ½ [X − √(X² − 4 (R₂/R₁)²)], evaluated here as 2(R₂/R₁)² / [X + √(X² − 4(R₂/R₁)²)], the same number
//!   without the cancellation that ruins the first form for distant disks.
//!
//! Differential area to finite area (the exact point kernel's references):
//! - **B-3**, a differential area whose normal passes through the corner of a parallel a × b rectangle at
//!   height h, X = a/h, Y = b/h:
//!   F = 1/(2π) · [X/√(1+X²) atan(Y/√(1+X²)) + Y/√(1+Y²) atan(X/√(1+Y²))].
//! - A differential area at the centre of a coaxial parallel disk of radius r at height h: F = r²/(r²+h²)
//!   (the disk subtends a cone of half-angle θ, tan θ = r/h, and F = sin²θ).
//! - A differential area on the floor facing a perpendicular a (high) × b (wide) wall at distance c, with the
//!   wall's bottom edge on the floor and its side edge above the foot of the perpendicular from the element:
//!   F = 1/(2π) · [atan(b/c) − c/√(a²+c²) · atan(b/√(a²+c²))]. This is Lambert's contour integral worked out
//!   for that rectangle (the bottom edge contributes atan(b/c), the top edge the second term, the vertical
//!   edges nothing); it is the horizon-clipping reference.
//!
//! Every function takes lengths, not ratios, and needs them positive and finite (debug builds assert it).
//! The catalogue expressions lose relative accuracy when the surfaces are far apart (X, Y → 0) through
//! cancellation: about ε/(X² + Y²) for C-11, so better than 1e-9 for X, Y ≥ 1e-3.

use std::f64::consts::PI;

fn check(args: &[f64]) {
    debug_assert!(
        args.iter().all(|x| x.is_finite() && *x > 0.0),
        "closed-form form factors need positive finite lengths, got {args:?}"
    );
}

/// Howell C-11: form factor between two parallel, directly opposed (coaxial) `a` × `b` rectangles a
/// distance `c` apart. Symmetric: F₁₂ = F₂₁. Unit squares at distance 1 give 0.199825.
pub fn parallel_rectangles(a: f64, b: f64, c: f64) -> f64 {
    check(&[a, b, c]);
    let (x, y) = (a / c, b / c);
    let (x2, y2) = (x * x, y * y);
    let (sx, sy) = ((1.0 + x2).sqrt(), (1.0 + y2).sqrt());
    // ½ ln[(1+X²)(1+Y²)/(1+X²+Y²)] = ½ ln(1 + X²Y²/(1+X²+Y²)), exact for small X, Y.
    let log_term = 0.5 * (x2 * y2 / (1.0 + x2 + y2)).ln_1p();
    let bracket = log_term + x * sy * (x / sy).atan() + y * sx * (y / sx).atan()
        - x * x.atan()
        - y * y.atan();
    2.0 / (PI * x * y) * bracket
}

/// Howell C-14: form factor from a `w` × `l` rectangle to an `h` × `l` rectangle perpendicular to it, the two
/// sharing their edge of length `l`. Unit squares give 0.200044; the reverse factor is `w/h` times this
/// (reciprocity), i.e. `perpendicular_rectangles(h, w, l)`.
pub fn perpendicular_rectangles(w: f64, h: f64, l: f64) -> f64 {
    check(&[w, h, l]);
    let (ww, hh) = (w / l, h / l);
    let (w2, h2) = (ww * ww, hh * hh);
    let s = (w2 + h2).sqrt();
    // The logarithm of the product, as a sum of logarithms (the powers W², H² overflow otherwise).
    let ln = ((1.0 + w2) * (1.0 + h2) / (1.0 + w2 + h2)).ln()
        + w2 * (w2 * (1.0 + w2 + h2) / ((1.0 + w2) * (w2 + h2))).ln()
        + h2 * (h2 * (1.0 + w2 + h2) / ((1.0 + h2) * (w2 + h2))).ln();
    let bracket =
        ww * (1.0 / ww).atan() + hh * (1.0 / hh).atan() - s * (1.0 / s).atan() + 0.25 * ln;
    bracket / (PI * ww)
}

/// Howell C-41: form factor from a disk of radius `r1` to a coaxial parallel disk of radius `r2` a distance
/// `h` away. Unit disks at distance 1 give (3 − √5)/2; the reverse factor is `coaxial_disks(r2, r1, h)`.
pub fn coaxial_disks(r1: f64, r2: f64, h: f64) -> f64 {
    check(&[r1, r2, h]);
    let (big_r1, big_r2) = (r1 / h, r2 / h);
    let x = 1.0 + (1.0 + big_r2 * big_r2) / (big_r1 * big_r1);
    let q = (big_r2 / big_r1).powi(2);
    // ½[X − √(X² − 4q)] = 2q / [X + √(X² − 4q)]; X² − 4q = (stuff)² ≥ 0 exactly, clamp rounding.
    2.0 * q / (x + (x * x - 4.0 * q).max(0.0).sqrt())
}

/// Howell B-3: form factor from a differential area to a parallel `a` × `b` rectangle at height `h`, the
/// area's normal passing through one corner of the rectangle. Sums of four such terms give any parallel
/// rectangle seen from any point.
pub fn point_to_parallel_rectangle_corner(a: f64, b: f64, h: f64) -> f64 {
    check(&[a, b, h]);
    let (x, y) = (a / h, b / h);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * PI)
}

/// Form factor from a differential area to a coaxial parallel disk of radius `r` at height `h`:
/// r²/(r² + h²).
pub fn point_to_coaxial_disk(r: f64, h: f64) -> f64 {
    check(&[r, h]);
    r * r / (r * r + h * h)
}

/// Form factor from a differential area on a floor to a perpendicular wall at distance `c`: the wall rises
/// `a` above the floor from the floor's plane and extends `b` sideways from the point nearest the element.
/// The part of a wall below the floor's plane is invisible to the element, so this is also the answer for a
/// wall that extends below the floor (what horizon clipping must reproduce).
pub fn point_to_perpendicular_rectangle(a: f64, b: f64, c: f64) -> f64 {
    check(&[a, b, c]);
    let s = (a * a + c * c).sqrt();
    ((b / c).atan() - c / s * (b / s).atan()) / (2.0 * PI)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn howell_tabulated_values() {
        assert!((parallel_rectangles(1.0, 1.0, 1.0) - 0.199825).abs() < 5e-7);
        assert!((perpendicular_rectangles(1.0, 1.0, 1.0) - 0.200044).abs() < 5e-7);
        let golden = (3.0 - 5f64.sqrt()) / 2.0;
        assert!((coaxial_disks(1.0, 1.0, 1.0) - golden).abs() < 1e-15);
    }

    #[test]
    fn limits() {
        // Plates much larger than their gap see only each other.
        assert!((parallel_rectangles(1e4, 1e4, 1.0) - 1.0).abs() < 1e-3);
        assert!((coaxial_disks(1e4, 1e4, 1.0) - 1.0).abs() < 1e-3);
        // Far apart: F → A₂/(π c²).
        let f = parallel_rectangles(1.0, 2.0, 1e3);
        assert!((f / (2.0 / (PI * 1e6)) - 1.0).abs() < 1e-5, "{f}");
        let f = coaxial_disks(1.0, 2.0, 1e6);
        assert!((f / (4.0 / 1e12) - 1.0).abs() < 1e-9, "{f}");
        // A quarter-infinite wall takes a quarter of the hemisphere.
        assert!((point_to_perpendicular_rectangle(1e8, 1e8, 1.0) - 0.25).abs() < 1e-7);
    }
}

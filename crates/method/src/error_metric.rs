//! The error metric every method, test, bench and report is measured by: over the evaluation points x_i with
//! area weights w_i and RGB channels c,
//!
//! L1 = Σ_i w_i Σ_c |B_ic − R_ic| / Σ_i w_i Σ_c |R_ic|,   L2 = √(Σ_i w_i Σ_c (B_ic − R_ic)²) / √(Σ_i w_i Σ_c R_ic²),
//! max = max_{i,c} |B_ic − R_ic| / max(|R_ic|, f · R̄),   R̄ = Σ_i w_i Σ_c |R_ic| / (3 Σ_i w_i),
//!
//! relative errors with a floor in the max of f = [`MAX_ERROR_FLOOR`] = 2% of the area-mean reference radiosity
//! (the floor Mitsuba 3's tests use for relative errors, `|a − r| / max(|r|, 2e-2)`, made relative to the
//! scene's light level), so a point in deep shadow does not report thousands of per cent for an absolute error
//! that is small on the scene's scale. The noise floor is the same metric of the reference's own error: with
//! standard errors s_ic, E|N(0, s)| = s √(2/π) for L1 and s for L2; the max floor is 3 s / max(|R|, f R̄).

use radlab_scene::Rgb;

/// The floor of the max error, as a fraction of the area-mean reference radiosity: a point's relative error
/// is |B − R| / max(|R|, `MAX_ERROR_FLOOR` · R̄).
pub const MAX_ERROR_FLOOR: f64 = 0.02;

/// Relative errors.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Errors {
    /// Area-weighted relative L1.
    pub l1: f64,
    /// Area-weighted relative L2 (RMS).
    pub l2: f64,
    /// Maximum relative error (with the floor).
    pub max: f64,
}

fn mean_abs(reference: &[Rgb], weights: &[f64]) -> (f64, f64, f64) {
    let wsum: f64 = weights.iter().sum();
    let l1: f64 = reference
        .iter()
        .zip(weights)
        .map(|(r, w)| w * r.abs().element_sum())
        .sum();
    let l2: f64 = reference
        .iter()
        .zip(weights)
        .map(|(r, w)| w * r.length_squared())
        .sum();
    (l1, l2, l1 / (3.0 * wsum.max(f64::MIN_POSITIVE)))
}

/// The denominator floor of the max error: `MAX_ERROR_FLOOR` times the area-mean reference radiosity R̄.
pub fn max_error_floor(reference: &[Rgb], weights: &[f64]) -> f64 {
    (MAX_ERROR_FLOOR * mean_abs(reference, weights).2).max(f64::MIN_POSITIVE)
}

/// Errors of `values` against `reference`.
pub fn errors(values: &[Rgb], reference: &[Rgb], weights: &[f64]) -> Errors {
    debug_assert_eq!(values.len(), reference.len());
    let (r1, r2, _) = mean_abs(reference, weights);
    let floor = max_error_floor(reference, weights);
    let mut e1 = 0.0;
    let mut e2 = 0.0;
    let mut emax: f64 = 0.0;
    for ((b, r), w) in values.iter().zip(reference).zip(weights) {
        let d = *b - *r;
        e1 += w * d.abs().element_sum();
        e2 += w * d.length_squared();
        for c in 0..3 {
            emax = emax.max(d[c].abs() / r[c].abs().max(floor));
        }
    }
    let rel = |e: f64, r: f64| {
        if r > 0.0 {
            e / r
        } else if e == 0.0 {
            0.0
        } else {
            f64::INFINITY
        }
    };
    let e = Errors {
        l1: rel(e1, r1),
        l2: rel(e2.sqrt(), r2.sqrt()),
        max: emax,
    };
    if values.iter().any(|v| !v.is_finite()) {
        Errors {
            l1: f64::NAN,
            l2: f64::NAN,
            max: f64::NAN,
        }
    } else {
        e
    }
}

/// The noise floor of a reference with standard errors `std_error`.
pub fn noise_floor(reference: &[Rgb], std_error: &[Rgb], weights: &[f64]) -> Errors {
    let (r1, r2, _) = mean_abs(reference, weights);
    let floor = max_error_floor(reference, weights);
    let s1: f64 = std_error
        .iter()
        .zip(weights)
        .map(|(s, w)| w * s.element_sum())
        .sum::<f64>()
        * (2.0 / std::f64::consts::PI).sqrt();
    let s2: f64 = std_error
        .iter()
        .zip(weights)
        .map(|(s, w)| w * s.length_squared())
        .sum();
    let smax = std_error
        .iter()
        .zip(reference)
        .map(|(s, r)| {
            (0..3)
                .map(|c| 3.0 * s[c] / r[c].abs().max(floor))
                .fold(0.0, f64::max)
        })
        .fold(0.0, f64::max);
    let rel = |e: f64, r: f64| if r > 0.0 { e / r } else { 0.0 };
    Errors {
        l1: rel(s1, r1),
        l2: rel(s2.sqrt(), r2.sqrt()),
        max: smax,
    }
}

/// Errors of `solution` against `reference` at evaluation points (their weights are the area weights).
pub fn solution_errors(
    solution: &dyn crate::Solution,
    points: &[crate::EvalPoint],
    reference: &[Rgb],
) -> Errors {
    let values: Vec<Rgb> = points
        .iter()
        .map(|p| solution.radiosity_at(p.face, p.point))
        .collect();
    let weights: Vec<f64> = points.iter().map(|p| p.weight).collect();
    errors(&values, reference, &weights)
}

/// Errors of solution `a` against solution `b` (taken as the reference) at `points`.
pub fn difference(
    a: &dyn crate::Solution,
    b: &dyn crate::Solution,
    points: &[crate::EvalPoint],
) -> Errors {
    let reference: Vec<Rgb> = points
        .iter()
        .map(|p| b.radiosity_at(p.face, p.point))
        .collect();
    solution_errors(a, points, &reference)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_is_zero_and_uniform_scaling_is_relative() {
        let r = vec![Rgb::new(1.0, 2.0, 3.0), Rgb::new(0.5, 0.5, 0.5)];
        let w = vec![1.0, 3.0];
        assert_eq!(errors(&r, &r, &w), Errors::default());
        let b: Vec<Rgb> = r.iter().map(|x| *x * 1.1).collect();
        let e = errors(&b, &r, &w);
        assert!(
            (e.l1 - 0.1).abs() < 1e-12 && (e.l2 - 0.1).abs() < 1e-12 && (e.max - 0.1).abs() < 1e-12,
            "{e:?}"
        );
    }

    #[test]
    fn weights_matter() {
        let r = vec![Rgb::ONE, Rgb::ONE];
        let b = vec![Rgb::splat(2.0), Rgb::ONE];
        // Error 1 on the first point only; weight 1 of 4 → L1 = 0.25.
        let e = errors(&b, &r, &[1.0, 3.0]);
        assert!((e.l1 - 0.25).abs() < 1e-12);
        assert!((e.l2 - 0.5).abs() < 1e-12);
    }

    #[test]
    fn noise_floor_of_gaussian_noise_matches_measured_error() {
        // Draw B = R + N(0, s) and compare the measured L1 with the floor's prediction.
        let n = 20_000;
        let r = vec![Rgb::ONE; n];
        let s = vec![Rgb::splat(0.01); n];
        let w = vec![1.0; n];
        let mut rng = radlab_scene::sampling::rng(3, 0);
        let normal = |rng: &mut radlab_scene::sampling::Rng| {
            let (u1, u2) = (
                radlab_scene::sampling::uniform(rng).max(1e-300),
                radlab_scene::sampling::uniform(rng),
            );
            (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
        };
        let b: Vec<Rgb> = r
            .iter()
            .map(|x| *x + 0.01 * Rgb::new(normal(&mut rng), normal(&mut rng), normal(&mut rng)))
            .collect();
        let e = errors(&b, &r, &w);
        let f = noise_floor(&r, &s, &w);
        assert!((e.l1 / f.l1 - 1.0).abs() < 0.03, "{e:?} {f:?}");
        assert!((e.l2 / f.l2 - 1.0).abs() < 0.03, "{e:?} {f:?}");
    }
}

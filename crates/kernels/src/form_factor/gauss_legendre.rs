//! Gauss–Legendre quadrature on [0, 1]: the m nodes x_i are the roots of the Legendre polynomial P_m (mapped
//! from [−1, 1]), the weights w_i = 1 / [(1 − ξ_i²) P_m′(ξ_i)²] (halved for the unit interval), so that
//! Σ w_i f(x_i) = ∫₀¹ f exactly for polynomials of degree < 2m (Abramowitz & Stegun 25.4.29; Golub & Welsch
//! 1969). Roots are found by Newton's method on the three-term recurrence (k+1) P_{k+1} = (2k+1) ξ P_k − k P_{k−1},
//! started from Tricomi's estimate ξ_i ≈ cos(π (i + 3/4) / (m + 1/2)). Rules up to [`CACHED_ORDERS`] points
//! are computed once and shared.

use std::sync::OnceLock;

/// Rules with up to this many points are computed once and cached.
pub const CACHED_ORDERS: usize = 64;

/// The m-point rule as (node, weight) pairs on [0, 1], nodes ascending, weights summing to 1.
pub fn rule(m: usize) -> std::borrow::Cow<'static, [(f64, f64)]> {
    static CACHE: OnceLock<Vec<Vec<(f64, f64)>>> = OnceLock::new();
    if (1..=CACHED_ORDERS).contains(&m) {
        let all = CACHE.get_or_init(|| (1..=CACHED_ORDERS).map(compute).collect());
        std::borrow::Cow::Borrowed(&all[m - 1])
    } else {
        std::borrow::Cow::Owned(compute(m.max(1)))
    }
}

/// P_m(ξ) and P_m′(ξ).
fn legendre(m: usize, xi: f64) -> (f64, f64) {
    let (mut p_prev, mut p) = (1.0, xi);
    for k in 1..m {
        let next = ((2 * k + 1) as f64 * xi * p - k as f64 * p_prev) / (k + 1) as f64;
        p_prev = p;
        p = next;
    }
    // P_m′ = m (ξ P_m − P_{m−1}) / (ξ² − 1).
    let dp = m as f64 * (xi * p - p_prev) / (xi * xi - 1.0);
    (p, dp)
}

fn compute(m: usize) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = (0..m)
        .map(|i| {
            let mut xi = (std::f64::consts::PI * (i as f64 + 0.75) / (m as f64 + 0.5)).cos();
            for _ in 0..100 {
                let (p, dp) = legendre(m, xi);
                let step = p / dp;
                xi -= step;
                if step.abs() <= 1e-16 {
                    break;
                }
            }
            let (_, dp) = legendre(m, xi);
            let w = 1.0 / ((1.0 - xi * xi) * dp * dp);
            (0.5 * (1.0 - xi), w)
        })
        .collect();
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integrates_polynomials_of_degree_below_2m_exactly() {
        for m in [1, 2, 3, 5, 8, 16, 33, 64, 70] {
            let r = rule(m);
            assert_eq!(r.len(), m);
            let wsum: f64 = r.iter().map(|&(_, w)| w).sum();
            assert!((wsum - 1.0).abs() < 1e-14, "{m}: {wsum}");
            for deg in 0..(2 * m).min(40) {
                let q: f64 = r.iter().map(|&(x, w)| w * x.powi(deg as i32)).sum();
                let exact = 1.0 / (deg + 1) as f64;
                assert!(
                    (q - exact).abs() < 1e-14,
                    "m {m} degree {deg}: {q} vs {exact}"
                );
            }
            assert!(r.iter().all(|&(x, w)| x > 0.0 && x < 1.0 && w > 0.0));
        }
    }
}

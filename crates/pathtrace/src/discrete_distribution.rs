//! Sampling an index i with probability w_i / Σ_k w_k from non-negative weights, by inverting the cumulative
//! sum with a binary search (O(log n) per sample). Entries of zero weight are never chosen.

/// A discrete distribution over `0..n`.
#[derive(Clone, Debug, Default)]
pub(crate) struct Discrete {
    cdf: Vec<f64>,
    last_positive: usize,
}

impl Discrete {
    /// From weights (each finite and ≥ 0; others count as zero).
    pub(crate) fn new(weights: impl IntoIterator<Item = f64>) -> Self {
        let mut cdf = Vec::new();
        let mut total = 0.0;
        let mut last_positive = 0;
        for (i, w) in weights.into_iter().enumerate() {
            if w.is_finite() && w > 0.0 {
                total += w;
                last_positive = i;
            }
            cdf.push(total);
        }
        Self { cdf, last_positive }
    }

    /// Σ w.
    pub(crate) fn total(&self) -> f64 {
        self.cdf.last().copied().unwrap_or(0.0)
    }

    /// Whether nothing can be sampled (no positive weight).
    pub(crate) fn is_empty(&self) -> bool {
        self.total() <= 0.0 // weights are finite and ≥ 0, so the total is never NaN
    }

    /// The index whose cumulative interval contains `u · Σ w`, for `u` in [0, 1). The distribution must not
    /// be empty.
    pub(crate) fn sample(&self, u: f64) -> usize {
        let t = u * self.total();
        self.cdf
            .partition_point(|&c| c <= t)
            .min(self.last_positive)
    }

    /// Probability of index `i`.
    #[cfg(test)]
    pub(crate) fn prob(&self, i: usize) -> f64 {
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        (self.cdf[i] - lo) / self.total()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frequencies_follow_weights_and_zeros_are_skipped() {
        let d = Discrete::new([0.0, 1.0, 0.0, 3.0, 0.0]);
        assert_eq!(d.total(), 4.0);
        let m = 40_000;
        let mut counts = [0usize; 5];
        for k in 0..m {
            counts[d.sample((k as f64 + 0.5) / m as f64)] += 1;
        }
        assert_eq!(counts, [0, 10_000, 0, 30_000, 0]);
        assert_eq!(d.sample(0.0), 1);
        assert_eq!(d.sample(1.0 - f64::EPSILON), 3);
        assert!((d.prob(3) - 0.75).abs() < 1e-15 && d.prob(2) == 0.0);
        assert!(Discrete::new([0.0, 0.0]).is_empty());
    }
}

//! Running mean and variance of RGB samples, per channel: Welford's update for one sample and Chan, Golub &
//! LeVeque's (1979) pairwise merge for two partial sums,
//!
//! n = n_a + n_b,  δ = m_b − m_a,  m = m_a + δ n_b / n,  M2 = M2_a + M2_b + δ² n_a n_b / n,
//!
//! so chunks of samples computed on different threads combine, in a fixed order, into bit-identical results
//! whatever the thread count. The standard error of the mean is √(M2 / (n − 1) / n).

use radlab_scene::Rgb;

/// Count, mean and sum of squared deviations of a stream of RGB samples.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RunningStats {
    n: u64,
    mean: Rgb,
    m2: Rgb,
}

impl RunningStats {
    /// Adds one sample.
    pub fn push(&mut self, x: Rgb) {
        self.n += 1;
        let delta = x - self.mean;
        self.mean += delta / self.n as f64;
        self.m2 += delta * (x - self.mean);
    }

    /// Adds the samples summarised by `other` (the order of merges is part of the result's bits).
    pub fn merge(&mut self, other: &RunningStats) {
        if other.n == 0 {
            return;
        }
        if self.n == 0 {
            *self = *other;
            return;
        }
        let (na, nb) = (self.n as f64, other.n as f64);
        let n = na + nb;
        let delta = other.mean - self.mean;
        self.mean += delta * (nb / n);
        self.m2 += other.m2 + delta * delta * (na * nb / n);
        self.n += other.n;
    }

    /// Number of samples.
    #[cfg(test)]
    pub fn count(&self) -> u64 {
        self.n
    }

    /// Sample mean (zero before any sample).
    pub fn mean(&self) -> Rgb {
        self.mean
    }

    /// Standard error of the mean per channel; infinite with fewer than two samples.
    pub fn std_error(&self) -> Rgb {
        if self.n < 2 {
            return Rgb::splat(f64::INFINITY);
        }
        let n = self.n as f64;
        (self.m2.max(Rgb::ZERO) / ((n - 1.0) * n)).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_two_pass_formulas_and_merges_exactly() {
        let xs: Vec<Rgb> = (0..97)
            .map(|i| {
                let t = i as f64;
                Rgb::new((t * 0.37).sin() + 3.0, t * t * 1e-3, 1e6 + (t * 1.3).cos())
            })
            .collect();
        let n = xs.len() as f64;
        let mean: Rgb = xs.iter().copied().sum::<Rgb>() / n;
        let var: Rgb = xs.iter().map(|&x| (x - mean) * (x - mean)).sum::<Rgb>() / (n - 1.0);
        let se = (var / n).sqrt();

        let mut all = RunningStats::default();
        xs.iter().for_each(|&x| all.push(x));
        let mut merged = RunningStats::default();
        for chunk in xs.chunks(10) {
            let mut c = RunningStats::default();
            chunk.iter().for_each(|&x| c.push(x));
            merged.merge(&c);
        }
        for s in [all, merged] {
            assert_eq!(s.count(), 97);
            assert!((s.mean() - mean).abs().max_element() < 1e-9 * mean.abs().max_element());
            assert!(
                ((s.std_error() - se).abs() / se).max_element() < 1e-9,
                "{:?} {se:?}",
                s.std_error()
            );
        }
    }

    #[test]
    fn constant_samples_have_zero_error_and_one_sample_infinite() {
        let mut s = RunningStats::default();
        s.push(Rgb::splat(2.5));
        assert!(s.std_error().x.is_infinite());
        s.push(Rgb::splat(2.5));
        s.push(Rgb::splat(2.5));
        assert_eq!(s.std_error(), Rgb::ZERO);
        assert_eq!(s.mean(), Rgb::splat(2.5));
    }
}

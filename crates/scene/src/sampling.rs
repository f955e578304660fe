//! Deterministic random streams and the direction samplers every method shares.
//!
//! Each random stream is derived from (seed, stream index) by SplitMix64 mixing (Steele et al. 2014) into a
//! PCG64 generator (O'Neill 2014), so work item i draws the same numbers whatever thread runs it: results are
//! bit-identical for any thread count. Cosine-weighted hemisphere sampling uses Malley's method
//! (concentric disk, Shirley & Chiu 1997), pdf cosθ/π.

use glam::DVec3;
use rand::{Rng as _, SeedableRng};

/// The generator used everywhere in radlab.
pub type Rng = rand_pcg::Pcg64Mcg;

/// SplitMix64 finaliser: a bijective 64-bit mix.
pub fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The random stream for work item `stream` of a computation seeded with `seed`.
pub fn rng(seed: u64, stream: u64) -> Rng {
    let a = mix64(seed ^ mix64(stream));
    let b = mix64(a ^ 0x5851_F42D_4C95_7F2D ^ stream.rotate_left(32));
    Rng::from_seed(((a as u128) << 64 | b as u128).to_le_bytes())
}

/// A uniform number in [0, 1).
pub fn uniform(r: &mut Rng) -> f64 {
    r.random::<f64>()
}

/// An orthonormal basis (t, b, n) around unit `n` (Duff et al. 2017).
pub fn basis(n: DVec3) -> (DVec3, DVec3) {
    let s = 1.0f64.copysign(n.z);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    (
        DVec3::new(1.0 + s * n.x * n.x * a, s * b, -s * n.x),
        DVec3::new(b, s + n.y * n.y * a, -n.y),
    )
}

/// A point on the unit disk from two numbers in [0,1), area-preserving (concentric map).
pub fn concentric_disk(u1: f64, u2: f64) -> (f64, f64) {
    let (a, b) = (2.0 * u1 - 1.0, 2.0 * u2 - 1.0);
    if a == 0.0 && b == 0.0 {
        return (0.0, 0.0);
    }
    let (r, phi) = if a.abs() > b.abs() {
        (a, std::f64::consts::FRAC_PI_4 * (b / a))
    } else {
        (
            b,
            std::f64::consts::FRAC_PI_2 - std::f64::consts::FRAC_PI_4 * (a / b),
        )
    };
    (r * phi.cos(), r * phi.sin())
}

/// A cosine-distributed direction about unit `n` (pdf cosθ/π per steradian).
pub fn cosine_hemisphere(n: DVec3, u1: f64, u2: f64) -> DVec3 {
    let (x, y) = concentric_disk(u1, u2);
    let z = (1.0 - x * x - y * y).max(0.0).sqrt();
    let (t, b) = basis(n);
    (x * t + y * b + z * n).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_reproducible_and_distinct() {
        let a: Vec<f64> = (0..4)
            .map(|_| 0.0)
            .scan(rng(7, 3), |r, _| Some(uniform(r)))
            .collect();
        let b: Vec<f64> = (0..4)
            .map(|_| 0.0)
            .scan(rng(7, 3), |r, _| Some(uniform(r)))
            .collect();
        let c: Vec<f64> = (0..4)
            .map(|_| 0.0)
            .scan(rng(7, 4), |r, _| Some(uniform(r)))
            .collect();
        assert_eq!(a, b);
        assert_ne!(a, c);
    }

    #[test]
    fn basis_is_orthonormal() {
        for n in [
            DVec3::Z,
            -DVec3::Z,
            DVec3::new(1.0, 2.0, -3.0).normalize(),
            DVec3::X,
        ] {
            let (t, b) = basis(n);
            assert!(t.dot(b).abs() < 1e-12 && t.dot(n).abs() < 1e-12 && b.dot(n).abs() < 1e-12);
            assert!((t.length() - 1.0).abs() < 1e-12 && (b.length() - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn cosine_sampling_has_mean_cosine_two_thirds() {
        // E[cosθ] under pdf cosθ/π is 2/3.
        let n = DVec3::new(0.3, -0.2, 0.9).normalize();
        let mut r = rng(1, 0);
        let m = 200_000;
        let s: f64 = (0..m)
            .map(|_| cosine_hemisphere(n, uniform(&mut r), uniform(&mut r)).dot(n))
            .sum();
        assert!((s / m as f64 - 2.0 / 3.0).abs() < 3e-3);
    }
}

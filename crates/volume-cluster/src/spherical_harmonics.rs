//! Real spherical harmonics to order 2 (nine functions) and the clamped-cosine lobe in that basis, the
//! directional description the `directional` cluster transfer keeps (Sillion, Arvo, Westin & Greenberg 1991
//! used spherical harmonics for directional radiance; Ramamoorthi & Hanrahan 2001 showed that order 2 captures
//! irradiance, i.e. the clamped cosine, to within a few percent).
//!
//! Basis (unit direction ω = (x, y, z)): Y00 = 0.282095; Y1,{−1,0,1} = 0.488603 (y, z, x);
//! Y2,{−2,−1,1} = 1.092548 (xy, yz, xz); Y20 = 0.315392 (3z² − 1); Y22 = 0.546274 (x² − y²).
//!
//! The clamped cosine about axis a, f(ω) = max(0, a·ω), has coefficients f_lm = Â_l Y_lm(a) with
//! Â_0 = π, Â_1 = 2π/3, Â_2 = π/4 (Ramamoorthi & Hanrahan 2001, eq. 8), so Σ f_lm Y_lm(ω) reproduces it with
//! the order-2 truncation error: 1.0625 instead of 1 at ω = a, 0.094 instead of 0 at ω ⊥ a.

use std::f64::consts::PI;

use glam::DVec3;

/// Values of the nine basis functions at unit direction `w`.
pub fn basis(w: DVec3) -> [f64; 9] {
    let (x, y, z) = (w.x, w.y, w.z);
    [
        0.282_094_791_773_878_1,
        0.488_602_511_902_919_9 * y,
        0.488_602_511_902_919_9 * z,
        0.488_602_511_902_919_9 * x,
        1.092_548_430_592_079_2 * x * y,
        1.092_548_430_592_079_2 * y * z,
        0.315_391_565_252_520_05 * (3.0 * z * z - 1.0),
        1.092_548_430_592_079_2 * x * z,
        0.546_274_215_296_039_6 * (x * x - y * y),
    ]
}

/// Convolution constants Â_l of the clamped cosine, per coefficient.
const LOBE: [f64; 9] = [
    PI,
    2.0 * PI / 3.0,
    2.0 * PI / 3.0,
    2.0 * PI / 3.0,
    PI / 4.0,
    PI / 4.0,
    PI / 4.0,
    PI / 4.0,
    PI / 4.0,
];

/// Coefficients of max(0, axis·ω).
pub fn clamped_cosine(axis: DVec3) -> [f64; 9] {
    let y = basis(axis);
    std::array::from_fn(|i| LOBE[i] * y[i])
}

/// Σ c_i Y_i(w).
pub fn evaluate(c: &[f64; 9], w: DVec3) -> f64 {
    basis(w).iter().zip(c).map(|(y, c)| y * c).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use radlab_scene::sampling;

    #[test]
    fn basis_is_orthonormal_over_the_sphere() {
        // Monte Carlo over 2e5 uniform directions: ∫ Y_i Y_j dω = δ_ij within 4 standard errors.
        let mut rng = sampling::rng(3, 0);
        let n = 200_000;
        let mut gram = [[0.0; 9]; 9];
        for _ in 0..n {
            let z = 2.0 * sampling::uniform(&mut rng) - 1.0;
            let phi = 2.0 * PI * sampling::uniform(&mut rng);
            let s = (1.0 - z * z).sqrt();
            let y = basis(DVec3::new(s * phi.cos(), s * phi.sin(), z));
            for i in 0..9 {
                for j in 0..9 {
                    gram[i][j] += 4.0 * PI * y[i] * y[j] / n as f64;
                }
            }
        }
        for (i, row) in gram.iter().enumerate() {
            for (j, g) in row.iter().enumerate() {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((g - want).abs() < 0.03, "({i},{j}): {g}");
            }
        }
    }

    #[test]
    fn clamped_cosine_matches_its_legendre_truncation() {
        // Order-2 truncation of max(0, t): 1/4 + t/2 + (5/16)(3t² − 1)/2 at t = a·ω.
        let a = DVec3::new(0.3, -0.5, 0.8).normalize();
        let c = clamped_cosine(a);
        for w in [a, -a, DVec3::X, DVec3::new(1.0, 1.0, 0.0).normalize()] {
            let t = a.dot(w);
            let want = 0.25 + 0.5 * t + 5.0 / 32.0 * (3.0 * t * t - 1.0);
            assert!((evaluate(&c, w) - want).abs() < 1e-12);
        }
        assert!((evaluate(&c, a) - 1.0625).abs() < 1e-12);
    }
}

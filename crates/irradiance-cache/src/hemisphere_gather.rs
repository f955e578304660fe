//! One irradiance record's hemisphere gather: stratified cosine-weighted sampling of the hemisphere over the
//! normal n at x, with Ward & Heckbert's (1992) rotational and translational gradients from the same samples.
//!
//! The hemisphere is cut into M × N cells of equal projected solid angle π/(MN): θ_j^± with
//! sin²θ_j^− = j/M, sin²θ_j^+ = (j+1)/M, φ_k^± = 2πk/N, 2π(k+1)/N (N ≈ πM, Ward & Heckbert 1992). One jittered
//! direction per cell reaches a surface at distance r_jk whose radiance toward x is L_jk = B_jk/π. Then
//!
//! - irradiance: H = π/(MN) Σ L_jk = (1/MN) Σ B_jk;
//! - rotational gradient (turning n about an axis a changes H by a·∇_r per radian):
//!   ∇_r = π/(MN) Σ_jk L_jk tan θ_jk v(φ_jk), with v(φ) = n × u(φ), u(φ) the tangent direction at azimuth φ;
//! - translational gradient (moving x by δ in the tangent plane changes H by δ·∇_t): moving x shifts what each
//!   cell sees across the cells' walls. Across the wall θ = θ_j^− (j ≥ 1) the content moves by
//!   dθ = −δ·u cos θ / r, across φ = φ_k^− by dφ = −δ·v/(r sin θ); integrating the jump in L times the
//!   projected solid angle cos θ sin θ dθ dφ swept gives
//!   ∇_t = Σ_k u(φ_k) (2π/N) Σ_{j≥1} sin θ_j^− cos² θ_j^− (L_jk − L_{j−1,k}) / min(r_jk, r_{j−1,k}) +
//!   Σ_k v(φ_k^−) Σ_j (sin θ_j^+ − sin θ_j^−) (L_jk − L_{j,k−1}) / min(r_jk, r_{j,k−1}), with
//!   φ_k the cell's middle azimuth; the minimum distance of the two cells is Ward & Heckbert's conservative
//!   choice (the nearer surface moves faster across the wall).
//!
//! The record's radius is the harmonic mean distance R = MN / Σ 1/r_jk (Ward, Rubinstein & Clear 1988), rays
//! that leave the scene counting 1/r = 0. Each channel has its own gradients.

use glam::DVec3;
use radlab_scene::{
    Rgb,
    sampling::{self, Rng},
};

/// What a gather over the hemisphere found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gather {
    /// Irradiance H (W/m² per channel) over the hemisphere, from the gathered radiosities.
    pub irradiance: Rgb,
    /// Translational gradient per channel (r, g, b), in the tangent plane (W/m² per unit length).
    pub translational: [DVec3; 3],
    /// Rotational gradient per channel: the change of H per radian of turning the normal about each axis.
    pub rotational: [DVec3; 3],
    /// Harmonic mean distance to the surfaces seen (infinite if every ray left the scene).
    pub harmonic_distance: f64,
}

/// Cells in θ (M) and φ (N) for about `samples` directions: M = round(√(samples/π)), N = round(samples/M),
/// both at least 1.
pub fn strata(samples: u32) -> (u32, u32) {
    let m = ((samples as f64 / std::f64::consts::PI).sqrt().round() as u32).max(1);
    let n = ((samples as f64 / m as f64).round() as u32).max(1);
    (m, n)
}

/// Gathers over the hemisphere of unit normal `n` with `m` × `n_phi` cells: `trace(dir, rng)` returns the
/// distance to the surface seen along `dir` and the radiosity B it sends back toward the origin (`None` when
/// the ray leaves the scene).
pub fn gather(
    n: DVec3,
    m: u32,
    n_phi: u32,
    rng: &mut Rng,
    mut trace: impl FnMut(DVec3, &mut Rng) -> Option<(f64, Rgb)>,
) -> Gather {
    let (t, b) = sampling::basis(n);
    let (mf, nf) = (m as f64, n_phi as f64);
    let tau = std::f64::consts::TAU;
    let azimuth = |phi: f64| {
        (
            phi.cos() * t + phi.sin() * b,
            -phi.sin() * t + phi.cos() * b,
        )
    };
    // Per cell (j major): distance and B.
    let cells = (m * n_phi) as usize;
    let mut r = vec![f64::INFINITY; cells];
    let mut v = vec![Rgb::ZERO; cells];
    let mut sum = Rgb::ZERO;
    let mut inv_r = 0.0;
    let mut rot = [DVec3::ZERO; 3];
    for j in 0..m {
        for k in 0..n_phi {
            let s2 = (j as f64 + sampling::uniform(rng)) / mf;
            let phi = tau * (k as f64 + sampling::uniform(rng)) / nf;
            let (sin_t, cos_t) = (s2.sqrt(), (1.0 - s2).max(0.0).sqrt());
            let (u, w) = azimuth(phi);
            let dir = (sin_t * u + cos_t * n).normalize();
            let c = (j * n_phi + k) as usize;
            if let Some((dist, bv)) = trace(dir, rng) {
                r[c] = dist;
                v[c] = bv;
                sum += bv;
                if dist > 0.0 {
                    inv_r += 1.0 / dist;
                }
                if cos_t > 0.0 {
                    let tan = sin_t / cos_t;
                    for (ch, g) in rot.iter_mut().enumerate() {
                        *g += w * (bv[ch] * tan);
                    }
                }
            }
        }
    }
    let cellsf = mf * nf;
    // π/(MN) Σ L tan θ v with L = B/π.
    for g in &mut rot {
        *g /= cellsf;
    }
    let inv_pi = std::f64::consts::FRAC_1_PI;
    let mut trans = [DVec3::ZERO; 3];
    for k in 0..n_phi {
        let (u_mid, _) = azimuth(tau * (k as f64 + 0.5) / nf);
        let (_, v_wall) = azimuth(tau * k as f64 / nf);
        let km = (k + n_phi - 1) % n_phi;
        for j in 0..m {
            let c = (j * n_phi + k) as usize;
            if j >= 1 {
                let below = ((j - 1) * n_phi + k) as usize;
                let d = r[c].min(r[below]);
                if d.is_finite() && d > 0.0 {
                    let s2 = j as f64 / mf;
                    let coef = tau / nf * s2.sqrt() * (1.0 - s2) / d * inv_pi;
                    let dl = v[c] - v[below];
                    for (ch, g) in trans.iter_mut().enumerate() {
                        *g += u_mid * (coef * dl[ch]);
                    }
                }
            }
            if n_phi > 1 {
                let left = (j * n_phi + km) as usize;
                let d = r[c].min(r[left]);
                if d.is_finite() && d > 0.0 {
                    let coef = (((j + 1) as f64 / mf).sqrt() - (j as f64 / mf).sqrt()) / d * inv_pi;
                    let dl = v[c] - v[left];
                    for (ch, g) in trans.iter_mut().enumerate() {
                        *g += v_wall * (coef * dl[ch]);
                    }
                }
            }
        }
    }
    Gather {
        irradiance: sum / cellsf,
        translational: trans,
        rotational: rot,
        harmonic_distance: if inv_r > 0.0 {
            cellsf / inv_r
        } else {
            f64::INFINITY
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use radlab_kernels::form_factor::point_polygon;
    use radlab_scene::Polygon;

    /// A square of uniform radiosity 1 facing down at height 1 over [x0, x0+1] × [−0.5, 0.5]; nothing else.
    fn panel(x0: f64) -> Polygon {
        Polygon::quad(
            DVec3::new(x0, -0.5, 1.0),
            DVec3::new(x0, 0.5, 1.0),
            DVec3::new(x0 + 1.0, 0.5, 1.0),
            DVec3::new(x0 + 1.0, -0.5, 1.0),
        )
    }

    fn trace_panel(x: DVec3, x0: f64) -> impl FnMut(DVec3, &mut Rng) -> Option<(f64, Rgb)> {
        move |d: DVec3, _: &mut Rng| {
            if d.z <= 0.0 {
                return None;
            }
            let t = (1.0 - x.z) / d.z;
            let p = x + t * d;
            (p.x >= x0 && p.x <= x0 + 1.0 && p.y.abs() <= 0.5).then_some((t, Rgb::ONE))
        }
    }

    /// Irradiance from the panel of radiosity 1 (radiance 1/π) at x with normal n: H = B F = F.
    fn exact(x: DVec3, n: DVec3, x0: f64) -> f64 {
        point_polygon(x, n, &panel(x0))
    }

    #[test]
    fn irradiance_and_gradients_match_the_closed_form_of_a_panel() {
        // The panel is offset so H has a clear gradient along x at the origin.
        let x0 = 0.3;
        let n = DVec3::Z;
        let h = 1e-4;
        let h0 = exact(DVec3::ZERO, n, x0);
        let gx = (exact(DVec3::new(h, 0., 0.), n, x0) - exact(DVec3::new(-h, 0., 0.), n, x0))
            / (2.0 * h);
        let gy = (exact(DVec3::new(0., h, 0.), n, x0) - exact(DVec3::new(0., -h, 0.), n, x0))
            / (2.0 * h);
        // Turning n about the y axis by α tilts it toward +x: n' = (sin α, 0, cos α).
        let a: f64 = 1e-3;
        let ry = (exact(DVec3::ZERO, DVec3::new(a.sin(), 0., a.cos()), x0)
            - exact(DVec3::ZERO, DVec3::new(-a.sin(), 0., a.cos()), x0))
            / (2.0 * a);
        let (m, np) = strata(4096);
        let runs = 16;
        let (mut e, mut t, mut rr) = (Vec::new(), Vec::new(), Vec::new());
        for s in 0..runs {
            let mut rng = sampling::rng(3, s);
            let g = gather(n, m, np, &mut rng, trace_panel(DVec3::ZERO, x0));
            e.push(g.irradiance.x);
            t.push(g.translational[0]);
            rr.push(g.rotational[0]);
            assert!(g.harmonic_distance.is_finite());
        }
        let mean = |xs: &[f64]| xs.iter().sum::<f64>() / xs.len() as f64;
        let se = |xs: &[f64]| {
            let m = mean(xs);
            (xs.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / ((xs.len() - 1) * xs.len()) as f64)
                .sqrt()
        };
        // Irradiance: unbiased, within 4 standard errors.
        assert!(
            (mean(&e) - h0).abs() < 4.0 * se(&e) + 1e-12,
            "{} {h0}",
            mean(&e)
        );
        // Gradients: consistent estimates (their bias falls with the cell size); 3 % of the gradient at
        // 4096 directions plus 4 standard errors of the runs' mean.
        let tx: Vec<f64> = t.iter().map(|g| g.x).collect();
        let ty: Vec<f64> = t.iter().map(|g| g.y).collect();
        assert!(
            (mean(&tx) - gx).abs() < 0.03 * gx.abs() + 4.0 * se(&tx),
            "{} {gx}",
            mean(&tx)
        );
        assert!(
            (mean(&ty) - gy).abs() < 0.03 * gx.abs() + 4.0 * se(&ty),
            "{} {gy}",
            mean(&ty)
        );
        // The axis turning +z toward +x is +y.
        let ryv: Vec<f64> = rr.iter().map(|g| g.y).collect();
        assert!(
            (mean(&ryv) - ry).abs() < 0.03 * ry.abs() + 4.0 * se(&ryv),
            "{} {ry}",
            mean(&ryv)
        );
        assert!(t.iter().all(|g| g.z.abs() < 1e-12) && rr.iter().all(|g| g.z.abs() < 1e-12));
    }

    #[test]
    fn a_uniform_hemisphere_has_no_gradient() {
        let (m, np) = strata(256);
        assert_eq!((m, np), (9, 28));
        let mut rng = sampling::rng(1, 0);
        let g = gather(
            DVec3::new(0.3, 0.4, 0.5).normalize(),
            m,
            np,
            &mut rng,
            |_, _| Some((2.0, Rgb::splat(3.0))),
        );
        assert!((g.irradiance - Rgb::splat(3.0)).abs().max_element() < 1e-12);
        assert!((g.harmonic_distance - 2.0).abs() < 1e-12);
        for c in 0..3 {
            assert!(g.translational[c].length() < 1e-12, "{:?}", g.translational);
        }
        let none = gather(DVec3::Z, m, np, &mut rng, |_, _| None);
        assert!(none.harmonic_distance.is_infinite() && none.irradiance == Rgb::ZERO);
    }
}

//! Multiple importance sampling weights of bidirectional path tracing (Veach & Guibas 1995; Veach 1997, ch. 10).
//!
//! A path x̄ = v_0 … v_k (v_0 on an emitter, v_k the query point) can be built by k + 1 strategies: s light
//! vertices v_0 … v_{s−1} and t = k + 1 − s eye vertices v_s … v_k, s = 0 … k. Strategy s samples x̄ with the
//! area density p_s = Π_{j<s} p_L(v_j) · Π_{j≥s} p_E(v_j), where p_L(v_j) is the density of v_j generated
//! from the light side (emitter sampling for v_0, cosine-weighted scattering from v_{j−1} otherwise) and
//! p_E(v_j) from the eye side (v_k = x is fixed: p_E(v_k) = 1; cosine-weighted scattering from v_{j+1}
//! otherwise). The weight of strategy s is Veach's balance heuristic w_s = p_s / Σ_i p_i, or the power
//! heuristic w_s = p_s² / Σ_i p_i² (β = 2, Veach 1997 §9.2), computed with the ratios
//! p_{i+1}/p_i = p_L(v_i)/p_E(v_i) chained outward from the connection (as in pbrt-v3's `MISWeight`).
//!
//! **The impossible strategy.** t = 0 (a light subpath reaching the query point itself, s = k + 1) has
//! probability zero: x is a single point, hit by a light path with probability 0. It is left out of every
//! sum: the chain over eye vertices stops at v_{k−1} and never reaches v_k. Every other strategy samples
//! every path of length k with positive density in a diffuse world (no delta distributions), so the weights
//! of the k + 1 remaining strategies sum to 1 for each path, as unbiasedness needs. Russian roulette
//! probabilities are not part of the densities (they scale every strategy's estimate, not its weight's
//! validity: any weights summing to 1 over the strategies that can make a path keep the sum unbiased).
//!
//! **Strategies not used.** Light subpaths are cut at `max_light` vertices (bright enclosures would
//! otherwise cost s·t shadow rays per sample with s, t ~ 1/(1 − ρ)); strategies with s > `max_light` are
//! then never formed and take no share: the sums run over s = 0 … min(k, `max_light`). The strategies
//! s = 0 and s = 1 make every path, so each path keeps weights summing to 1.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// How the strategies that could have made a path share it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum Heuristic {
    /// w_s = p_s / Σ p_i: Veach's balance heuristic, provably close to the best of all weightings.
    Balance,
    /// w_s = p_s² / Σ p_i²: the power heuristic (β = 2), lower variance where one strategy is much better.
    /// The default.
    #[default]
    Power,
}

impl Heuristic {
    /// A density ratio raised to the heuristic's exponent (1 or 2).
    fn apply(self, r: f64) -> f64 {
        match self {
            Heuristic::Balance => r,
            Heuristic::Power => r * r,
        }
    }
}

/// The two area densities of a subpath vertex: `fwd`, from its own subpath's side; `rev`, from the other
/// side (for the connection's end vertices, as connected).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Densities {
    /// Area density with which its own subpath generated it.
    pub fwd: f64,
    /// Area density with which the other subpath would generate it.
    pub rev: f64,
}

/// The weight of the strategy that joined light vertices `light` = y_0 … y_{s−1} to eye vertices
/// `eye` = z_0 … z_{t−1} (z_0 the query point), given their densities, among the strategies with at most
/// `max_light` light vertices (the others are not used, so they take no share). Zero for t = 0 (impossible at
/// a point).
pub fn mis_weight(
    light: &[Densities],
    eye: &[Densities],
    heuristic: Heuristic,
    max_light: usize,
) -> f64 {
    if eye.is_empty() {
        return 0.0;
    }
    let ratio = |d: &Densities| {
        let r = heuristic.apply(d.rev / d.fwd);
        if r.is_finite() { r } else { 0.0 }
    };
    let mut sum = 0.0;
    let mut r = 1.0;
    // Strategies with more light vertices: v_{s}, v_{s+1}, … taken by the light side, up to v_{k−1} (z_1),
    // while they have at most `max_light` light vertices.
    let more = max_light.saturating_sub(light.len());
    for d in eye[1..].iter().rev().take(more) {
        r *= ratio(d);
        sum += r;
    }
    // Strategies with fewer light vertices: v_{s−1}, …, v_0 taken by the eye side.
    r = 1.0;
    for d in light.iter().rev() {
        r *= ratio(d);
        sum += r;
    }
    let w = 1.0 / (1.0 + sum);
    if w.is_finite() { w } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use radlab_scene::sampling;

    /// Densities p_L(v_j), p_E(v_j) for a path of k segments; p_E(v_k) = 1 (the query point).
    fn path(k: usize, rng: &mut radlab_scene::sampling::Rng) -> (Vec<f64>, Vec<f64>) {
        let mut draw = || 10f64.powf(4.0 * sampling::uniform(rng) - 2.0);
        let pl: Vec<f64> = (0..=k).map(|_| draw()).collect();
        let mut pe: Vec<f64> = (0..=k).map(|_| draw()).collect();
        pe[k] = 1.0;
        (pl, pe)
    }

    /// The subpaths of strategy s as the estimator sees them.
    fn split(pl: &[f64], pe: &[f64], s: usize) -> (Vec<Densities>, Vec<Densities>) {
        let k = pl.len() - 1;
        let light = (0..s)
            .map(|j| Densities {
                fwd: pl[j],
                rev: pe[j],
            })
            .collect();
        let eye = (s..=k)
            .rev()
            .map(|j| Densities {
                fwd: pe[j],
                rev: pl[j],
            })
            .collect();
        (light, eye)
    }

    #[test]
    fn weights_of_all_strategies_sum_to_one_and_match_the_definition() {
        let mut rng = sampling::rng(7, 0);
        for k in 1..=8 {
            for _ in 0..50 {
                let (pl, pe) = path(k, &mut rng);
                // p_s by its definition; t = 0 (s = k + 1) left out, and s > max_light when light subpaths are
                // cut.
                let p: Vec<f64> = (0..=k)
                    .map(|s| pl[..s].iter().product::<f64>() * pe[s..].iter().product::<f64>())
                    .collect();
                for (h, max_light) in [
                    (Heuristic::Balance, k),
                    (Heuristic::Power, k),
                    (Heuristic::Balance, 2),
                    (Heuristic::Power, 1),
                ] {
                    let beta = if h == Heuristic::Power { 2 } else { 1 };
                    let used = max_light.min(k);
                    let total: f64 = p[..=used].iter().map(|q| q.powi(beta)).sum();
                    let mut sum = 0.0;
                    for (s, p_s) in p[..=used].iter().enumerate() {
                        let (light, eye) = split(&pl, &pe, s);
                        let w = mis_weight(&light, &eye, h, max_light);
                        let want = p_s.powi(beta) / total;
                        assert!(
                            (w - want).abs() <= 1e-9 * want + 1e-15,
                            "k {k} s {s} {h:?}: {w} vs {want}"
                        );
                        sum += w;
                    }
                    assert!(
                        (sum - 1.0).abs() < 1e-12,
                        "k {k} {h:?}: weights sum to {sum}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_light_path_ending_at_the_query_point_has_weight_zero() {
        let light = [Densities { fwd: 1.0, rev: 1.0 }; 3];
        assert_eq!(mis_weight(&light, &[], Heuristic::Balance, 8), 0.0);
    }
}

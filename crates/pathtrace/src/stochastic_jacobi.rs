//! Stochastic Jacobi iteration for radiosity (Neumann, Feda, Kopp & Tobler 1995, "A new stochastic radiosity
//! method for highly complex scenes"; Bekaert 1999, §5.2, incremental shooting):
//!
//! ΔP^(0) = A E,   ΔP_j^(k+1) = (ρ_j / o_j) Σ_i F_ij ΔP_i^(k),   P = Σ_k ΔP^(k),
//!
//! with ΔP_i the power shot from uniform points of all of element i and o_i its open fraction (1 where nothing
//! is sealed): the open part's power divided by o_i, as the open-area system of mesh_radiosity.rs requires.
//!
//! Each transfer is estimated by shooting particles of equal scalar power u = Σ_e A_e Ē_e / N: generation k
//! shoots n_k particles, n_k the stochastic rounding of Ē(ΔP^(k))/u (so E[n_k u] = Ē(ΔP^(k)) exactly), each from
//! an element chosen with probability Ē(ΔP_i^(k)) / Ē(ΔP^(k)), at a uniform point, cosine-distributed,
//! carrying ΔP_i^(k) · u/Ē(ΔP_i^(k)). Given ΔP^(k), the expected power landing on j is Σ_i F_ij ΔP_i^(k), so
//! every generation — and the sum over generations — is unbiased. Generations end when the rounding leaves no
//! particle (the unshot power has decayed below about one particle's worth, stochastically).
//!
//! Particle k of generation g draws from stream k of a seed derived from (step seed, g); deposits are summed in
//! particle order, so results do not depend on the thread count.

use radlab_scene::{Rgb, sampling};
use rayon::prelude::*;

use crate::discrete_distribution::Discrete;
use crate::emitter_sampling::channel_mean;
use crate::mesh_radiosity::{Transport, derive_seed};
use crate::random_walk::WAVE;

/// One complete stochastic Jacobi solution with `particles` particles in the first generation. Returns the
/// incident power per element and the rays cast.
pub(crate) fn run(t: &Transport, particles: u64, seed: u64) -> (Vec<Rgb>, u64) {
    let n = t.mesh.len();
    let mut incident = vec![Rgb::ZERO; n];
    let mut next = vec![Rgb::ZERO; n];
    let mut touched: Vec<usize> = Vec::new();
    let mut rays = 0u64;
    let unit = t.emitted_power() / particles as f64;
    let mut unshot: Vec<(usize, Rgb)> = t
        .source_elements
        .iter()
        .map(|&e| (e, t.emission(e) * t.mesh.elements[e].area))
        .collect();
    for generation in 0..t.max_depth as u64 {
        if unshot.is_empty() {
            break;
        }
        let choose = Discrete::new(unshot.iter().map(|(_, p)| channel_mean(*p)));
        let gen_seed = derive_seed(seed, generation, 1);
        let count = if generation == 0 {
            particles
        } else {
            let expected = choose.total() / unit;
            let mut r = sampling::rng(gen_seed, u64::MAX);
            let whole = expected.floor();
            whole as u64 + u64::from(sampling::uniform(&mut r) < expected - whole)
        };
        if count == 0 {
            break;
        }
        let mut start = 0;
        while start < count {
            let wave = WAVE.min(count - start);
            let landed: Vec<Option<(usize, Rgb)>> = (start..start + wave)
                .into_par_iter()
                .map(|k| {
                    let mut rng = sampling::rng(gen_seed, k);
                    let (from, p) = unshot[choose.sample(sampling::uniform(&mut rng))];
                    let power = p * (unit / channel_mean(p));
                    t.shoot(from, &mut rng).map(|j| (j, power))
                })
                .collect();
            rays += wave;
            for (j, power) in landed.into_iter().flatten() {
                incident[j] += power;
                let reflected = t.reflected(j, power);
                if reflected.max_element() > 0.0 {
                    if next[j] == Rgb::ZERO {
                        touched.push(j);
                    }
                    next[j] += reflected;
                }
            }
            start += wave;
        }
        unshot = touched
            .drain(..)
            .map(|j| (j, std::mem::take(&mut next[j])))
            .collect();
    }
    (incident, rays)
}

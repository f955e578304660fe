//! Discrete shooting random walks with the collision estimator (Shirley 1991, "Radiosity via ray tracing";
//! Sbert 1993; Bekaert 1999, "Hierarchical and stochastic algorithms for radiosity", §4.3 and eq. 4.11).
//!
//! N particles each start on an emitting element e chosen with probability A_e Ē_e / Σ, at a uniform point,
//! carrying power A_e E_e / (N p_e) = E_e · (Σ/N) / Ē_e (scalar power Σ/N). A flight lands on element j
//! with probability F_ij; every landing tallies the particle's power into Φ_j (collision estimator). The
//! particle then survives with probability q = min(1, Ē(R)/Ē(P)) with R = ρ_j ⊙ P / o_j (o_j the element's
//! open fraction, 1 unless part of it is sealed; ρ_j / o_j for grey surfaces), its power becoming R / q (so its
//! scalar power does not change while q < 1), and is re-emitted from a *uniform* point of element j — which
//! makes the walk a Markov chain over elements with transition ρ_j F_jk / o_j, so its tallies are unbiased
//! estimates of the incident powers of the discrete open-area system (mesh_radiosity.rs),
//! E[Φ_j] = Σ_i F_ij P_i / o_i with P_i = o_i A_i B_i.
//!
//! Walks advance together one flight per round (a wavefront, [`WAVE`] walks at a time) so the deposits of a
//! round are summed in walk order: the same sums for any number of threads.

use radlab_scene::{Rgb, sampling};
use rayon::prelude::*;

use crate::emitter_sampling::channel_mean;
use crate::mesh_radiosity::Transport;

/// Walks traced together (bounds memory; fixed so results do not depend on the thread count).
pub(crate) const WAVE: u64 = 1 << 16;

/// What one flight produced: the deposit (element, power) if it landed, and the walker if it survived.
type Flight = (Option<(usize, Rgb)>, Option<Walker>);

struct Walker {
    rng: sampling::Rng,
    element: usize,
    power: Rgb,
}

/// Shoots `particles` walks, numbered from `first` (walk k draws from stream `first + k` of `seed`). Returns
/// the incident power per element and the rays cast.
pub(crate) fn shoot_walks(t: &Transport, particles: u64, first: u64, seed: u64) -> (Vec<Rgb>, u64) {
    let mut incident = vec![Rgb::ZERO; t.mesh.len()];
    let mut rays = 0u64;
    let unit = t.emitted_power() / particles as f64;
    let mut start = 0;
    while start < particles {
        let count = WAVE.min(particles - start);
        let mut alive: Vec<Walker> = (0..count)
            .into_par_iter()
            .map(|k| {
                let mut rng = sampling::rng(seed, first + start + k);
                let s = t.sources.sample(sampling::uniform(&mut rng));
                let element = t.source_elements[s];
                let e = t.emission(element);
                Walker {
                    rng,
                    element,
                    power: e * (unit / channel_mean(e)),
                }
            })
            .collect();
        let mut depth = 0;
        while !alive.is_empty() && depth < t.max_depth {
            rays += alive.len() as u64;
            let moved: Vec<Flight> = alive
                .into_par_iter()
                .map(|mut w| {
                    let Some(j) = t.shoot(w.element, &mut w.rng) else {
                        return (None, None);
                    };
                    let deposit = Some((j, w.power));
                    let kept = t.reflected(j, w.power);
                    let q = (channel_mean(kept) / channel_mean(w.power)).min(1.0);
                    if q.is_nan() || q <= 0.0 || sampling::uniform(&mut w.rng) >= q {
                        return (deposit, None);
                    }
                    w.power = kept / q;
                    w.element = j;
                    (deposit, Some(w))
                })
                .collect();
            alive = Vec::with_capacity(moved.len());
            for (deposit, next) in moved {
                if let Some((j, p)) = deposit {
                    incident[j] += p;
                }
                if let Some(w) = next {
                    alive.push(w);
                }
            }
            depth += 1;
        }
        start += count;
    }
    (incident, rays)
}

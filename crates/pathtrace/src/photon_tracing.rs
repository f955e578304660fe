//! Photon tracing (Jensen 1996, "Global illumination using photon maps", §2): photons leave the emitters with
//! probability proportional to power (face chosen by A_f Ē_f, a uniform point on it, a cosine-distributed
//! direction), each carrying Φ = E_f / p_A (the emitted power over the count, once divided by the number of
//! photons emitted, N_e). At every front-side hit the photon is stored, then survives with probability
//! q = max_c(ρ ⊙ Φ)_c / max_c Φ_c and carries ρ ⊙ Φ / q on (Russian roulette, Arvo & Kirk 1990: unbiased, no
//! depth cut but `max_depth`). A photon reaching a face's back is absorbed. Every stored photon's power sums,
//! over a surface region, to an unbiased estimate of N_e times the power arriving there.
//!
//! Photons are emitted in chunks of [`CHUNK`]; chunk c draws photon j from stream c·CHUNK + j, chunks are
//! traced in parallel and their photons kept in emission order until the map holds the requested number of
//! landings (the last emitted photon kept whole), so the map is the same for any number of threads.

use glam::DVec3;
use radlab_scene::{FaceId, Rgb, Scene, sampling};
use radlab_visibility::Accel;

use crate::EmitterSampler;
use rayon::prelude::*;

/// Photons emitted per chunk.
pub const CHUNK: u64 = 256;
/// Chunks traced together before checking whether the map is full.
const WAVE: u64 = 64;
/// Chunks emitted without any photon landing after which tracing stops (4,096 photons: the emitters light
/// nothing, e.g. they face away from every surface).
pub const EMPTY_CHUNKS: u64 = 16;

/// A stored photon.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Photon {
    /// Where it landed.
    pub point: DVec3,
    /// The normal of the face it landed on.
    pub normal: DVec3,
    /// The face it landed on.
    pub face: FaceId,
    /// Unit direction back toward where it came from.
    pub toward_source: DVec3,
    /// Power per channel, not yet divided by the number of photons emitted.
    pub power: Rgb,
    /// Reflections before it landed (0: straight from an emitter, i.e. direct light).
    pub bounces: u32,
}

/// Photons stored from one tracing run.
#[derive(Clone, Debug, Default)]
pub struct PhotonBatch {
    /// The photons, in emission order.
    pub photons: Vec<Photon>,
    /// Photons emitted (the estimator's N_e).
    pub emitted: u64,
}

/// Traces photons from `scene`'s emitters until at least `target` are stored (whole emitted photons), the first chunk
/// numbered `first_chunk`; `keep(bounces)` chooses which landings are stored. An empty batch when nothing
/// emits or no photon lands.
#[allow(clippy::too_many_arguments)]
pub fn trace_photons(
    scene: &Scene,
    accel: &Accel,
    emitters: &EmitterSampler,
    target: u64,
    first_chunk: u64,
    seed: u64,
    max_depth: u32,
    keep: &(dyn Fn(u32) -> bool + Sync),
) -> PhotonBatch {
    let mut batch = PhotonBatch::default();
    if emitters.is_empty() || target == 0 {
        return batch;
    }
    let mut chunk = first_chunk;
    // Caps so a scene whose photons never land cannot loop for ever: at most 1024 times the chunks a map
    // would need if every photon landed once, and none beyond [`EMPTY_CHUNKS`] chunks if none has landed.
    let max_chunks = target.div_ceil(CHUNK).saturating_mul(1 << 10).max(WAVE);
    while (batch.photons.len() as u64) < target
        && chunk - first_chunk < max_chunks
        && !(batch.photons.is_empty() && chunk - first_chunk >= EMPTY_CHUNKS)
    {
        // Chunks traced together: one at first, then about as many as the map still needs (at most WAVE).
        // Which chunks are kept does not depend on this, only how many are traced in vain.
        let done = chunk - first_chunk;
        let stored = batch.photons.len() as u64;
        let wave = if done == 0 || stored == 0 {
            if done == 0 { 1 } else { EMPTY_CHUNKS }
        } else {
            (target - stored)
                .div_ceil(stored.div_ceil(done))
                .clamp(1, WAVE)
        };
        let wave: Vec<(Vec<Photon>, Vec<usize>)> = (chunk..chunk + wave)
            .into_par_iter()
            .map(|c| trace_chunk(scene, accel, emitters, c, seed, max_depth, keep))
            .collect();
        'wave: for (photons, ends) in wave {
            // Photon by photon (each with all its landings), so the map stops at the first emitted photon
            // that fills it and N_e counts exactly the photons whose landings it holds.
            let mut start = 0;
            for end in ends {
                if (batch.photons.len() as u64) >= target {
                    break 'wave;
                }
                batch.photons.extend_from_slice(&photons[start..end]);
                batch.emitted += 1;
                start = end;
            }
            chunk += 1;
        }
    }
    batch
}

fn trace_chunk(
    scene: &Scene,
    accel: &Accel,
    emitters: &EmitterSampler,
    chunk: u64,
    seed: u64,
    max_depth: u32,
    keep: &(dyn Fn(u32) -> bool + Sync),
) -> (Vec<Photon>, Vec<usize>) {
    let mut out = Vec::new();
    let mut ends = Vec::with_capacity(CHUNK as usize);
    for j in 0..CHUNK {
        trace_one(
            scene,
            accel,
            emitters,
            chunk * CHUNK + j,
            seed,
            max_depth,
            keep,
            &mut out,
        );
        ends.push(out.len());
    }
    (out, ends)
}

/// Traces emitted photon `index`, appending its landings to `out`.
#[allow(clippy::too_many_arguments)]
fn trace_one(
    scene: &Scene,
    accel: &Accel,
    emitters: &EmitterSampler,
    index: u64,
    seed: u64,
    max_depth: u32,
    keep: &(dyn Fn(u32) -> bool + Sync),
    out: &mut Vec<Photon>,
) {
    let mut rng = sampling::rng(seed, index);
    let (u0, u1, u2) = (
        sampling::uniform(&mut rng),
        sampling::uniform(&mut rng),
        sampling::uniform(&mut rng),
    );
    let Some(light) = emitters.sample(u0, u1, u2) else {
        return;
    };
    let mut power = scene.emission(light.face) / light.pdf_area;
    let (mut face, mut x) = (light.face, light.point);
    let mut n = scene.faces[face].normal;
    for bounces in 0..max_depth {
        let dir = sampling::cosine_hemisphere(
            n,
            sampling::uniform(&mut rng),
            sampling::uniform(&mut rng),
        );
        let Some(hit) = accel.intersect_from(face, x, dir) else {
            break;
        };
        let nh = scene.faces[hit.face].normal;
        if !(-nh.dot(dir) > 0.0) {
            break; // a back: absorbed
        }
        if keep(bounces) {
            out.push(Photon {
                point: hit.point,
                normal: nh,
                face: hit.face,
                toward_source: -dir,
                power,
                bounces,
            });
        }
        let reflected = power * scene.reflectance(hit.face);
        let q = (reflected.max_element() / power.max_element()).min(1.0);
        if !(q > 0.0) || sampling::uniform(&mut rng) >= q {
            break;
        }
        power = reflected / q;
        (face, x, n) = (hit.face, hit.point, nh);
    }
}

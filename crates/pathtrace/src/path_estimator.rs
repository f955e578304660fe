//! One sample of the radiosity leaving a surface point: the path-tracing estimator every Monte Carlo method
//! here shares (the per-point reference and camera path tracing).
//!
//! Radiosity at x satisfies B(x) = E(x) + ρ(x) H(x), H(x) = ∫_Ω B(y(ω))/π cos θ_x dω over the hemisphere
//! of x's normal (the radiosity equation written over directions, Kajiya 1986; B/π is the radiance of a diffuse surface). At each
//! path vertex x_k, with throughput T_k:
//!
//! - **next-event estimation**: a point y on an emitter, area density p_A (emitter_sampling.rs), adds
//!   T_k ρ_k · E(y)/π · cos θ_x cos θ_y / r² · V(x,y) / p_A · w_light;
//! - **hemisphere sampling**: a cosine-distributed direction (pdf cos θ_x/π, so the estimator of H is B(y)
//!   itself) reaches y; its emission adds T_{k+1} E(y) · w_hemi, and the walk continues from y;
//! - the weights are Veach's power heuristic (Veach 1997, §9.2.1, eq. 9.13),
//!   w_light = p_l² / (p_l² + p_h²), w_hemi = p_h² / (p_l² + p_h²), with both densities per unit solid angle
//!   (p_l = p_A r² / cos θ_y, p_h = cos θ_x / π), so the two strategies sum to an unbiased direct term;
//! - **Russian roulette** (Arvo & Kirk 1990): the walk continues with probability q = max_c(T ρ)_c / max_c T_c
//!   (the albedo for grey surfaces) and divides by q, so T stays bounded by 1 and the estimator stays unbiased
//!   for any ρ < 1: at ρ → 0.999 paths just get longer (mean 1/(1 − ρ) vertices), never cut.
//!
//! Surfaces are one-sided, as in every radlab method: a face emits and reflects from its front only; a ray
//! reaching a face's back is absorbed (the back's radiosity is 0). A point on an emitter counts its own E.
//! `max_depth` caps the number of segments of a path (a safety net; with the default the bias it could
//! cause, at most ρ_max^max_depth relative, is far below any reported standard error).

use glam::DVec3;
use radlab_scene::{
    FaceId, Rgb, Scene,
    sampling::{self, Rng},
};
use radlab_visibility::Accel;
use serde::{Deserialize, Serialize};

use crate::emitter_sampling::EmitterSampler;

const INV_PI: f64 = std::f64::consts::FRAC_1_PI;

/// How the light arriving directly from emitters is estimated at each path vertex.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum DirectSampling {
    /// Next-event estimation and hemisphere sampling combined by the power heuristic (Veach 1997): robust
    /// for small bright emitters and for receivers close to large ones. The default.
    #[default]
    Mis,
    /// Next-event estimation only (emission reached by hemisphere rays is not counted): low noise for small
    /// emitters, noisy where a receiver nearly touches an emitter.
    NextEvent,
    /// Hemisphere sampling only (no shadow rays): pure path tracing; very noisy for small emitters.
    Hemisphere,
}

/// Power heuristic weight of a strategy with density `a` against one with density `b` (β = 2).
fn power_heuristic(a: f64, b: f64) -> f64 {
    if a.is_nan() || a <= 0.0 {
        return 0.0;
    }
    let r = b / a;
    let w = 1.0 / (1.0 + r * r);
    if w.is_finite() { w } else { 0.0 }
}

/// The shared path estimator for one scene: samples of the radiosity leaving a surface point (the walk
/// described in the module documentation), of its reflected part, and of the direct irradiance by next-event
/// estimation alone. Other Monte Carlo crates (irradiance caching, photon maps) reuse it for the parts of their
/// estimates that are plain path tracing.
pub struct PathEstimator<'a> {
    scene: &'a Scene,
    accel: &'a Accel,
    emitters: EmitterSampler,
    max_depth: u32,
    direct: DirectSampling,
}

impl<'a> PathEstimator<'a> {
    /// The estimator for `scene` through `accel`: paths of at most `max_depth` segments, direct light at each
    /// vertex sampled as `direct` says.
    pub fn new(scene: &'a Scene, accel: &'a Accel, max_depth: u32, direct: DirectSampling) -> Self {
        Self {
            scene,
            accel,
            emitters: EmitterSampler::new(scene),
            max_depth,
            direct,
        }
    }

    /// One unbiased sample of the radiosity leaving point `x` of face `face`, gathering over the hemisphere of
    /// unit normal `n`.
    pub fn radiosity(&self, face: FaceId, x: DVec3, n: DVec3, rng: &mut Rng) -> Rgb {
        self.walk(self.scene.emission(face), face, x, n, rng)
    }

    /// One unbiased sample of the radiosity that point `x` of face `face` reflects, ρ(x) H(x): the radiosity
    /// without the point's own emission E(x).
    pub fn reflected_radiosity(&self, face: FaceId, x: DVec3, n: DVec3, rng: &mut Rng) -> Rgb {
        self.walk(Rgb::ZERO, face, x, n, rng)
    }

    /// One unbiased sample of the irradiance arriving at point `x` of face `face` (unit normal `n`) directly
    /// from the emitters, by the estimator's `direct` strategy: next-event estimation (one shadow ray,
    /// E(y)/π cos θ_x cos θ_y / r² V(x, y) / p_A(y)) and/or one cosine-distributed ray whose emitter adds E(y),
    /// combined by the power heuristic under `mis`. Zero when the scene has no emitter.
    pub fn direct_irradiance(&self, face: FaceId, x: DVec3, n: DVec3, rng: &mut Rng) -> Rgb {
        let mut h = Rgb::ZERO;
        if self.direct != DirectSampling::Hemisphere {
            h += self.next_event(face, x, n, rng);
        }
        if self.direct != DirectSampling::NextEvent {
            let dir =
                sampling::cosine_hemisphere(n, sampling::uniform(rng), sampling::uniform(rng));
            if let Some((e, w)) = self
                .accel
                .intersect_from(face, x, dir)
                .and_then(|hit| self.emission_seen(n, dir, &hit))
            {
                h += e * w;
            }
        }
        h
    }

    /// The emission a cosine-sampled ray along `dir` from a point of normal `n` meets at `hit`, and its MIS
    /// weight against next-event estimation (1 unless `mis`); `None` at a back or a non-emitter.
    fn emission_seen(
        &self,
        n: DVec3,
        dir: DVec3,
        hit: &radlab_visibility::Hit,
    ) -> Option<(Rgb, f64)> {
        let cos_y = -self.scene.faces[hit.face].normal.dot(dir);
        let e = self.scene.emission(hit.face);
        if !(cos_y > 0.0) || e.max_element() <= 0.0 {
            return None;
        }
        let w = if self.direct == DirectSampling::Mis {
            let p_hemi = n.dot(dir).max(0.0) * INV_PI;
            let p_light = self.emitters.pdf_area(hit.face) * hit.t * hit.t / cos_y;
            power_heuristic(p_hemi, p_light)
        } else {
            1.0
        };
        Some((e, w))
    }

    /// The walk from (`face`, `x`, `n`) adding to `b`.
    fn walk(&self, mut b: Rgb, face: FaceId, x: DVec3, n: DVec3, rng: &mut Rng) -> Rgb {
        let scene = self.scene;
        let mut throughput = Rgb::ONE;
        let (mut f, mut x, mut n) = (face, x, n);
        for _ in 0..self.max_depth {
            let reflected = throughput * scene.reflectance(f);
            let keep = reflected.max_element();
            if keep.is_nan() || keep <= 0.0 {
                break;
            }
            if self.direct != DirectSampling::Hemisphere {
                b += reflected * self.next_event(f, x, n, rng);
            }
            // Russian roulette before spending the ray.
            let q = (keep / throughput.max_element()).min(1.0);
            if sampling::uniform(rng) >= q {
                break;
            }
            throughput = reflected / q;
            let dir =
                sampling::cosine_hemisphere(n, sampling::uniform(rng), sampling::uniform(rng));
            let Some(hit) = self.accel.intersect_from(f, x, dir) else {
                break;
            };
            let normal = scene.faces[hit.face].normal;
            let cos_y = -normal.dot(dir);
            if cos_y.is_nan() || cos_y <= 0.0 {
                break; // the back of a face: absorbed
            }
            if self.direct != DirectSampling::NextEvent
                && let Some((e, w)) = self.emission_seen(n, dir, &hit)
            {
                b += throughput * e * w;
            }
            (f, x, n) = (hit.face, hit.point, normal);
        }
        b
    }

    /// Irradiance estimate H from one emitter sample, weighted for MIS (without the ρ factor).
    fn next_event(&self, f: FaceId, x: DVec3, n: DVec3, rng: &mut Rng) -> Rgb {
        let (u0, u1, u2) = (
            sampling::uniform(rng),
            sampling::uniform(rng),
            sampling::uniform(rng),
        );
        let Some(light) = self.emitters.sample(u0, u1, u2) else {
            return Rgb::ZERO;
        };
        if light.face == f {
            return Rgb::ZERO;
        }
        let d = light.point - x;
        let r2 = d.length_squared();
        if r2.is_nan() || r2 <= 0.0 {
            return Rgb::ZERO;
        }
        let dir = d / r2.sqrt();
        let cos_x = n.dot(dir);
        let cos_y = -self.scene.faces[light.face].normal.dot(dir);
        if !(cos_x > 0.0 && cos_y > 0.0) {
            return Rgb::ZERO;
        }
        if !self.accel.visible_between(x, f, light.point, light.face) {
            return Rgb::ZERO;
        }
        let w = if self.direct == DirectSampling::Mis {
            let p_light = light.pdf_area * r2 / cos_y;
            power_heuristic(p_light, cos_x * INV_PI)
        } else {
            1.0
        };
        self.scene.emission(light.face) * (cos_x * cos_y * INV_PI / (r2 * light.pdf_area) * w)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn power_heuristic_weights_sum_to_one() {
        for (a, b) in [(1.0, 2.0), (1e-9, 3.0), (5.0, 0.0), (0.3, 0.3)] {
            let s = power_heuristic(a, b) + power_heuristic(b, a);
            assert!((s - 1.0).abs() < 1e-12, "{a} {b} {s}");
        }
        assert_eq!(power_heuristic(0.0, 1.0), 0.0);
        assert_eq!(power_heuristic(1.0, f64::INFINITY), 0.0);
    }
}

//! Area sampling of the emitters for next-event estimation: an emitting face f is chosen with probability
//! proportional to its power A_f Ē_f (Ē the mean over RGB channels), then a point uniformly over its area,
//! so the area density of a light sample is p_A(y) = Ē_f / Σ_g A_g Ē_g on every emitter (Shirley, Wang &
//! Zimmerman 1996, "Monte Carlo techniques for direct lighting calculations"). The same density is what
//! multiple importance sampling needs when a hemisphere-sampled ray happens to hit an emitter.

use glam::DVec3;
use radlab_scene::{AreaSampler, FaceId, Rgb, Scene};

use crate::discrete_distribution::Discrete;

/// Mean of the three channels: the scalar used to choose by power.
pub(crate) fn channel_mean(c: Rgb) -> f64 {
    (c.x + c.y + c.z) / 3.0
}

/// A light sample.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// The emitting face.
    pub face: FaceId,
    /// A point on it.
    pub point: DVec3,
    /// Area density of having chosen that point (1/m²).
    pub pdf_area: f64,
}

/// The scene's emitters, ready for sampling.
#[derive(Clone, Debug)]
pub struct EmitterSampler {
    faces: Vec<FaceId>,
    /// Per emitter, its polygon's area sampler (built once, not per sample).
    samplers: Vec<AreaSampler>,
    choose: Discrete,
    /// Ē_f / total power (the area density) for emitting faces, for lookup from any face.
    density: Vec<(FaceId, f64)>,
}

impl EmitterSampler {
    /// Collects the emitting faces of `scene`.
    pub fn new(scene: &Scene) -> Self {
        let faces = scene.emitters();
        let choose = Discrete::new(
            faces
                .iter()
                .map(|&f| scene.faces[f].area * channel_mean(scene.emission(f))),
        );
        let total = choose.total();
        let density = faces
            .iter()
            .map(|&f| {
                let d = if total > 0.0 {
                    channel_mean(scene.emission(f)) / total
                } else {
                    0.0
                };
                (f, d)
            })
            .collect();
        let samplers = faces
            .iter()
            .map(|&f| AreaSampler::new(scene.polygon(f)))
            .collect();
        Self {
            faces,
            samplers,
            choose,
            density,
        }
    }

    /// Whether there is nothing to sample (no emitter with positive power).
    pub fn is_empty(&self) -> bool {
        self.choose.is_empty()
    }

    /// A point on an emitter from three numbers in [0, 1).
    pub fn sample(&self, u0: f64, u1: f64, u2: f64) -> Option<LightSample> {
        if self.is_empty() {
            return None;
        }
        let k = self.choose.sample(u0);
        let face = self.faces[k];
        Some(LightSample {
            face,
            point: self.samplers[k].sample(u1, u2),
            pdf_area: self.density[k].1,
        })
    }

    /// Area density with which [`EmitterSampler::sample`] produces points on `face` (0 for non-emitters).
    pub fn pdf_area(&self, face: FaceId) -> f64 {
        match self.density.binary_search_by_key(&face, |&(f, _)| f) {
            Ok(k) => self.density[k].1,
            Err(_) => 0.0,
        }
    }
}

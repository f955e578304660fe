//! Final gather: the radiosity at a query point recomputed from a finite-element solution by one more
//! application of the radiosity equation (Lischinski, Tampieri & Greenberg 1993; Cohen & Wallace 1993, "Radiosity and Realistic Image
//! Synthesis", ch. 9; Lischinski, Tampieri & Greenberg 1993 use it for their displayed radiosity):
//!
//! B(x) = E(x) + ρ(x) Σ_j F_{x→j} V_xj B_j,
//!
//! over the solution's source elements j (polygon, face, radiosity), with the exact point-to-polygon factor
//! F_{x→j} ([`crate::form_factor::point_polygon`], Nishita & Nakamae 1985; Baum, Rushmeier & Winget 1989,
//! eq. 3) and the visibility fraction V_xj from rays through the shared [`Accel`]. The error of the element
//! solution then enters only through the integral, which smooths it: constant-element staircases and
//! discontinuities at element edges disappear, and direct light from exactly represented emitters is exact
//! up to the visibility estimate.
//!
//! Visibility: toward emitting sources (the direct light, whose shadows are sharp) `direct` rays per source
//! element (default 4 × 4 stratified points on the source, [`DEFAULT_DIRECT_VISIBILITY`]); toward the others
//! `indirect` rays (default one ray to the centroid, [`DEFAULT_INDIRECT_VISIBILITY`]). A source whose
//! radiosity is that of its open part only ([`ElementValue::open`] < 1, [`crate::open_fraction`]) gets the
//! `direct` rays too: its visible share must be measured over its area, since one ray to its centroid would
//! count it whole or not at all. The random points of a
//! query come from a stream derived from the seed and the query point's coordinates, so an answer depends only
//! on (solution, point, seed), never on the order or thread of the queries. Sources on the query's own face
//! (planar, so it cannot see them) and sources with B_j = 0 are skipped.
//!
//! Cost per query: one kernel evaluation per source element in front of the point, plus its rays; counted in
//! [`FinalGather::rays`] and [`FinalGather::kernel_evaluations`] so the method answering can charge them.

use std::sync::atomic::{AtomicU64, Ordering};

use glam::DVec3;

use crate::form_factor::{VisibilitySampling, point_polygon};
use crate::gouraud::ElementValue;
use crate::sampling::{self, mix64};
use crate::{Accel, FaceId, Rgb, Scene};

/// Default visibility toward emitting source elements.
pub const DEFAULT_DIRECT_VISIBILITY: VisibilitySampling = VisibilitySampling::Jittered4x4;
/// Default visibility toward non-emitting source elements.
pub const DEFAULT_INDIRECT_VISIBILITY: VisibilitySampling = VisibilitySampling::Centre;

/// How a final gather estimates visibility, and its random seed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GatherSettings {
    /// Rays toward each emitting source element.
    pub direct: VisibilitySampling,
    /// Rays toward each non-emitting source element.
    pub indirect: VisibilitySampling,
    /// Seed of the visibility streams.
    pub seed: u64,
}

impl GatherSettings {
    /// The defaults with `seed`.
    pub fn with_seed(seed: u64) -> Self {
        Self {
            direct: DEFAULT_DIRECT_VISIBILITY,
            indirect: DEFAULT_INDIRECT_VISIBILITY,
            seed,
        }
    }
}

/// The random stream of a query: a hash of the face and of the point's coordinates along two of the face's
/// edges in units of those edges, quantised to 2^-30, so the stream (and the answer) does not change when the
/// scene is scaled.
fn query_key(scene: &Scene, face: FaceId, point: DVec3) -> u64 {
    let poly = scene.polygon(face);
    let v = poly.vertices();
    let d = point - v[0];
    let q = |e: DVec3| {
        let l2 = e.length_squared();
        let t = if l2 > 0.0 { d.dot(e) / l2 } else { 0.0 };
        (t * (1u64 << 30) as f64).round() as i64 as u64
    };
    let (a, b) = (q(v[1] - v[0]), q(v[v.len() - 1] - v[0]));
    mix64(a ^ mix64(b ^ mix64(face as u64)))
}

/// A solution's source elements, ready to gather from.
#[derive(Debug)]
pub struct FinalGather {
    sources: Vec<(ElementValue, bool)>,
    settings: GatherSettings,
    rays: AtomicU64,
    kernels: AtomicU64,
}

impl FinalGather {
    /// Gathers from `elements` (those with zero radiosity are dropped); `emitting(face)` tells which faces
    /// emit, for the choice of visibility sampling.
    pub fn new(scene: &Scene, elements: &[ElementValue], settings: GatherSettings) -> Self {
        let sources = elements
            .iter()
            .filter(|e| e.radiosity.max_element() > 0.0)
            .map(|e| (*e, scene.material(e.face).is_emitter()))
            .collect();
        Self {
            sources,
            settings,
            rays: AtomicU64::new(0),
            kernels: AtomicU64::new(0),
        }
    }

    /// Number of source elements gathered from.
    pub fn source_count(&self) -> usize {
        self.sources.len()
    }

    /// Rays cast by all queries so far.
    pub fn rays(&self) -> u64 {
        self.rays.load(Ordering::Relaxed)
    }

    /// Point-to-polygon kernel evaluations of all queries so far.
    pub fn kernel_evaluations(&self) -> u64 {
        self.kernels.load(Ordering::Relaxed)
    }

    /// Approximate heap bytes held.
    pub fn bytes(&self) -> usize {
        self.sources.capacity() * size_of::<(ElementValue, bool)>()
    }

    /// B(x) at `point` on `face` (see the module documentation). NaN for a face outside the scene.
    pub fn radiosity_at(&self, scene: &Scene, accel: &Accel, face: FaceId, point: DVec3) -> Rgb {
        if face >= scene.faces.len() {
            return Rgb::splat(f64::NAN);
        }
        let n = scene.faces[face].normal;
        let rho = scene.reflectance(face);
        let e = scene.emission(face);
        if rho.max_element() <= 0.0 {
            return e;
        }
        let key = query_key(scene, face, point);
        let (mut rays, mut kernels) = (0u64, 0u64);
        let mut sum = Rgb::ZERO;
        for (j, (src, emits)) in self.sources.iter().enumerate() {
            if src.face == face {
                continue;
            }
            kernels += 1;
            let f = point_polygon(point, n, &src.polygon);
            if !(f > 0.0) {
                continue;
            }
            let how = if *emits || src.open < 1.0 {
                self.settings.direct
            } else {
                self.settings.indirect
            };
            let v = match how {
                VisibilitySampling::Unoccluded => 1.0,
                VisibilitySampling::Centre => {
                    rays += 1;
                    if accel.visible_between(point, face, src.polygon.centroid(), src.face) {
                        1.0
                    } else {
                        0.0
                    }
                }
                _ => {
                    let total = how.rays();
                    let side = (total as f64).sqrt().round() as u32;
                    let mut r = sampling::rng(self.settings.seed, key ^ mix64(j as u64));
                    let mut seen = 0u32;
                    for k in 0..total {
                        let u = (((k % side) as f64) + sampling::uniform(&mut r)) / side as f64;
                        let w = (((k / side) as f64) + sampling::uniform(&mut r)) / side as f64;
                        let y = src.polygon.point_at(u, w);
                        if accel.visible_between(point, face, y, src.face) {
                            seen += 1;
                        }
                    }
                    rays += total as u64;
                    seen as f64 / total as f64
                }
            };
            sum += (f * v) * src.radiosity;
        }
        self.rays.fetch_add(rays, Ordering::Relaxed);
        self.kernels.fetch_add(kernels, Ordering::Relaxed);
        e + rho * sum
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ElementMesh, builtin};

    /// Howell B-3: differential area below the corner of a parallel a × b rectangle at height h.
    fn corner(a: f64, b: f64, h: f64) -> f64 {
        let (x, y) = (a / h, b / h);
        (x / (1. + x * x).sqrt() * (y / (1. + x * x).sqrt()).atan()
            + y / (1. + y * y).sqrt() * (x / (1. + y * y).sqrt()).atan())
            / (2.0 * std::f64::consts::PI)
    }

    #[test]
    fn exact_for_unoccluded_direct_light_between_parallel_plates() {
        // Receiver z = 0 facing up, emitter 0.7 above facing down, both meshed 3 × 3; gathering from the
        // emitter's exact elements (B = E, ρ = 0) gives B(x) = ρ E F(x → emitter) with F the sum of four
        // corner rectangles (Howell B-3), whatever the visibility sampling (nothing occludes).
        let (w, d, h, e, rho) = (1.0, 0.6, 0.7, 2.0, 0.4);
        let scene = builtin(&format!(
            "parallel-squares?width={w}&depth={d}&distance={h}&emission={e}&reflectance={rho}&tessellation=3"
        ))
        .expect("plates");
        let accel = Accel::new(&scene);
        let mesh = ElementMesh::new(&scene, 0.1);
        let emission: Vec<Rgb> = mesh
            .elements
            .iter()
            .map(|el| scene.emission(el.face as usize))
            .collect();
        let els = mesh.values(&emission);
        let g = FinalGather::new(&scene, &els, GatherSettings::with_seed(7));
        let f_exact = |x: f64, y: f64| {
            corner(x, y, h) + corner(w - x, y, h) + corner(x, d - y, h) + corner(w - x, d - y, h)
        };
        for (x, y) in [(0.5, 0.3), (0.1, 0.05), (0.93, 0.41), (0.0, 0.0)] {
            let p = glam::dvec3(x, y, 0.0);
            let f = (0..scene.faces.len())
                .find(|&f| !scene.material(f).is_emitter() && scene.polygon(f).contains(p, 1e-9))
                .expect("a receiver face");
            let b = g.radiosity_at(&scene, &accel, f, p);
            let want = rho * e * f_exact(x, y);
            assert!(
                (b - Rgb::splat(want)).abs().max_element() < 1e-12 * want.max(1.0),
                "({x}, {y}): {b} vs {want}"
            );
        }
    }

    #[test]
    fn counts_its_work_and_skips_its_own_face() {
        let scene = builtin("furnace-cube?tessellation=2&reflectance=0.5").expect("furnace");
        let accel = Accel::new(&scene);
        let mesh = ElementMesh::new(&scene, 1e9);
        let els = mesh.values(&vec![Rgb::ONE; mesh.len()]);
        let g = FinalGather::new(&scene, &els, GatherSettings::with_seed(1));
        let p = scene.polygon(0).centroid();
        let b = g.radiosity_at(&scene, &accel, 0, p);
        assert!(b.is_finite());
        assert_eq!(g.kernel_evaluations(), (els.len() - 1) as u64);
        assert!(g.rays() > 0);
    }
}

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
//! `indirect` rays (default one ray to the centroid, [`DEFAULT_INDIRECT_VISIBILITY`]). The random points of a
//! query come from a stream derived from the seed and the query point's coordinates, so an answer depends only
//! on (solution, point, seed), never on the order or thread of the queries. Sources on the query's own face
//! (planar, so it cannot see them) and sources with B_j = 0 are skipped.
//!
//! Near sources. A constant B_j is the element's mean; a query point closer to a source element than the
//! element's diameter ([`NEAR_FACTOR`]) sees mostly the part of it next to the point, where the radiosity can
//! differ from the mean by its whole value: the floor beside a block standing on it (partly in the block's
//! contact shadow), the wall just below a ceiling lamp. There the element is split into 4^[`NEAR_SPLITS`]
//! parts, each with its exact point-to-polygon factor and its own visibility ray to its centroid, and each
//! part's radiosity is the element's value with its direct light redistributed,
//! B_j(y_k) = B_j + ρ_j (D(y_k) − D̄_j), D(y) = Σ_e E_e F_{y→e} V_ye over the emitting elements e (exact
//! factor, [`NEAR_DIRECT_VISIBILITY`] rays) and D̄_j the area mean of D over the parts, so the element's mean
//! is kept and only the shape of its direct light is added: direct light computed exactly at the point seen,
//! indirect light from the element solution (the split of Shirley 1990, "A ray tracing method for illumination
//! calculation in diffuse-specular scenes", Graphics Interface, applied to the gathered element). Indirect
//! light stays the element's constant, so points in gaps narrower than an element that no light reaches
//! directly (under a block standing 1 mm above a floor) keep the element solution's error there.
//!
//! Cost per query: one kernel evaluation per source element in front of the point, plus its rays, and for
//! each near source its parts' kernels and rays and the direct light at their centroids; counted in
//! [`FinalGather::rays`] and [`FinalGather::kernel_evaluations`] so the method answering can charge them.

use std::sync::atomic::{AtomicU64, Ordering};

use glam::DVec3;

use crate::form_factor::{VisibilitySampling, point_polygon};
use crate::gouraud::ElementValue;
use crate::sampling::{self, mix64};
use crate::{Accel, FaceId, Polygon, Rgb, Scene};

/// Default visibility toward emitting source elements.
pub const DEFAULT_DIRECT_VISIBILITY: VisibilitySampling = VisibilitySampling::Jittered4x4;
/// Default visibility toward non-emitting source elements.
pub const DEFAULT_INDIRECT_VISIBILITY: VisibilitySampling = VisibilitySampling::Centre;

/// A non-emitting source element closer to the query point than this many times its diameter is split into
/// parts with their own direct light (see the module documentation).
pub const NEAR_FACTOR: f64 = 1.0;
/// Levels of four-way splitting of a near source element (4^2 = 16 parts).
pub const NEAR_SPLITS: u32 = 2;
/// Visibility toward emitting elements when computing the direct light at a near source's parts.
pub const NEAR_DIRECT_VISIBILITY: VisibilitySampling = VisibilitySampling::Jittered2x2;

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

    /// Visibility fraction from `point` on `face` to `polygon` on `target` with `how` rays, drawing jitter from
    /// the stream `stream`.
    #[allow(clippy::too_many_arguments)]
    fn visibility(
        &self,
        accel: &Accel,
        point: DVec3,
        face: FaceId,
        polygon: &Polygon,
        target: FaceId,
        how: VisibilitySampling,
        stream: u64,
        rays: &mut u64,
    ) -> f64 {
        match how {
            VisibilitySampling::Unoccluded => 1.0,
            VisibilitySampling::Centre => {
                *rays += 1;
                if accel.visible_between(point, face, polygon.centroid(), target) {
                    1.0
                } else {
                    0.0
                }
            }
            _ => {
                let total = how.rays();
                let side = (total as f64).sqrt().round() as u32;
                let mut r = sampling::rng(self.settings.seed, stream);
                let mut seen = 0u32;
                for k in 0..total {
                    let u = (((k % side) as f64) + sampling::uniform(&mut r)) / side as f64;
                    let w = (((k / side) as f64) + sampling::uniform(&mut r)) / side as f64;
                    let y = polygon.point_at(u, w);
                    if accel.visible_between(point, face, y, target) {
                        seen += 1;
                    }
                }
                *rays += total as u64;
                seen as f64 / total as f64
            }
        }
    }

    /// Σ_j F_{x→j} V_xj B_j over the parts of the near source `src` (index `j`) seen from `point` on `face`
    /// (normal `n`), each part's radiosity with the source's direct light redistributed (module documentation).
    #[allow(clippy::too_many_arguments)]
    fn near_source(
        &self,
        scene: &Scene,
        accel: &Accel,
        face: FaceId,
        point: DVec3,
        n: DVec3,
        src: &ElementValue,
        stream: u64,
        rays: &mut u64,
        kernels: &mut u64,
    ) -> Rgb {
        let mut parts = vec![src.polygon];
        for _ in 0..NEAR_SPLITS {
            parts = parts.iter().flat_map(|p| p.split4()).collect();
        }
        let n_src = scene.faces[src.face].normal;
        let rho_src = scene.reflectance(src.face);
        // Direct irradiance from the emitting elements at each part's centroid, and its area mean.
        let mut direct = Vec::with_capacity(parts.len());
        let (mut mean, mut area) = (Rgb::ZERO, 0.0);
        for (k, part) in parts.iter().enumerate() {
            let y = part.centroid();
            let mut d = Rgb::ZERO;
            for (e, (em, emits)) in self.sources.iter().enumerate() {
                if !*emits || em.face == src.face {
                    continue;
                }
                *kernels += 1;
                let f = point_polygon(y, n_src, &em.polygon);
                if !(f > 0.0) {
                    continue;
                }
                let key = stream ^ mix64(((k as u64) << 32) ^ e as u64 ^ 0x5eed);
                let v = self.visibility(
                    accel,
                    y,
                    src.face,
                    &em.polygon,
                    em.face,
                    NEAR_DIRECT_VISIBILITY,
                    key,
                    rays,
                );
                d += (f * v) * scene.emission(em.face);
            }
            let a = part.area();
            mean += a * d;
            area += a;
            direct.push(d);
        }
        if area > 0.0 {
            mean /= area;
        }
        let mut sum = Rgb::ZERO;
        for (part, d) in parts.iter().zip(&direct) {
            *kernels += 1;
            let f = point_polygon(point, n, part);
            if !(f > 0.0) {
                continue;
            }
            let v = self.visibility(
                accel,
                point,
                face,
                part,
                src.face,
                VisibilitySampling::Centre,
                stream,
                rays,
            );
            let b = (src.radiosity + rho_src * (*d - mean)).max(Rgb::ZERO);
            sum += (f * v) * b;
        }
        sum
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
            let stream = key ^ mix64(j as u64);
            if !*emits && src.polygon.distance_to(point) < NEAR_FACTOR * src.polygon.diameter() {
                sum += self.near_source(
                    scene,
                    accel,
                    face,
                    point,
                    n,
                    src,
                    stream,
                    &mut rays,
                    &mut kernels,
                );
                continue;
            }
            let how = if *emits {
                self.settings.direct
            } else {
                self.settings.indirect
            };
            let v = self.visibility(
                accel,
                point,
                face,
                &src.polygon,
                src.face,
                how,
                stream,
                &mut rays,
            );
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
    fn a_near_source_gives_the_direct_light_it_has_where_the_point_sees_it() {
        // A point 1 cm up a wall (x = 0, facing +x) above a floor (z = 0, one element) lit by a small emitter
        // 0.3 above it: the floor's direct light varies across it by a factor of about 40, so its constant mean
        // seen from just above its edge is far off. Truth (element values chosen, no occlusion, one bounce off
        // the floor): B(x) = ρ_w (E F_{x→e} + Σ_c F_{x→c} ρ_f D(y_c)) over 128 × 128 floor cells, D(y) = E F_{y→e}
        // exact. The gather splits the floor into 16 parts with the direct light at their centroids, so it
        // is off by at most ρ_w Σ_k F_{x→k} max_{y∈k} |ρ_f D(y) − b_k| (b_k its value on part k): the bound
        // below, from D on an 8 × 8 grid in each part.
        let (rho_w, rho_f, e) = (0.5, 0.6, 10.0);
        let mut b = crate::SceneBuilder::new("near");
        let wall = b
            .add_material(crate::Material::new("wall", Rgb::splat(rho_w), Rgb::ZERO).expect("m"))
            .expect("m");
        let floor = b
            .add_material(crate::Material::new("floor", Rgb::splat(rho_f), Rgb::ZERO).expect("m"))
            .expect("m");
        let lamp = b
            .add_material(crate::Material::new("lamp", Rgb::ZERO, Rgb::splat(e)).expect("m"))
            .expect("m");
        let v = glam::dvec3;
        b.add_polygon_points(
            &[v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)],
            floor,
            "f",
        )
        .expect("floor");
        b.add_polygon_points(
            &[v(0., 0., 0.), v(0., 1., 0.), v(0., 1., 1.), v(0., 0., 1.)],
            wall,
            "w",
        )
        .expect("wall");
        // Facing down: counter-clockwise seen from below.
        b.add_polygon_points(
            &[
                v(0.6, 0.4, 0.3),
                v(0.6, 0.6, 0.3),
                v(0.8, 0.6, 0.3),
                v(0.8, 0.4, 0.3),
            ],
            lamp,
            "l",
        )
        .expect("lamp");
        let scene = b.build().expect("scene");
        let accel = Accel::new(&scene);
        let (fl, wl, lp) = (0, 1, 2);
        assert!(scene.faces[fl].normal.z > 0.99 && scene.faces[wl].normal.x > 0.99);
        assert!(scene.faces[lp].normal.z < -0.99);
        let lamp_poly = scene.polygon(lp);
        let d = |y: DVec3| e * point_polygon(y, DVec3::Z, &lamp_poly);
        // The floor element's exact mean (fine midpoint rule) and the truth at the query point.
        let x = v(0.0, 0.5, 0.01);
        let m = 128;
        let (mut mean, mut gathered) = (0.0, 0.0);
        let fpoly = scene.polygon(fl);
        for i in 0..m {
            for k in 0..m {
                let (s0, t0) = (i as f64 / m as f64, k as f64 / m as f64);
                let (s1, t1) = (s0 + 1.0 / m as f64, t0 + 1.0 / m as f64);
                let cell = Polygon::quad(
                    fpoly.point_at(s0, t0),
                    fpoly.point_at(s1, t0),
                    fpoly.point_at(s1, t1),
                    fpoly.point_at(s0, t1),
                );
                let dy = d(cell.centroid());
                mean += dy / (m * m) as f64;
                gathered += point_polygon(x, DVec3::X, &cell) * rho_f * dy;
            }
        }
        let f_lamp = point_polygon(x, DVec3::X, &lamp_poly);
        let truth = rho_w * (e * f_lamp + gathered);
        let els = vec![
            ElementValue {
                face: fl,
                polygon: fpoly,
                radiosity: Rgb::splat(rho_f * mean),
            },
            ElementValue {
                face: lp,
                polygon: lamp_poly,
                radiosity: Rgb::splat(e),
            },
        ];
        let g = FinalGather::new(&scene, &els, GatherSettings::with_seed(3));
        let got = g.radiosity_at(&scene, &accel, wl, x).x;
        // The bound: each part's value against ρ_f D over the part.
        let mut parts = vec![fpoly];
        for _ in 0..NEAR_SPLITS {
            parts = parts.iter().flat_map(|p| p.split4()).collect();
        }
        let dbar: f64 = parts
            .iter()
            .map(|p| p.area() * d(p.centroid()))
            .sum::<f64>()
            / parts.iter().map(|p| p.area()).sum::<f64>();
        let mut bound = 0.0;
        for p in &parts {
            let bk = rho_f * mean + rho_f * (d(p.centroid()) - dbar);
            let mut worst: f64 = 0.0;
            for i in 0..=8 {
                for k in 0..=8 {
                    let y = p.point_at(i as f64 / 8.0, k as f64 / 8.0);
                    worst = worst.max((rho_f * d(y) - bk).abs());
                }
            }
            bound += point_polygon(x, DVec3::X, p) * worst;
        }
        bound *= rho_w;
        assert!(
            (got - truth).abs() <= bound,
            "near gather {got} vs {truth}: off by {} > bound {bound}",
            (got - truth).abs()
        );
        // The constant element, as the gather used it before near sources were split, fails this test.
        let constant = rho_w * (e * f_lamp + point_polygon(x, DVec3::X, &fpoly) * rho_f * mean);
        assert!(
            (constant - truth).abs() > bound,
            "constant {constant} vs {truth}: the test scene does not separate them (bound {bound})"
        );
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

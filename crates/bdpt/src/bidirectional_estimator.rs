//! One sample of the radiosity leaving a surface point by bidirectional path tracing (Lafortune & Willems
//! 1993; Veach & Guibas 1995; Veach 1997, ch. 10), in radlab's diffuse, one-sided world.
//!
//! B(x) = E(x) + ρ(x) H(x), and ρ(x) H(x) is a sum over paths x̄ = v_0 … v_k = x of every length k ≥ 1 of
//!
//! f(x̄) = E(v_0)/π · G(v_0, v_1) · Π_{j=1}^{k−1} [ρ(v_j)/π · G(v_j, v_{j+1})] · ρ(x),
//! G(a, b) = cos θ_a cos θ_b / ‖a − b‖² · V(a, b),
//!
//! integrated over the areas of v_0 … v_{k−1}. The query point is the eye vertex z_0 = x, a fixed point with
//! importance ρ(x) cos θ_x (a pinhole whose "lens" is x's hemisphere). Each sample draws a **light subpath**
//! y_0 … (y_0 on an emitter chosen by power, area density p_A; cosine-weighted directions) and an **eye
//! subpath** z_0 = x, z_1, … (cosine-weighted directions), both ended by Russian roulette (continue with
//! probability max_c ρ_c, Arvo & Kirk 1990), and joins every prefix pair (s light, t eye vertices,
//! k = s + t − 1 ≤ `max_depth`, s ≤ `max_light`):
//!
//! - s = 0, t ≥ 2: the eye subpath reaches an emitter, α_E(z_{t−1}) E/π;
//! - s = 1: a fresh emitter sample y (next-event estimation), α_E(z_{t−1}) f(z_{t−1}) E(y)/π G(y, z_{t−1})/p_A;
//! - s ≥ 2: α_L(y_{s−1}) ρ(y_{s−1})/π G(y_{s−1}, z_{t−1}) f(z_{t−1}) α_E(z_{t−1}), one shadow ray;
//! - t = 0 is impossible at a point (mis_weight.rs) and never formed; s > `max_light` is not used.
//!
//! Here α are the subpath throughputs (α_L(y_1) = E/p_A, α_E(z_1) = π ρ(x), each later vertex × ρ/q) and
//! f(z_0) = ρ(x), f(z_j) = ρ(z_j)/π. Each connection is weighted by mis_weight.rs (balance or power
//! heuristic), so the sum over strategies is an unbiased estimate of ρ(x) H(x) per path length; paths longer
//! than `max_depth` segments are dropped (bias at most ρ_max^max_depth, relative). Faces emit and reflect
//! from their fronts only: a subpath reaching a back is absorbed, and a connection needs both ends to face
//! each other. Every ray (subpath extensions and shadow rays) goes through the shared [`Accel`], whose counter
//! the solver reads.

use glam::DVec3;
use radlab_pathtrace::{EmitterSampler, SurfacePoint};
use radlab_scene::{
    FaceId, Rgb, Scene,
    sampling::{self, Rng},
};
use radlab_visibility::Accel;

use crate::mis_weight::{Densities, Heuristic, mis_weight};

const INV_PI: f64 = std::f64::consts::FRAC_1_PI;

/// A vertex of a subpath.
#[derive(Clone, Copy, Debug)]
struct Vertex {
    face: FaceId,
    point: DVec3,
    normal: DVec3,
    /// Throughput of the subpath up to this vertex (α).
    alpha: Rgb,
    /// Its factor in a connection: E/π at a light subpath's origin, ρ(x) at the query point, ρ/π elsewhere.
    f: Rgb,
}

/// Area density of reaching `to` by a cosine-weighted direction from `from` (0 unless they face each other).
fn cosine_area_pdf(from: &Vertex, to: &Vertex) -> f64 {
    let d = to.point - from.point;
    let r2 = d.length_squared();
    let dir = d / r2.sqrt();
    let (cos_from, cos_to) = (from.normal.dot(dir), -to.normal.dot(dir));
    if !(cos_from > 0.0 && cos_to > 0.0 && r2 > 0.0) {
        return 0.0;
    }
    cos_from * INV_PI * cos_to / r2
}

/// A subpath: its vertices and their densities (`pdf[i].rev` filled once vertex i + 1 exists).
#[derive(Default)]
struct Subpath {
    vertices: Vec<Vertex>,
    pdf: Vec<Densities>,
}

impl Subpath {
    fn push(&mut self, v: Vertex, fwd: f64) {
        if let Some(prev) = self.vertices.last() {
            let rev = cosine_area_pdf(&v, prev);
            if let Some(p) = self.pdf.last_mut() {
                p.rev = rev;
            }
        }
        self.vertices.push(v);
        self.pdf.push(Densities { fwd, rev: 0.0 });
    }
}

/// The bidirectional estimator for one scene: see the module documentation.
pub struct BidirectionalEstimator<'a> {
    scene: &'a Scene,
    accel: &'a Accel,
    emitters: EmitterSampler,
    max_depth: u32,
    max_light: u32,
    heuristic: Heuristic,
}

impl<'a> BidirectionalEstimator<'a> {
    /// The estimator for `scene` through `accel`: paths of at most `max_depth` segments, light subpaths of at
    /// most `max_light` vertices, strategies weighted by `heuristic`.
    pub fn new(
        scene: &'a Scene,
        accel: &'a Accel,
        max_depth: u32,
        max_light: u32,
        heuristic: Heuristic,
    ) -> Self {
        Self {
            scene,
            accel,
            emitters: EmitterSampler::new(scene),
            max_depth,
            max_light,
            heuristic,
        }
    }

    fn weight(&self, light: &[Densities], eye: &[Densities]) -> f64 {
        mis_weight(light, eye, self.heuristic, self.max_light as usize)
    }

    /// One unbiased sample of the radiosity leaving `p` (its face's emission plus the reflected part).
    pub fn radiosity(&self, p: &SurfacePoint, rng: &mut Rng) -> Rgb {
        self.scene.emission(p.face) + self.reflected_radiosity(p, rng)
    }

    /// One unbiased sample of ρ(x) H(x) at `p`: every strategy of one light and one eye subpath, weighted.
    pub fn reflected_radiosity(&self, p: &SurfacePoint, rng: &mut Rng) -> Rgb {
        let rho = self.scene.reflectance(p.face);
        if !(rho.max_element() > 0.0) || self.emitters.is_empty() {
            return Rgb::ZERO;
        }
        let light = self.light_subpath(rng);
        let eye = self.eye_subpath(p, rho, rng);
        let mut sum = Rgb::ZERO;
        let max = self.max_depth as usize;
        for t in 1..=eye.vertices.len() {
            if t >= 2 {
                sum += self.eye_reaches_emitter(&eye, t);
            }
            if t <= max {
                sum += self.next_event(&eye, t, rng);
            }
            for s in 2..=light.vertices.len().min(max + 1 - t) {
                sum += self.connect(&light, s, &eye, t);
            }
        }
        sum
    }

    /// A cosine-weighted step from `from`: the vertex hit on a front face, or `None`.
    fn extend(&self, from: &Vertex, alpha: Rgb, rng: &mut Rng) -> Option<Vertex> {
        let dir = sampling::cosine_hemisphere(
            from.normal,
            sampling::uniform(rng),
            sampling::uniform(rng),
        );
        let hit = self.accel.intersect_from(from.face, from.point, dir)?;
        let normal = self.scene.faces[hit.face].normal;
        if !(-normal.dot(dir) > 0.0) {
            return None; // a back: absorbed
        }
        Some(Vertex {
            face: hit.face,
            point: hit.point,
            normal,
            alpha,
            f: self.scene.reflectance(hit.face) * INV_PI,
        })
    }

    /// Continues `path` from its last vertex by Russian roulette until it ends or holds `max_len` vertices.
    fn random_walk(&self, path: &mut Subpath, mut alpha: Rgb, max_len: usize, rng: &mut Rng) {
        while path.vertices.len() < max_len {
            let Some(&from) = path.vertices.last() else {
                return;
            };
            let Some(v) = self.extend(&from, alpha, rng) else {
                return;
            };
            let fwd = cosine_area_pdf(&from, &v);
            path.push(v, fwd);
            let rho = self.scene.reflectance(v.face);
            let q = rho.max_element().min(1.0);
            if !(q > 0.0) || sampling::uniform(rng) >= q {
                return;
            }
            alpha *= rho / q;
        }
    }

    /// y_0 on an emitter (by power), then a cosine-weighted walk: at most min(`max_depth`, `max_light`)
    /// vertices.
    fn light_subpath(&self, rng: &mut Rng) -> Subpath {
        let mut path = Subpath::default();
        let (u0, u1, u2) = (
            sampling::uniform(rng),
            sampling::uniform(rng),
            sampling::uniform(rng),
        );
        let Some(ls) = self.emitters.sample(u0, u1, u2) else {
            return path;
        };
        let e = self.scene.emission(ls.face);
        let y0 = Vertex {
            face: ls.face,
            point: ls.point,
            normal: self.scene.faces[ls.face].normal,
            alpha: Rgb::splat(1.0 / ls.pdf_area),
            f: e * INV_PI,
        };
        path.push(y0, ls.pdf_area);
        // α(y_1) = α(y_0) · (E/π) · cos / (cos/π) = E / p_A.
        let max_len = self.max_depth.min(self.max_light) as usize;
        self.random_walk(&mut path, e / ls.pdf_area, max_len, rng);
        path
    }

    /// z_0 = the query point, then a cosine-weighted walk: at most `max_depth` + 1 vertices.
    fn eye_subpath(&self, p: &SurfacePoint, rho: Rgb, rng: &mut Rng) -> Subpath {
        let mut path = Subpath::default();
        let z0 = Vertex {
            face: p.face,
            point: p.point,
            normal: p.normal,
            alpha: Rgb::ONE,
            f: rho,
        };
        path.push(z0, 1.0);
        // α(z_1) = ρ(x) · cos / (cos/π) = π ρ(x).
        self.random_walk(
            &mut path,
            rho * std::f64::consts::PI,
            self.max_depth as usize + 1,
            rng,
        );
        path
    }

    /// s = 0: the eye subpath's vertex t − 1 lies on an emitter.
    fn eye_reaches_emitter(&self, eye: &Subpath, t: usize) -> Rgb {
        let z = &eye.vertices[t - 1];
        let e = self.scene.emission(z.face);
        if !(e.max_element() > 0.0) {
            return Rgb::ZERO;
        }
        let mut pdf = eye.pdf[..t].to_vec();
        pdf[t - 1].rev = self.emitters.pdf_area(z.face);
        z.alpha * e * INV_PI * self.weight(&[], &pdf)
    }

    /// s = 1: a fresh emitter sample joined to the eye subpath's vertex t − 1 (one shadow ray).
    fn next_event(&self, eye: &Subpath, t: usize, rng: &mut Rng) -> Rgb {
        let (u0, u1, u2) = (
            sampling::uniform(rng),
            sampling::uniform(rng),
            sampling::uniform(rng),
        );
        let Some(ls) = self.emitters.sample(u0, u1, u2) else {
            return Rgb::ZERO;
        };
        let y = Vertex {
            face: ls.face,
            point: ls.point,
            normal: self.scene.faces[ls.face].normal,
            alpha: Rgb::splat(1.0 / ls.pdf_area),
            f: self.scene.emission(ls.face) * INV_PI,
        };
        let light = [Densities {
            fwd: ls.pdf_area,
            rev: 0.0,
        }];
        self.join(&y, &light, eye, t)
    }

    /// s ≥ 2: the light subpath's vertex s − 1 joined to the eye subpath's vertex t − 1 (one shadow ray).
    fn connect(&self, light: &Subpath, s: usize, eye: &Subpath, t: usize) -> Rgb {
        self.join(&light.vertices[s - 1], &light.pdf[..s], eye, t)
    }

    /// The weighted contribution of light vertex `y` (last of densities `light_pdf`) joined to eye vertex t − 1.
    fn join(&self, y: &Vertex, light_pdf: &[Densities], eye: &Subpath, t: usize) -> Rgb {
        let z = &eye.vertices[t - 1];
        if y.face == z.face {
            return Rgb::ZERO; // a planar face does not see itself
        }
        let unweighted = y.alpha * y.f * z.f * z.alpha;
        if !(unweighted.max_element() > 0.0) {
            return Rgb::ZERO;
        }
        let d = z.point - y.point;
        let r2 = d.length_squared();
        let dir = d / r2.sqrt();
        let (cos_y, cos_z) = (y.normal.dot(dir), -z.normal.dot(dir));
        if !(cos_y > 0.0 && cos_z > 0.0 && r2 > 0.0) {
            return Rgb::ZERO;
        }
        if !self.accel.visible_between(y.point, y.face, z.point, z.face) {
            return Rgb::ZERO;
        }
        let mut lp = light_pdf.to_vec();
        let mut ep = eye.pdf[..t].to_vec();
        if let Some(last) = lp.last_mut() {
            last.rev = cosine_area_pdf(z, y);
        }
        ep[t - 1].rev = cosine_area_pdf(y, z);
        let g = cos_y * cos_z / r2;
        unweighted * (g * self.weight(&lp, &ep))
    }
}

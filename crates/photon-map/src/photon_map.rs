//! The photon map as a method at query points, in two modes.
//!
//! At a query point x: B(x) = E(x) + ρ(x) (H_d(x) + H_i(x)), with the direct irradiance H_d by next-event
//! estimation (radlab-pathtrace's estimator, `direct_samples` samples) in both modes, so the modes differ
//! only in the indirect term, as every Monte Carlo method in radlab does.
//!
//! **final-gather** (Jensen 1996, §4; Christensen 1999, "Faster photon map global illumination"): one global
//! map of every landing (direct ones included); irradiance precomputed by the density estimate
//! (density_estimate.rs) at every `precompute_stride`-th photon; at x, `gather_samples` cosine-distributed
//! rays whose hits y give H_i(x) ≈ (1/G) Σ ρ(y) H(y), H(y) read from the nearest precomputed point that faces
//! the same way (n·n_y > 0.9) and, under `leak_test`, sees y (one ray; none found: 0). Biased by the density
//! estimate at y (edges, corners), not by the gather. Steps: (1) trace the photons and precompute, (2) answer.
//!
//! **progressive** (Hachisuka, Ogaki & Jensen 2008, §4.2): each query point keeps a radius R, a photon count
//! N and an unnormalised flux τ; each step traces a batch of photons that have reflected at least once (the
//! direct light is H_d's) and, with M of them within R of x (facing x's side, and under `leak_test` seen from
//! x: one ray each) carrying Φ_M: N' = N + αM, R' = R √(N'/(N + M)), τ' = (τ + Φ_M) R'²/R², then
//! H_i(x) = τ / (π R² N_e) with N_e all photons emitted so far. The radius shrinks and the estimate is
//! consistent. One pass per step, `passes` steps.
//!
//! Points off the query set are answered fresh: final gather with streams keyed by the point's coordinates;
//! progressive by the density estimate over the last pass's photons (its radius is not tracked there).
//! Photons, precomputed points, their k-d trees (kiddo) and the per-point state are counted in bytes; every
//! ray (photon flights, gathers, leak tests, shadow rays) through the shared `Accel`'s counter.

use std::num::NonZero;

use glam::DVec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use radlab_method::{MethodParams, Solution, SolveError, Solver, Stats, Step};
use radlab_pathtrace::{
    EmitterSampler, PathEstimator, QueryPoints, SurfacePoint, coordinate_stream,
};
use radlab_scene::{
    FaceId, Rgb, Scene,
    sampling::{self, Rng, mix64},
};
use radlab_visibility::Accel;
use rayon::prelude::*;

use crate::density_estimate::PhotonMap;
use crate::params::{PhotonMapParams, PhotonMode};
use radlab_pathtrace::{CHUNK, trace_photons};

const PHOTON_STREAM_TAG: u64 = 0x7068_6f74_6f6e_6d70; // "photonmp"
const GATHER_STREAM_TAG: u64 = 0x7068_6761_7468_6572; // "phgather"
const DIRECT_STREAM_TAG: u64 = 0x7068_6469_7265_6374; // "phdirect"
/// Chunks of photons reserved per progressive pass (streams never overlap between passes).
const CHUNKS_PER_PASS: u64 = 1 << 32;
/// Precomputed irradiance points consulted per gather hit.
const NEAREST_IRRADIANCE: usize = 8;
/// Smallest n·n_y for a precomputed point to serve a gather hit (about 25°).
const SAME_FACING: f64 = 0.9;

/// Irradiance precomputed at a photon's position.
#[derive(Clone, Copy, Debug, PartialEq)]
struct IrradiancePoint {
    point: DVec3,
    normal: DVec3,
    face: FaceId,
    irradiance: Rgb,
}

/// Progressive photon mapping state of one query point.
#[derive(Clone, Copy, Debug, PartialEq)]
struct PpmPoint {
    radius2: f64,
    n: f64,
    tau: Rgb,
}

/// The photon map's counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PhotonCounts {
    /// Photons emitted so far.
    pub emitted: u64,
    /// Photons stored so far (over all passes).
    pub stored: u64,
    /// Precomputed irradiance points (final gather).
    pub irradiance_points: u64,
    /// Passes (progressive) or 1 once the map is built (final gather).
    pub passes: u64,
}

/// The photon map at a fixed set of query points.
pub struct PhotonMapSolver<'a> {
    scene: &'a Scene,
    accel: &'a Accel,
    params: PhotonMapParams,
    estimator: PathEstimator<'a>,
    emitters: EmitterSampler,
    seed: u64,
    points: QueryPoints,
    map: Option<PhotonMap>,
    irradiance: Vec<IrradiancePoint>,
    irradiance_tree: Option<ImmutableKdTree<f64, 3>>,
    ppm: Vec<PpmPoint>,
    direct: Vec<Rgb>,
    answers: Vec<Rgb>,
    counts: PhotonCounts,
    steps: u64,
    rays: u64,
    converged: bool,
}

impl std::fmt::Debug for PhotonMapSolver<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PhotonMapSolver")
            .field("points", &self.points.len())
            .field("counts", &self.counts)
            .field("params", &self.params)
            .finish()
    }
}

impl<'a> PhotonMapSolver<'a> {
    /// The photon map for `points` (nothing traced yet).
    pub fn new(
        scene: &'a Scene,
        accel: &'a Accel,
        params: PhotonMapParams,
        seed: u64,
        points: Vec<SurfacePoint>,
    ) -> Result<Self, SolveError> {
        params.validate()?;
        let points = QueryPoints::new(scene, points)?;
        let r0 = params.initial_radius * scene.diagonal();
        Ok(Self {
            scene,
            accel,
            estimator: PathEstimator::new(scene, accel, params.max_depth, params.direct),
            emitters: EmitterSampler::new(scene),
            seed,
            ppm: vec![
                PpmPoint {
                    radius2: r0 * r0,
                    n: 0.0,
                    tau: Rgb::ZERO,
                };
                points.len()
            ],
            points,
            map: None,
            irradiance: Vec::new(),
            irradiance_tree: None,
            direct: Vec::new(),
            answers: Vec::new(),
            params,
            counts: PhotonCounts::default(),
            steps: 0,
            rays: 0,
            converged: false,
        })
    }

    /// The counters.
    pub fn counts(&self) -> PhotonCounts {
        self.counts
    }

    fn stream_seed(&self, tag: u64) -> u64 {
        mix64(self.seed ^ tag)
    }

    /// Direct irradiance at a point from stream `stream`.
    fn direct_at(&self, face: FaceId, x: DVec3, n: DVec3, stream: u64) -> Rgb {
        let mut rng = sampling::rng(self.stream_seed(DIRECT_STREAM_TAG), stream);
        let k = self.params.direct_samples;
        let mut h = Rgb::ZERO;
        for _ in 0..k {
            h += self.estimator.direct_irradiance(face, x, n, &mut rng);
        }
        h / k as f64
    }

    /// Precomputed irradiance serving gather hit `y` on `face` (normal `n`).
    fn lookup(&self, face: FaceId, y: DVec3, n: DVec3) -> Rgb {
        let Some(tree) = &self.irradiance_tree else {
            return Rgb::ZERO;
        };
        let k = NonZero::new(NEAREST_IRRADIANCE).unwrap_or(NonZero::<usize>::MIN);
        for c in tree.nearest_n::<SquaredEuclidean>(&y.to_array(), k) {
            let p = &self.irradiance[c.item as usize];
            if p.normal.dot(n) < SAME_FACING {
                continue;
            }
            if self.params.leak_test && !self.accel.visible_between(p.point, p.face, y, face) {
                continue;
            }
            return p.irradiance;
        }
        Rgb::ZERO
    }

    /// Indirect irradiance at x by the final gather from `rng`.
    fn final_gather(&self, face: FaceId, x: DVec3, n: DVec3, rng: &mut Rng) -> Rgb {
        let g = self.params.gather_samples;
        let mut sum = Rgb::ZERO;
        for _ in 0..g {
            let dir =
                sampling::cosine_hemisphere(n, sampling::uniform(rng), sampling::uniform(rng));
            let Some(hit) = self.accel.intersect_from(face, x, dir) else {
                continue;
            };
            let ny = self.scene.faces[hit.face].normal;
            if !(-ny.dot(dir) > 0.0) {
                continue;
            }
            sum += self.scene.reflectance(hit.face) * self.lookup(hit.face, hit.point, ny);
        }
        sum / g as f64
    }

    /// Indirect irradiance at query point `i` (or at an arbitrary point, `i` = None, from `stream`).
    fn indirect(&self, face: FaceId, x: DVec3, n: DVec3, i: Option<usize>, stream: u64) -> Rgb {
        match self.params.mode {
            PhotonMode::FinalGather => {
                let mut rng = sampling::rng(self.stream_seed(GATHER_STREAM_TAG), stream);
                self.final_gather(face, x, n, &mut rng)
            }
            PhotonMode::Progressive => match i {
                Some(i) => {
                    let s = &self.ppm[i];
                    if self.counts.emitted == 0 || !(s.radius2 > 0.0) {
                        Rgb::ZERO
                    } else {
                        s.tau / (std::f64::consts::PI * s.radius2 * self.counts.emitted as f64)
                    }
                }
                None => self.map.as_ref().map_or(Rgb::ZERO, |m| {
                    m.irradiance(x, n, self.params.nearest as usize, self.params.filter)
                }),
            },
        }
    }

    fn radiosity(&self, face: FaceId, x: DVec3, n: DVec3, i: Option<usize>, stream: u64) -> Rgb {
        let hd = match i {
            Some(i) if !self.direct.is_empty() => self.direct[i],
            _ => self.direct_at(face, x, n, stream),
        };
        let h = hd + self.indirect(face, x, n, i, stream);
        self.scene.emission(face) + self.scene.reflectance(face) * h
    }

    fn compute_direct(&mut self) {
        let this = &*self;
        self.direct = (0..this.points.len())
            .into_par_iter()
            .map(|i| {
                let p = &this.points[i];
                this.direct_at(p.face, p.point, p.normal, i as u64)
            })
            .collect();
    }

    fn compute_answers(&mut self) -> Result<(), SolveError> {
        let this = &*self;
        let answers: Vec<Rgb> = (0..this.points.len())
            .into_par_iter()
            .map(|i| {
                let p = &this.points[i];
                this.radiosity(p.face, p.point, p.normal, Some(i), i as u64)
            })
            .collect();
        if answers.iter().any(|b| !b.is_finite()) {
            return Err(SolveError::Numerical(
                "the photon map produced a non-finite radiosity".into(),
            ));
        }
        self.answers = answers;
        self.converged = true;
        Ok(())
    }

    /// Final gather, first step: the global map and the precomputed irradiance.
    fn build_map(&mut self) {
        let batch = trace_photons(
            self.scene,
            self.accel,
            &self.emitters,
            self.params.photons,
            0,
            self.stream_seed(PHOTON_STREAM_TAG),
            self.params.max_depth,
            &|_| true,
        );
        self.counts.emitted = batch.emitted;
        self.counts.stored = batch.photons.len() as u64;
        let map = PhotonMap::new(batch.photons, batch.emitted);
        let (k, filter) = (self.params.nearest as usize, self.params.filter);
        let stride = self.params.precompute_stride as usize;
        self.irradiance = map
            .photons()
            .par_iter()
            .step_by(stride)
            .map(|p| IrradiancePoint {
                point: p.point,
                normal: p.normal,
                face: p.face,
                irradiance: map.irradiance(p.point, p.normal, k, filter),
            })
            .collect();
        self.irradiance_tree = (!self.irradiance.is_empty()).then(|| {
            let pts: Vec<[f64; 3]> = self.irradiance.iter().map(|p| p.point.to_array()).collect();
            ImmutableKdTree::new_from_slice(&pts)
        });
        self.counts.irradiance_points = self.irradiance.len() as u64;
        self.counts.passes = 1;
        self.map = Some(map);
    }

    /// Progressive: one pass of photons and the radius update at every query point.
    fn progressive_pass(&mut self) {
        let pass = self.counts.passes;
        let batch = trace_photons(
            self.scene,
            self.accel,
            &self.emitters,
            self.params.photons,
            pass * CHUNKS_PER_PASS,
            self.stream_seed(PHOTON_STREAM_TAG),
            self.params.max_depth,
            &|bounces| bounces >= 1,
        );
        // Every emitted photon counts toward N_e, stored or not (even when the batch stored nothing).
        let emitted = if batch.emitted == 0 && !self.emitters.is_empty() {
            CHUNK
        } else {
            batch.emitted
        };
        self.counts.emitted += emitted;
        self.counts.stored += batch.photons.len() as u64;
        let map = PhotonMap::new(batch.photons, emitted);
        let alpha = self.params.alpha;
        let leak = self.params.leak_test;
        let this = &*self;
        let updated: Vec<PpmPoint> = (0..this.points.len())
            .into_par_iter()
            .map(|i| {
                let p = &this.points[i];
                let mut s = this.ppm[i];
                let (mut m, mut phi) = (0u64, Rgb::ZERO);
                for j in map.within(p.point, s.radius2) {
                    let ph = &map.photons()[j];
                    if !(ph.toward_source.dot(p.normal) > 0.0 && ph.normal.dot(p.normal) > 0.0) {
                        continue;
                    }
                    if leak
                        && !this
                            .accel
                            .visible_between(ph.point, ph.face, p.point, p.face)
                    {
                        continue;
                    }
                    m += 1;
                    phi += ph.power;
                }
                if m > 0 {
                    let m = m as f64;
                    let n_new = s.n + alpha * m;
                    let shrink = n_new / (s.n + m);
                    s.radius2 *= shrink;
                    s.tau = (s.tau + phi) * shrink;
                    s.n = n_new;
                }
                s
            })
            .collect();
        self.ppm = updated;
        self.counts.passes += 1;
        self.map = Some(map);
    }

    fn bytes(&self) -> u64 {
        (self.points.bytes()
            + self.map.as_ref().map_or(0, PhotonMap::bytes)
            + self.irradiance.capacity() * size_of::<IrradiancePoint>()
            + self
                .irradiance_tree
                .as_ref()
                .map_or(0, |_| self.irradiance.len() * (24 + 8))
            + self.ppm.capacity() * size_of::<PpmPoint>()
            + (self.direct.capacity() + self.answers.capacity()) * size_of::<Rgb>()) as u64
    }
}

impl Solver for PhotonMapSolver<'_> {
    fn step(&mut self) -> Result<Step, SolveError> {
        if self.converged {
            return Ok(Step::Converged);
        }
        let rays0 = self.accel.rays_cast();
        if self.direct.is_empty() && !self.points.is_empty() {
            self.compute_direct();
        }
        match self.params.mode {
            PhotonMode::FinalGather => {
                if self.map.is_none() {
                    self.build_map();
                } else {
                    self.compute_answers()?;
                }
            }
            PhotonMode::Progressive => {
                self.progressive_pass();
                if self.counts.passes >= self.params.passes as u64 {
                    self.compute_answers()?;
                }
            }
        }
        self.rays += self.accel.rays_cast() - rays0;
        self.steps += 1;
        Ok(if self.converged {
            Step::Converged
        } else {
            Step::Continue
        })
    }

    fn solution(&self) -> &dyn Solution {
        self
    }

    fn stats(&self) -> Stats {
        Stats {
            steps: self.steps,
            elements: self.counts.stored,
            links: 0,
            form_factors: 0,
            rays: self.rays,
            bytes: self.bytes(),
            residual: None,
        }
    }
}

impl Solution for PhotonMapSolver<'_> {
    /// The answer at a query point once solved (before then, from the state so far); elsewhere a fresh
    /// estimate (see the module documentation).
    fn radiosity_at(&self, face: FaceId, point: DVec3) -> Rgb {
        if face >= self.scene.faces.len() {
            return Rgb::splat(f64::NAN);
        }
        let n = self.scene.faces[face].normal;
        match self.points.find(face, point) {
            Some(i) if self.converged => self.answers[i],
            Some(i) => self.radiosity(face, point, n, Some(i), i as u64),
            None => self.radiosity(face, point, n, None, coordinate_stream(face, point)),
        }
    }
}

//! The irradiance cache as a method (Ward, Rubinstein & Clear 1988; Ward & Heckbert 1992; radius bounds after
//! Tabellion & Lamorlette 2004 and neighbour clamping after Křivánek et al. 2006).
//!
//! At a surface point x: B(x) = E(x) + ρ(x) (H_d(x) + H_i(x)). The direct irradiance H_d is estimated at every
//! answered point by next-event estimation (radlab-pathtrace's emitter sampling, `direct_samples` shadow rays).
//! The indirect irradiance H_i = ∫ (B(y) − E(y))/π cos θ dω is cached: a *record* at x_i holds H_i from a
//! stratified hemisphere gather (hemisphere_gather.rs) whose rays are each continued by one path to termination
//! by Russian roulette (radlab-pathtrace's path estimator: the reflected radiosity B − E at the hit), with its
//! gradients and radius R_i, the harmonic mean distance clamped to [min_radius, max_radius] × the scene's
//! diagonal. Deeper bounces are not cached (Radiance caches each ambient level; here only the first indirect
//! bounce is, and the rest is path traced, unbiased). Records are interpolated with Ward's error
//! ε_i(x) = ‖x − x_i‖/R_i + √(1 − n·n_i), used while ε_i < a, with weight w_i = 1/ε_i − 1/a (Ward's 1/ε_i
//! shifted to vanish at the edge of validity, so the interpolation is continuous) and the value extrapolated
//! by the gradients: H_i(x) ≈ Σ w_i (H_i + (n_i × n)·∇_r + (x − x_i)·∇_t) / Σ w_i. Records behind x
//! ((x − x_i)·(n + n_i)/2 < −10⁻³ R_i, Ward et al. 1988) and records hidden from x (one ray, `leak_test`) are
//! skipped.
//!
//! **Deterministic build.** The cache is built over the query points in passes: a pass finds, in parallel and
//! reading the cache only, the points no record serves; walks them in their given order choosing new record
//! sites at least a separation s apart (a tentative site serves a point when ε < a with R = s/a), gathers those
//! records in parallel (record at point i from random stream i), and inserts them in point order (neighbour
//! clamping then shrinks radii in that order). s starts at a·max_radius and halves each pass until it falls below
//! a·min_radius, after which every point no record serves becomes a site. A pass that finds every point served
//! computes the answers (in parallel, read-only) and ends the solve. Nothing depends on the thread count.
//!
//! **Other points** (an image, a probe off the query set): the cache is read, not extended: the interpolated
//! value where a record serves the point, otherwise a fresh gather that is not stored (streams keyed by the
//! point's coordinates), so answers are reproducible in any order.

use std::collections::HashMap;

use glam::DVec3;
use radlab_method::{MethodParams, Solution, SolveError, Solver, Stats, Step};
use radlab_pathtrace::{PathEstimator, QueryPoints, SurfacePoint, coordinate_stream};
use radlab_scene::{
    FaceId, Rgb, Scene,
    sampling::{self, Rng, mix64},
};
use radlab_visibility::Accel;
use rayon::prelude::*;

use crate::hemisphere_gather::{gather, strata};
use crate::params::IrradianceCacheParams;
use crate::record_octree::RecordOctree;

/// Mixed into the seed for the records' gathers.
pub const GATHER_STREAM_TAG: u64 = 0x6972_7261_6463_6163; // "irradcac"
/// Mixed into the seed for the direct light at answered points.
const DIRECT_STREAM_TAG: u64 = 0x6972_6469_7265_6374; // "irdirect"
/// Marks a query point that has no record of its own.
const NO_RECORD: u32 = u32::MAX;

/// One irradiance record.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Record {
    /// Where it was gathered.
    pub point: DVec3,
    /// The normal gathered over.
    pub normal: DVec3,
    /// The face it lies on.
    pub face: FaceId,
    /// Indirect irradiance H_i (W/m² per channel).
    pub irradiance: Rgb,
    /// Translational gradient per channel.
    pub translational: [DVec3; 3],
    /// Rotational gradient per channel.
    pub rotational: [DVec3; 3],
    /// Radius R (scene units): clamped harmonic mean distance, possibly shrunk by neighbour clamping.
    pub radius: f64,
}

/// The cache's counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CacheCounts {
    /// Records gathered.
    pub records: u64,
    /// Query points.
    pub query_points: u64,
    /// Query points answered by interpolating records (not by a record of their own).
    pub reused: u64,
    /// Build passes so far.
    pub passes: u64,
    /// Hemisphere directions per record (M × N).
    pub samples_per_record: u64,
}

/// The irradiance cache over a fixed set of query points.
pub struct IrradianceCacheSolver<'a> {
    scene: &'a Scene,
    accel: &'a Accel,
    params: IrradianceCacheParams,
    estimator: PathEstimator<'a>,
    seed: u64,
    points: QueryPoints,
    records: Vec<Record>,
    octree: RecordOctree,
    /// Per query point, the record gathered there (or [`NO_RECORD`]).
    site: Vec<u32>,
    answers: Vec<Rgb>,
    strata: (u32, u32),
    r_min: f64,
    r_max: f64,
    passes: u64,
    steps: u64,
    rays: u64,
    converged: bool,
}

impl std::fmt::Debug for IrradianceCacheSolver<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("IrradianceCacheSolver")
            .field("points", &self.points.len())
            .field("records", &self.records.len())
            .field("params", &self.params)
            .finish()
    }
}

impl<'a> IrradianceCacheSolver<'a> {
    /// The cache for `points` (nothing gathered yet: each step is a build pass, the last one answers).
    pub fn new(
        scene: &'a Scene,
        accel: &'a Accel,
        params: IrradianceCacheParams,
        seed: u64,
        points: Vec<SurfacePoint>,
    ) -> Result<Self, SolveError> {
        params.validate()?;
        let points = QueryPoints::new(scene, points)?;
        let (lo, hi) = scene.bounds();
        let diag = scene.diagonal();
        Ok(Self {
            scene,
            accel,
            estimator: PathEstimator::new(scene, accel, params.max_depth, params.direct),
            seed,
            site: vec![NO_RECORD; points.len()],
            answers: Vec::new(),
            points,
            records: Vec::new(),
            octree: RecordOctree::new(lo, hi),
            strata: strata(params.samples),
            r_min: params.min_radius * diag,
            r_max: params.max_radius * diag,
            params,
            passes: 0,
            steps: 0,
            rays: 0,
            converged: false,
        })
    }

    /// The records gathered so far, in insertion order.
    pub fn records(&self) -> &[Record] {
        &self.records
    }

    /// The cache's counters.
    pub fn counts(&self) -> CacheCounts {
        CacheCounts {
            records: self.records.len() as u64,
            query_points: self.points.len() as u64,
            reused: if self.converged {
                self.site.iter().filter(|&&s| s == NO_RECORD).count() as u64
            } else {
                0
            },
            passes: self.passes,
            samples_per_record: (self.strata.0 * self.strata.1) as u64,
        }
    }

    /// A record gathered at (`face`, `x`, `n`) from `rng`.
    fn gather_record(&self, face: FaceId, x: DVec3, n: DVec3, rng: &mut Rng) -> Record {
        let scene = self.scene;
        let g = gather(n, self.strata.0, self.strata.1, rng, |dir, rng| {
            let hit = self.accel.intersect_from(face, x, dir)?;
            let nh = scene.faces[hit.face].normal;
            if !(-nh.dot(dir) > 0.0) {
                return Some((hit.t, Rgb::ZERO)); // a back: absorbed
            }
            Some((
                hit.t,
                self.estimator
                    .reflected_radiosity(hit.face, hit.point, nh, rng),
            ))
        });
        let (translational, rotational) = if self.params.gradients {
            (g.translational, g.rotational)
        } else {
            ([DVec3::ZERO; 3], [DVec3::ZERO; 3])
        };
        Record {
            point: x,
            normal: n,
            face,
            irradiance: g.irradiance,
            translational,
            rotational,
            radius: g.harmonic_distance.clamp(self.r_min, self.r_max),
        }
    }

    /// Indirect irradiance interpolated from the records that serve (`face`, `x`, `n`), or `None` if none does.
    fn interpolate(&self, face: FaceId, x: DVec3, n: DVec3) -> Option<Rgb> {
        let a = self.params.accuracy;
        if !(a > 0.0) {
            return None;
        }
        let (mut sw, mut sum) = (0.0, Rgb::ZERO);
        self.octree.for_each_candidate(x, 0.0, &mut |id| {
            let r = &self.records[id as usize];
            let d = x - r.point;
            let eps = d.length() / r.radius + (1.0 - n.dot(r.normal)).max(0.0).sqrt();
            if !(eps < a) || d.dot(n + r.normal) * 0.5 < -1e-3 * r.radius {
                return;
            }
            if self.params.leak_test && !self.accel.visible_between(r.point, r.face, x, face) {
                return;
            }
            let w = 1.0 / eps.max(1e-9) - 1.0 / a;
            let turn = r.normal.cross(n);
            let value = r.irradiance
                + Rgb::new(
                    turn.dot(r.rotational[0]) + d.dot(r.translational[0]),
                    turn.dot(r.rotational[1]) + d.dot(r.translational[1]),
                    turn.dot(r.rotational[2]) + d.dot(r.translational[2]),
                );
            sw += w;
            sum += w * value;
        });
        (sw > 0.0).then(|| (sum / sw).max(Rgb::ZERO))
    }

    /// Direct irradiance at a point by `direct_samples` next-event samples from `rng`.
    fn direct(&self, face: FaceId, x: DVec3, n: DVec3, rng: &mut Rng) -> Rgb {
        let k = self.params.direct_samples;
        let mut h = Rgb::ZERO;
        for _ in 0..k {
            h += self.estimator.direct_irradiance(face, x, n, rng);
        }
        h / k as f64
    }

    /// Radiosity at a point: its own record if it has one, else the cache, else a fresh (unstored) gather;
    /// random streams `stream` of the direct and gather seeds.
    fn answer(&self, face: FaceId, x: DVec3, n: DVec3, own: u32, stream: u64) -> Rgb {
        let indirect = if own != NO_RECORD {
            self.records[own as usize].irradiance
        } else if let Some(h) = self.interpolate(face, x, n) {
            h
        } else {
            let mut rng = sampling::rng(mix64(self.seed ^ GATHER_STREAM_TAG), stream);
            self.gather_record(face, x, n, &mut rng).irradiance
        };
        let mut rng = sampling::rng(mix64(self.seed ^ DIRECT_STREAM_TAG), stream);
        let h = self.direct(face, x, n, &mut rng) + indirect;
        self.scene.emission(face) + self.scene.reflectance(face) * h
    }

    /// Inserts a record, clamping its radius and its neighbours' (Křivánek et al. 2006).
    fn insert(&mut self, mut rec: Record) -> u32 {
        let a = self.params.accuracy;
        if self.params.neighbour_clamp && a > 0.0 {
            let mut near = Vec::new();
            self.octree
                .for_each_candidate(rec.point, a * rec.radius, &mut |id| near.push(id));
            near.retain(|&id| {
                let r = &self.records[id as usize];
                (r.point - rec.point).length() < a * (r.radius + rec.radius)
            });
            for &id in &near {
                let r = &self.records[id as usize];
                rec.radius = rec.radius.min(r.radius + (r.point - rec.point).length());
            }
            for &id in &near {
                let r = &mut self.records[id as usize];
                r.radius = r.radius.min(rec.radius + (r.point - rec.point).length());
            }
        }
        let id = self.records.len() as u32;
        self.octree.insert(id, rec.point, a * rec.radius);
        self.records.push(rec);
        id
    }

    /// Separation of new sites in the current pass (0 once below a·min_radius).
    fn separation(&self) -> f64 {
        let a = self.params.accuracy;
        let s = a * self.r_max * 0.5f64.powi(self.passes.min(1000) as i32);
        if a > 0.0 && s >= a * self.r_min {
            s
        } else {
            0.0
        }
    }

    /// Chooses new sites among `uncovered` (in order), at least the pass's separation apart.
    fn choose_sites(&self, uncovered: &[usize]) -> Vec<usize> {
        let s = self.separation();
        if s <= 0.0 {
            return uncovered.to_vec();
        }
        let a = self.params.accuracy;
        let r = s / a;
        let cell = |p: DVec3| (p / s).floor().as_i64vec3().to_array();
        let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
        let mut chosen = Vec::new();
        for &i in uncovered {
            let p = &self.points[i];
            let c = cell(p.point);
            let mut served = false;
            'search: for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        let Some(list) = grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) else {
                            continue;
                        };
                        for &j in list {
                            let q = &self.points[j];
                            let d = p.point - q.point;
                            let eps =
                                d.length() / r + (1.0 - p.normal.dot(q.normal)).max(0.0).sqrt();
                            if eps < a && d.dot(p.normal + q.normal) * 0.5 >= -1e-3 * r {
                                served = true;
                                break 'search;
                            }
                        }
                    }
                }
            }
            if !served {
                grid.entry(c).or_default().push(i);
                chosen.push(i);
            }
        }
        chosen
    }

    fn bytes(&self) -> u64 {
        (self.points.bytes()
            + self.records.capacity() * size_of::<Record>()
            + self.octree.bytes()
            + self.site.capacity() * 4
            + self.answers.capacity() * size_of::<Rgb>()) as u64
    }
}

impl Solver for IrradianceCacheSolver<'_> {
    fn step(&mut self) -> Result<Step, SolveError> {
        if self.converged {
            return Ok(Step::Converged);
        }
        let rays0 = self.accel.rays_cast();
        let this = &*self;
        let uncovered: Vec<usize> = (0..this.points.len())
            .into_par_iter()
            .filter(|&i| {
                let p = &this.points[i];
                this.site[i] == NO_RECORD && this.interpolate(p.face, p.point, p.normal).is_none()
            })
            .collect();
        if uncovered.is_empty() {
            let answers: Vec<Rgb> = (0..this.points.len())
                .into_par_iter()
                .map(|i| {
                    let p = &this.points[i];
                    this.answer(p.face, p.point, p.normal, this.site[i], i as u64)
                })
                .collect();
            if answers.iter().any(|b| !b.is_finite()) {
                return Err(SolveError::Numerical(
                    "the irradiance cache produced a non-finite radiosity".into(),
                ));
            }
            self.answers = answers;
            self.converged = true;
        } else {
            let sites = this.choose_sites(&uncovered);
            let gather_seed = mix64(this.seed ^ GATHER_STREAM_TAG);
            let new: Vec<Record> = sites
                .par_iter()
                .map(|&i| {
                    let p = &this.points[i];
                    let mut rng = sampling::rng(gather_seed, i as u64);
                    this.gather_record(p.face, p.point, p.normal, &mut rng)
                })
                .collect();
            for (&i, rec) in sites.iter().zip(new) {
                if !rec.irradiance.is_finite() {
                    return Err(SolveError::Numerical(format!(
                        "the gather at query point {i} produced a non-finite irradiance"
                    )));
                }
                self.site[i] = self.insert(rec);
            }
            self.passes += 1;
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

    fn counters(&self) -> Vec<(&'static str, u64)> {
        let c = self.counts();
        vec![
            ("records", c.records),
            ("query_points", c.query_points),
            ("reused", c.reused),
            ("passes", c.passes),
        ]
    }

    fn stats(&self) -> Stats {
        Stats {
            steps: self.steps,
            elements: self.records.len() as u64,
            links: 0,
            form_factors: 0,
            rays: self.rays,
            bytes: self.bytes(),
            residual: None,
        }
    }
}

impl Solution for IrradianceCacheSolver<'_> {
    /// The answer at a query point once the cache is built (before then, computed from the cache as it
    /// stands); elsewhere the cache interpolated or, where no record serves, a fresh gather (not stored).
    fn radiosity_at(&self, face: FaceId, point: DVec3) -> Rgb {
        if face >= self.scene.faces.len() {
            return Rgb::splat(f64::NAN);
        }
        let n = self.scene.faces[face].normal;
        match self.points.find(face, point) {
            Some(i) if self.converged => self.answers[i],
            Some(i) => self.answer(face, point, n, self.site[i], i as u64),
            None => self.answer(face, point, n, NO_RECORD, coordinate_stream(face, point)),
        }
    }
}

//! The radiosity texture as a [`Solver`] (Heckbert 1990, "Adaptive radiosity textures for bidirectional ray
//! tracing", SIGGRAPH 90, §4–5): light is shot from the emitters and, by Russian roulette, on from every
//! surface it lands on (radlab-pathtrace's `trace_photons`, every bounce kept), and each landing's power is
//! deposited in the rex of the face it lands on (rex.rs). A leaf ℓ of face f then holds
//!
//! B_ℓ = E_f + ρ_f Φ_ℓ / (N_e A_ℓ),
//!
//! Φ_ℓ the power of the landings in it and N_e the particles emitted so far: an unbiased estimate of the leaf's
//! mean radiosity (the collision estimator of particle tracing; Shirley 1991; Bekaert 1999, ch. 4), whose noise is about
//! 1/√(landings in ℓ) and whose bias at a point x is the difference between B(x) and the leaf's mean, O(size
//! × |∇B|). Heckbert shoots progressively from the brightest surfaces; tracing each particle on by Russian
//! roulette carries the same power along the same paths in expectation (Arvo & Kirk 1990) and needs no
//! per-surface unshot power, so every light-tracing method in radlab shares one tracer.
//!
//! Each step is one pass of `particles / passes` landings (streams disjoint between passes); the hit points are
//! kept, the rexes are rebuilt over every landing so far and the leaves re-estimated with N_e over all passes,
//! so the result after k passes is the estimate from all particles so far and does not depend on how they were
//! split into passes but through the streams. Landings on faces that reflect nothing (ρ = 0 in every channel)
//! are not kept: their radiosity is E whatever lands.
//!
//! Points are answered through radlab-answer's [`Reconstructor`] over the leaves: `constant` (the leaf's
//! value), `gouraud` (vertex values fitted per face, bilinear within a quad leaf, T-vertices anchored as for
//! adaptive meshes) or `final-gather`. Rays (particle flights) through the shared `Accel`'s counter; bytes are
//! the kept hits, the cells and the leaf values, plus what the reconstruction has built.

use glam::DVec3;
use radlab_answer::{Reconstructor, gouraud::ElementValue};
use radlab_method::{MethodParams, Solution, SolveError, Solver, Stats, Step};
use radlab_pathtrace::{EmitterSampler, trace_photons};
use radlab_scene::{FaceId, Rgb, Scene, sampling::mix64};
use radlab_visibility::Accel;
use rayon::prelude::*;

use crate::params::{DEFAULT_MIN_CELL_REL, RadiosityTextureParams};
use crate::rex::{Hit, Rex, SplitSettings};

const PARTICLE_STREAM_TAG: u64 = 0x7261_6474_6578_7470; // "radtextp"
/// Chunks of particles reserved per pass (streams never overlap between passes).
const CHUNKS_PER_PASS: u64 = 1 << 32;
/// Marks a cell that is not a leaf in the leaf index.
const INNER: u32 = u32::MAX;

/// The radiosity texture's counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TextureCounts {
    /// Particles emitted so far (N_e).
    pub emitted: u64,
    /// Landings so far (every bounce of every particle).
    pub landings: u64,
    /// Landings kept in the rexes (those on faces that reflect).
    pub kept: u64,
    /// Leaves over all faces.
    pub leaves: u64,
    /// Cells (leaves and inner nodes) over all faces.
    pub cells: u64,
    /// The deepest leaf's depth.
    pub depth: u64,
    /// Passes done.
    pub passes: u64,
}

/// The textures: a rex per face and the radiosity of its cells.
struct Textures<'a> {
    scene: &'a Scene,
    accel: &'a Accel,
    rexes: Vec<Rex>,
    /// Radiosity of every cell of every face (inner cells: their subtree's mean).
    radiosity: Vec<Vec<Rgb>>,
    /// Global leaf index of every cell ([`INNER`] for inner cells), in face then cell order.
    leaf_index: Vec<Vec<u32>>,
    leaves: u64,
    output: Reconstructor,
}

impl Textures<'_> {
    fn leaf(&self, face: FaceId, point: DVec3) -> usize {
        let st = self.scene.polygon(face).param_coords(point);
        self.rexes[face].leaf_at(st)
    }

    fn values(&self) -> Vec<ElementValue> {
        let mut out = Vec::with_capacity(self.leaves as usize);
        for (f, rex) in self.rexes.iter().enumerate() {
            for l in rex.leaves() {
                out.push(ElementValue {
                    face: f,
                    polygon: rex.cells()[l].polygon,
                    radiosity: self.radiosity[f][l],
                    open: 1.0,
                });
            }
        }
        out
    }

    fn bytes(&self) -> usize {
        self.rexes.iter().map(Rex::bytes).sum::<usize>()
            + self
                .radiosity
                .iter()
                .map(|v| v.capacity() * size_of::<Rgb>())
                .sum::<usize>()
            + self
                .leaf_index
                .iter()
                .map(|v| v.capacity() * size_of::<u32>())
                .sum::<usize>()
            + self.output.bytes()
    }
}

impl Solution for Textures<'_> {
    fn answer_kernel_evaluations(&self) -> u64 {
        self.output.gather_work().1
    }

    fn radiosity_at(&self, face: FaceId, point: DVec3) -> Rgb {
        if face >= self.scene.faces.len() {
            return Rgb::splat(f64::NAN);
        }
        let cell = || self.leaf(face, point);
        self.output.radiosity_at(
            self.scene,
            self.accel,
            face,
            point,
            || self.radiosity[face][cell()],
            || Some(self.leaf_index[face][cell()] as usize),
            || self.values(),
        )
    }
}

/// Adaptive radiosity textures (Heckbert 1990) as a [`Solver`]: one pass of particles per step.
pub struct RadiosityTextureSolver<'a> {
    params: RadiosityTextureParams,
    seed: u64,
    emitters: EmitterSampler,
    split: SplitSettings,
    /// Kept landings per face, in emission order.
    hits: Vec<Vec<Hit>>,
    counts: TextureCounts,
    rays: u64,
    solution: Textures<'a>,
}

impl std::fmt::Debug for RadiosityTextureSolver<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RadiosityTextureSolver")
            .field("counts", &self.counts)
            .field("params", &self.params)
            .finish()
    }
}

impl<'a> RadiosityTextureSolver<'a> {
    /// The textures of `scene`, each face one leaf holding its emission (nothing traced yet). Fails on invalid
    /// parameters, naming the key.
    pub fn new(
        scene: &'a Scene,
        accel: &'a Accel,
        params: RadiosityTextureParams,
        seed: u64,
    ) -> Result<Self, SolveError> {
        params.validate()?;
        let min_cell = params
            .min_cell
            .unwrap_or_else(|| DEFAULT_MIN_CELL_REL * scene.diagonal());
        if !(min_cell.is_finite() && min_cell > 0.0) {
            return Err(SolveError::param(
                "min_cell",
                format!(
                    "the default smallest cell of this scene is {min_cell}; set min_cell explicitly"
                ),
            ));
        }
        let split = SplitSettings {
            rule: params.split,
            threshold: params.split_threshold,
            min_cell,
        };
        let faces = scene.faces.len();
        let rexes: Vec<Rex> = (0..faces)
            .map(|f| Rex::build(scene.polygon(f), &[], split))
            .collect();
        let solution = Textures {
            scene,
            accel,
            radiosity: (0..faces).map(|f| vec![scene.emission(f)]).collect(),
            leaf_index: (0..faces).map(|f| vec![f as u32]).collect(),
            leaves: faces as u64,
            rexes,
            output: Reconstructor::of(&params.answer, seed),
        };
        Ok(Self {
            emitters: EmitterSampler::new(scene),
            seed,
            split,
            hits: vec![Vec::new(); faces],
            counts: TextureCounts {
                leaves: faces as u64,
                cells: faces as u64,
                ..TextureCounts::default()
            },
            rays: 0,
            solution,
            params,
        })
    }

    /// The counters.
    pub fn counts(&self) -> TextureCounts {
        self.counts
    }

    /// The rex of face `f`.
    pub fn rex(&self, f: FaceId) -> &Rex {
        &self.solution.rexes[f]
    }

    /// The radiosity of cell `cell` of face `f`'s rex (a leaf's B = E + ρ Φ/(N_e A); an inner cell's, its
    /// subtree's mean).
    pub fn cell_radiosity(&self, f: FaceId, cell: usize) -> Rgb {
        self.solution.radiosity[f][cell]
    }

    /// The smallest cell size the split rule allows (scene units).
    pub fn min_cell(&self) -> f64 {
        self.split.min_cell
    }

    /// Landings for pass `pass` (0-based): an equal share, the last pass taking the remainder.
    fn pass_target(&self, pass: u64) -> u64 {
        let passes = u64::from(self.params.passes);
        let share = self.params.particles / passes;
        if pass + 1 == passes {
            self.params.particles - share * (passes - 1)
        } else {
            share
        }
    }

    /// One pass: trace, keep the landings, rebuild the rexes and re-estimate every cell.
    fn pass(&mut self) -> Result<(), SolveError> {
        let scene = self.solution.scene;
        let accel = self.solution.accel;
        let pass = self.counts.passes;
        let batch = trace_photons(
            scene,
            accel,
            &self.emitters,
            self.pass_target(pass),
            pass * CHUNKS_PER_PASS,
            mix64(self.seed ^ PARTICLE_STREAM_TAG),
            self.params.max_depth,
            &|_| true,
        );
        self.counts.emitted += batch.emitted;
        self.counts.landings += batch.photons.len() as u64;
        let reflects: Vec<bool> = (0..scene.faces.len())
            .map(|f| scene.reflectance(f).max_element() > 0.0)
            .collect();
        let kept: Vec<(FaceId, Hit)> = batch
            .photons
            .par_iter()
            .filter(|p| reflects[p.face])
            .map(|p| {
                (
                    p.face,
                    Hit {
                        st: scene.polygon(p.face).param_coords(p.point),
                        power: p.power,
                    },
                )
            })
            .collect();
        self.counts.kept += kept.len() as u64;
        for (f, h) in kept {
            self.hits[f].push(h);
        }
        let split = self.split;
        let hits = &self.hits;
        self.solution.rexes = (0..scene.faces.len())
            .into_par_iter()
            .map(|f| Rex::build(scene.polygon(f), &hits[f], split))
            .collect();
        let n_e = self.counts.emitted;
        let radiosity: Vec<Vec<Rgb>> = self
            .solution
            .rexes
            .par_iter()
            .enumerate()
            .map(|(f, rex)| {
                let (e, rho) = (scene.emission(f), scene.reflectance(f));
                rex.cells()
                    .iter()
                    .map(|c| {
                        if n_e == 0 || c.count == 0 {
                            e
                        } else {
                            e + rho * c.power / (n_e as f64 * c.area)
                        }
                    })
                    .collect()
            })
            .collect();
        if let Some((f, _)) = radiosity
            .iter()
            .enumerate()
            .find(|(_, v)| v.iter().any(|b| !b.is_finite()))
        {
            return Err(SolveError::Numerical(format!(
                "face {f}'s radiosity texture got a non-finite value"
            )));
        }
        let mut next = 0u32;
        self.solution.leaf_index = self
            .solution
            .rexes
            .iter()
            .map(|rex| {
                rex.cells()
                    .iter()
                    .map(|c| {
                        if c.is_leaf() {
                            next += 1;
                            next - 1
                        } else {
                            INNER
                        }
                    })
                    .collect()
            })
            .collect();
        self.solution.radiosity = radiosity;
        self.solution.leaves = u64::from(next);
        self.solution.output.invalidate();
        self.counts.leaves = u64::from(next);
        self.counts.cells = self
            .solution
            .rexes
            .iter()
            .map(|r| r.cells().len() as u64)
            .sum();
        self.counts.depth = self
            .solution
            .rexes
            .iter()
            .map(|r| u64::from(r.depth()))
            .max()
            .unwrap_or(0);
        self.counts.passes += 1;
        Ok(())
    }

    fn bytes(&self) -> u64 {
        (self
            .hits
            .iter()
            .map(|h| h.capacity() * size_of::<Hit>())
            .sum::<usize>()
            + self.solution.bytes()) as u64
    }
}

impl Solver for RadiosityTextureSolver<'_> {
    fn step(&mut self) -> Result<Step, SolveError> {
        if self.counts.passes >= u64::from(self.params.passes) {
            return Ok(Step::Converged);
        }
        let rays0 = self.solution.accel.rays_cast();
        let result = self.pass();
        self.rays += self.solution.accel.rays_cast() - rays0;
        result?;
        Ok(if self.counts.passes >= u64::from(self.params.passes) {
            Step::Converged
        } else {
            Step::Continue
        })
    }

    fn solution(&self) -> &dyn Solution {
        &self.solution
    }

    fn stats(&self) -> Stats {
        Stats {
            steps: self.counts.passes,
            elements: self.counts.leaves,
            links: 0,
            form_factors: 0,
            rays: self.rays,
            bytes: self.bytes(),
            residual: None,
        }
    }

    fn counters(&self) -> Vec<(&'static str, u64)> {
        let c = self.counts;
        vec![
            ("particles", c.emitted),
            ("landings", c.landings),
            ("kept", c.kept),
            ("leaves", c.leaves),
            ("cells", c.cells),
            ("depth", c.depth),
        ]
    }
}

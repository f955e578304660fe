//! Mesh-based Monte Carlo radiosity (Shirley 1991; Neumann et al. 1995; Bekaert 1999): a view-independent solution over a fixed element mesh,
//! estimated by particles shot from the emitters and deposited on the elements they hit, as a [`Solver`].
//!
//! The unknowns are those of the discretised radiosity system (Cohen & Wallace 1993, ch. 3), written for powers
//! P_j = A_j B_j: P_j = A_j E_j + ρ_j Σ_i F_ij P_i. A particle leaving a uniformly chosen point of element i
//! in a cosine-distributed direction lands on element j with probability exactly F_ij (visibility included),
//! so tallying the power Φ_j arriving at each element estimates the incident powers without computing a
//! single form factor (Shirley 1991; Neumann et al. 1995; Bekaert 1999, ch. 4–5), and
//!
//! B_j = E_j + ρ_j Φ_j / A_j.
//!
//! Sealed contacts (a floor covering 1 mm above the floor, a lamp just under the ceiling): the part of an
//! element that sees only a panel's back receives nothing, and light re-emitted from it is absorbed by that
//! back, so every element crossed by such an edge would lose the sealed share of what it reflects (the
//! light leaks of Baum, Mann, Smith & Winget 1991). As matrix and progressive radiosity do, the first step
//! estimates each element's open fraction o_j ([`radlab_kernels::open_fraction`]) and the solver solves the
//! open-area system, B_j the radiosity of the open part:
//!
//! o_j A_j B_j = o_j A_j E_j + ρ_j Σ_i A_i F_ij B_i,   B_j = E_j + ρ_j Φ_j / (o_j A_j),
//!
//! with F_ij the form factor from *all* of element i (its sealed points see nothing, so A_i F_ij already
//! carries the factor o_i). Power P_i = o_i A_i B_i leaving element i's open part therefore reaches j as
//! A_i F_ij B_i = (P_i / o_i) F_ij: a particle still leaves from a uniform point of the whole element, with
//! its power divided by o_i. Those leaving sealed points die on the panel's back, or at the front of a face
//! over the gap they leave (a cube's bottom on the floor: `hit_closes` ends every flight the seal test would
//! close), share 1 − o_i; the rest carry P_i / o_i × o_i = P_i on average, so the estimator stays unbiased for the open-area system with
//! no per-point sealed test, and converges to what matrix radiosity solves on the same mesh and open
//! fractions. Emitters need no factor: A_e E_e shot from all of element e is (o_e A_e E_e) / o_e. Where
//! nothing is sealed, o = 1 and nothing changes.
//!
//! Two estimators ([`McMethod`]), both unbiased for the given mesh (they converge to what matrix radiosity
//! solves, up to its form-factor quadrature error) and both with error ∝ 1/√particles:
//! - `random-walk` (random_walk.rs): discrete collision-shooting random walks;
//! - `stochastic-jacobi` (stochastic_jacobi.rs): Bekaert's stochastic Jacobi iteration.
//!
//! Each [`Solver::step`] runs `particles_per_step` fresh particles (an independent estimate); the solution
//! after k steps is the mean over the k steps, i.e. over every particle so far, and the spread of the step
//! estimates gives each element's standard error. Particles draw from streams derived from (seed, step,
//! particle index) and deposits are summed in a fixed order, so results are bit-identical for any number of
//! threads.

use glam::DVec3;
use radlab_answer::{
    AnswerParams, ElementMesh, Reconstructor, element_size, gouraud::ElementValue,
};
use radlab_kernels::open_fraction::{SEAL_GAP_REL, hit_closes, open_fractions};
use radlab_method::{MethodParams, Solution, SolveError, Solver, Stats, Step};
use radlab_scene::{
    FaceId, Rgb, Scene,
    sampling::{self, Rng},
};
use radlab_visibility::Accel;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::discrete_distribution::Discrete;
use crate::emitter_sampling::channel_mean;
use crate::point_estimator::DEFAULT_MAX_DEPTH;
use crate::{random_walk, stochastic_jacobi};

/// Which Monte Carlo estimator of the element radiosities to run.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum McMethod {
    /// Discrete shooting random walks with the collision estimator (Shirley 1991; Sbert 1993; Bekaert 1999
    /// §4.3): each particle starts on an emitting element chosen by power, every landing is tallied, and it
    /// survives with probability ρ (Russian roulette), re-emitted from a uniform point of the element it hit.
    /// The default.
    #[default]
    RandomWalk,
    /// Stochastic Jacobi iteration (Neumann et al. 1995; Bekaert 1999 §5.2): generation k shoots the power
    /// received in generation k − 1, with particles of equal power chosen over elements by unshot power and
    /// their number rounded stochastically, until no power is left. Same cost; spreads samples by power
    /// rather than by path, which suits scenes with many weak secondary sources.
    StochasticJacobi,
}

/// Parameters of mesh-based Monte Carlo radiosity, each declared once on its field (doc comment: help;
/// `schemars` attribute: range; default: `impl Default`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct McRadiosityParams {
    /// Element edge length in scene units; unset: 1/25 of the scene's bounding diagonal, as for matrix.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub element_size: Option<f64>,
    /// Particles shot from the emitters per step.
    #[schemars(range(min = 1))]
    pub particles_per_step: u64,
    /// Steps before convergence is reported; the result is the mean over all steps.
    #[schemars(range(min = 1))]
    pub max_steps: u64,
    /// The estimator: random-walk (collision-shooting random walks) or stochastic-jacobi.
    pub method: McMethod,
    /// Cap on bounces per particle (random walk) or generations per step (stochastic Jacobi); Russian roulette
    /// ends walks without bias, the cap only guards against runaway walks.
    #[schemars(range(min = 1))]
    pub max_depth: u32,
    /// How points are answered: reconstruction and gather_opening, declared once in radlab-answer.
    #[serde(flatten)]
    pub answer: AnswerParams,
}

impl Default for McRadiosityParams {
    fn default() -> Self {
        Self {
            element_size: None,
            particles_per_step: 100_000,
            max_steps: 100,
            method: McMethod::RandomWalk,
            max_depth: DEFAULT_MAX_DEPTH,
            // The final gather, chosen by measurement (docs/methods.md gives the figures): it averages out
            // the elements' noise and sees which points are sealed.
            answer: AnswerParams::default(),
        }
    }
}

impl MethodParams for McRadiosityParams {
    /// An opening other than the default is refused under answers other than a final gather.
    fn check_combination(&self) -> Result<(), SolveError> {
        self.answer.check(&Self::default().answer)
    }
}

/// What the particle estimators share: the mesh, where particles start, and how they fly.
pub(crate) struct Transport<'a> {
    pub scene: &'a Scene,
    pub accel: &'a Accel,
    pub mesh: &'a ElementMesh,
    /// Emitting elements, chosen with probability A_e Ē_e / Σ.
    pub sources: &'a Discrete,
    pub source_elements: &'a [usize],
    /// Open fraction o_j of each element ([`radlab_kernels::open_fraction`]): a particle leaving element j
    /// carries the power of its open part divided by o_j (see the module documentation).
    pub open: &'a [f64],
    pub max_depth: u32,
}

impl Transport<'_> {
    /// Σ_e A_e Ē_e: the scalar emitted power.
    pub(crate) fn emitted_power(&self) -> f64 {
        self.sources.total()
    }

    /// Reflectance of element `e`.
    pub(crate) fn reflectance(&self, e: usize) -> Rgb {
        self.scene.reflectance(self.mesh.elements[e].face as FaceId)
    }

    /// Emission of element `e`.
    pub(crate) fn emission(&self, e: usize) -> Rgb {
        self.scene.emission(self.mesh.elements[e].face as FaceId)
    }

    /// The power to shoot from all of element `e` for `power` reflected by its open part: ρ_e ⊙ power / o_e.
    pub(crate) fn reflected(&self, e: usize, power: Rgb) -> Rgb {
        power * self.reflectance(e) / self.open[e]
    }

    /// Flies a particle from a uniform point of element `from` in a cosine-distributed direction about its
    /// normal (landing on element j with probability F_ij); returns the element whose front it lands on.
    pub(crate) fn shoot(&self, from: usize, rng: &mut Rng) -> Option<usize> {
        let el = &self.mesh.elements[from];
        let f = el.face as FaceId;
        let x = el
            .polygon
            .sample_uniform(sampling::uniform(rng), sampling::uniform(rng));
        let dir = sampling::cosine_hemisphere(
            self.scene.faces[f].normal,
            sampling::uniform(rng),
            sampling::uniform(rng),
        );
        let hit = self.accel.intersect_from(f, x, dir)?;
        // The back of a face absorbs; so does the front of one over a gap the flight leaves (a cube's bottom
        // lying on the floor): light from a sealed point never reaches the open scene, as the open fractions
        // assume (module documentation).
        let gap = SEAL_GAP_REL * self.scene.diagonal();
        if hit_closes(self.scene, f, dir, hit.face, hit.t, gap) {
            return None;
        }
        Some(self.mesh.locate(hit.face, hit.point))
    }
}

/// A seed for one (step, generation) of a computation seeded with `seed`.
pub(crate) fn derive_seed(seed: u64, a: u64, b: u64) -> u64 {
    sampling::mix64(seed ^ sampling::mix64(a ^ sampling::mix64(b ^ 0xA076_1D64_78BD_642F)))
}

/// Piecewise-constant radiosity over the element mesh.
struct MeshSolution<'a> {
    scene: &'a Scene,
    accel: &'a Accel,
    mesh: ElementMesh,
    /// Radiosity of each element's open part.
    radiosity: Vec<Rgb>,
    /// Open fraction of each element (all 1 before the first step).
    open: Vec<f64>,
    output: Reconstructor,
}

impl MeshSolution<'_> {
    /// The elements' values for Gouraud vertices and final gathers, each with its open fraction.
    fn values(&self) -> Vec<ElementValue> {
        let mut v = self.mesh.values(&self.radiosity);
        for (x, &o) in v.iter_mut().zip(&self.open) {
            x.open = o;
        }
        v
    }
}

impl Solution for MeshSolution<'_> {
    fn answer_kernel_evaluations(&self) -> u64 {
        self.output.gather_work().1
    }

    fn radiosity_at(&self, face: FaceId, point: DVec3) -> Rgb {
        if face >= self.scene.faces.len() {
            return Rgb::splat(f64::NAN);
        }
        let element = || self.mesh.locate(face, point);
        self.output.radiosity_at(
            self.scene,
            self.accel,
            face,
            point,
            || self.radiosity[element()],
            || Some(element()),
            || self.values(),
        )
    }
}

/// Mesh-based Monte Carlo radiosity as a [`Solver`]: one batch of particles per step.
pub struct McRadiositySolver<'a> {
    accel: &'a Accel,
    params: McRadiosityParams,
    seed: u64,
    solution: MeshSolution<'a>,
    /// Σ over steps of squared deviations of the step estimates (Welford).
    m2: Vec<Rgb>,
    sources: Discrete,
    source_elements: Vec<usize>,
    steps: u64,
    rays: u64,
    /// Whether the open fractions have been estimated (the first step does it).
    open_estimated: bool,
}

impl<'a> McRadiositySolver<'a> {
    /// Meshes the scene and prepares the sources. Fails on invalid parameters.
    pub fn new(
        scene: &'a Scene,
        accel: &'a Accel,
        params: McRadiosityParams,
        seed: u64,
    ) -> Result<Self, SolveError> {
        params.validate()?;
        let size = element_size(params.element_size, scene)?;
        let mesh = ElementMesh::new(scene, size);
        let source_elements: Vec<usize> = (0..mesh.len())
            .filter(|&e| scene.material(mesh.elements[e].face as FaceId).is_emitter())
            .collect();
        let sources = Discrete::new(source_elements.iter().map(|&e| {
            mesh.elements[e].area * channel_mean(scene.emission(mesh.elements[e].face as FaceId))
        }));
        let radiosity = mesh
            .elements
            .iter()
            .map(|el| scene.emission(el.face as FaceId))
            .collect();
        let output = Reconstructor::of(&params.answer, seed);
        let n = mesh.len();
        Ok(Self {
            accel,
            params,
            seed,
            solution: MeshSolution {
                scene,
                accel,
                output,
                open: vec![1.0; mesh.len()],
                mesh,
                radiosity,
            },
            m2: vec![Rgb::ZERO; n],
            sources,
            source_elements,
            steps: 0,
            rays: 0,
            open_estimated: false,
        })
    }

    /// The element mesh solved over.
    pub fn mesh(&self) -> &ElementMesh {
        &self.solution.mesh
    }

    /// Radiosity per element over its open part (the mean over all steps so far; E before the first step).
    pub fn element_radiosity(&self) -> &[Rgb] {
        &self.solution.radiosity
    }

    /// The open fraction o_j of each element ([`radlab_kernels::open_fraction`]), estimated in the first step
    /// (all 1 before it): the element's power is o_j A_j B_j.
    pub fn open_fractions(&self) -> &[f64] {
        &self.solution.open
    }

    /// Standard error of each element's radiosity, from the spread of the step estimates (`None` before
    /// two steps).
    pub fn element_std_error(&self) -> Option<Vec<Rgb>> {
        if self.steps < 2 {
            return None;
        }
        let k = self.steps as f64;
        Some(
            self.m2
                .iter()
                .map(|m2| (m2.max(Rgb::ZERO) / ((k - 1.0) * k)).sqrt())
                .collect(),
        )
    }

    /// Particles shot so far from the emitters.
    pub fn particles(&self) -> u64 {
        self.steps * self.params.particles_per_step
    }

    /// Relative standard error of the whole solution: √(Σ A_j se_j²) / √(Σ A_j B_j²), channel means.
    fn relative_std_error(&self) -> Option<f64> {
        let se = self.element_std_error()?;
        let mesh = &self.solution.mesh;
        let (mut num, mut den) = (0.0, 0.0);
        for (e, (s, b)) in se.iter().zip(&self.solution.radiosity).enumerate() {
            let a = mesh.elements[e].area;
            num += a * channel_mean(*s * *s);
            den += a * channel_mean(*b * *b);
        }
        (den > 0.0).then(|| (num / den).sqrt())
    }
}

impl Solver for McRadiositySolver<'_> {
    fn step(&mut self) -> Result<Step, SolveError> {
        if self.steps >= self.params.max_steps {
            return Ok(Step::Converged);
        }
        if !self.open_estimated {
            let mesh = &self.solution.mesh;
            let (open, rays) = open_fractions(
                self.solution.scene,
                self.accel,
                &mesh.elements,
                |e| (&e.polygon, e.face as FaceId),
                self.seed,
                0,
            );
            self.solution.open = open;
            self.rays += rays;
            self.open_estimated = true;
        }
        let transport = Transport {
            scene: self.solution.scene,
            accel: self.accel,
            mesh: &self.solution.mesh,
            sources: &self.sources,
            source_elements: &self.source_elements,
            open: &self.solution.open,
            max_depth: self.params.max_depth,
        };
        let n = self.params.particles_per_step;
        let (incident, rays) = if self.sources.is_empty() {
            (vec![Rgb::ZERO; self.solution.mesh.len()], 0)
        } else {
            match self.params.method {
                McMethod::RandomWalk => {
                    random_walk::shoot_walks(&transport, n, self.steps * n, self.seed)
                }
                McMethod::StochasticJacobi => {
                    stochastic_jacobi::run(&transport, n, derive_seed(self.seed, self.steps, 0))
                }
            }
        };
        self.rays += rays;
        self.steps += 1;
        self.solution.output.invalidate();
        let k = self.steps as f64;
        let mesh = &self.solution.mesh;
        for (e, phi) in incident.iter().enumerate() {
            let open_area = self.solution.open[e] * mesh.elements[e].area;
            let b = transport.emission(e) + transport.reflectance(e) * *phi / open_area;
            if !b.is_finite() {
                return Err(SolveError::Numerical(format!(
                    "element {e} (face {}) got a non-finite radiosity estimate",
                    mesh.elements[e].face
                )));
            }
            let mean = &mut self.solution.radiosity[e];
            let delta = b - *mean;
            *mean += delta / k;
            self.m2[e] += delta * (b - *mean);
        }
        Ok(if self.steps >= self.params.max_steps {
            Step::Converged
        } else {
            Step::Continue
        })
    }

    fn solution(&self) -> &dyn Solution {
        &self.solution
    }

    fn stats(&self) -> Stats {
        let n = self.solution.mesh.len();
        Stats {
            steps: self.steps,
            elements: n as u64,
            links: 0,
            form_factors: 0,
            rays: self.rays,
            bytes: (self.solution.mesh.bytes()
                + 2 * n * size_of::<Rgb>()
                + n * size_of::<f64>()
                + self.source_elements.len() * (size_of::<usize>() + size_of::<f64>())
                + self.solution.output.bytes()) as u64,
            residual: self.relative_std_error(),
        }
    }
}

//! The progressive radiosity solver (Cohen, Chen, Wallace & Greenberg 1988): Southwell shooting over a
//! substructured mesh (Cohen et al. 1986) with adaptive subdivision and the ambient term, driven one step at a
//! time through [`radlab_method::Solver`].
//!
//! A step shoots `shots_per_step` patches one after another (each the one with the largest unshot power at the
//! time, [`crate::shooting`]), then, if adaptive subdivision is on, splits elements across large contrasts
//! ([`crate::adaptive_subdivision`]). It stops when the unshot power falls to `stop_unshot_fraction` of the
//! emitted power: at that point, in a closed scene of reflectance ρ, the light still to arrive is about
//! ρ/(1 − ρ) times the unshot power while the total is Φ/(1 − ρ), so the radiosity is short by a fraction of
//! about ρ · (unshot fraction) — below the stopping fraction whatever ρ.

use glam::DVec3;
use std::sync::OnceLock;

use radlab_answer::gouraud::ElementValue;
use radlab_answer::{AnswerParams, Reconstruction, Reconstructor};
use radlab_method::{Solution, SolveError, Solver, Stats, Step};
use radlab_scene::{FaceId, Polygon, Rgb, Scene};
use radlab_visibility::Accel;

use crate::adaptive_subdivision::{self, Refinement};
use crate::ambient;
use crate::element_location::ElementLocator;
use crate::params::{Overshoot, ProgressiveParams, Resolved};
use crate::shooting::{self, Interreflection, Kernel, Work};
use crate::substructuring::{BYTES_PER_ELEMENT, Mesh};

/// Why the solver stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StopReason {
    /// The unshot power fell to `stop_unshot_fraction` of the emitted power.
    UnshotFraction,
    /// `max_shots` shots were taken.
    MaxShots,
    /// No patch has unshot power (nothing emits, or every reflectance is zero and the emitters have shot).
    NothingToShoot,
}

impl StopReason {
    /// What a step reports once the solver stopped for this reason: the cap on shots is no convergence.
    pub fn step(self) -> Step {
        match self {
            StopReason::MaxShots => Step::Capped,
            StopReason::UnshotFraction | StopReason::NothingToShoot => Step::Converged,
        }
    }
}

/// One leaf element of the current solution.
#[derive(Clone, Copy, Debug)]
pub struct ElementView {
    /// The input face it lies on.
    pub face: FaceId,
    /// Its geometry.
    pub polygon: Polygon,
    /// Area.
    pub area: f64,
    /// Radiosity (W/m²) of its open part, without the ambient term.
    pub radiosity: Rgb,
    /// Its open share ([`radlab_kernels::open_fraction`]; 1 unless estimated): the element's power is
    /// `open · area · radiosity`.
    pub open: f64,
}

/// The current solution: constant radiosity per leaf element, plus the ambient term when it is on.
#[derive(Clone, Debug)]
pub struct ProgressiveSolution {
    mesh: Mesh,
    locator: ElementLocator,
    reflectance: Vec<Rgb>,
    ambient: Rgb,
}

impl Solution for ProgressiveSolution {
    fn radiosity_at(&self, face: FaceId, point: DVec3) -> Rgb {
        match self.locator.locate(&self.mesh, face, point) {
            Some(e) => self.mesh.radiosity[e as usize] + self.reflectance[face] * self.ambient,
            None => Rgb::ZERO,
        }
    }
}

/// Progressive radiosity over one scene. See the crate documentation for the method and its parameters.
pub struct ProgressiveSolver<'a> {
    scene: &'a Scene,
    accel: &'a Accel,
    params: ProgressiveParams,
    lengths: Resolved,
    kernel: Kernel,
    solution: ProgressiveSolution,
    pairs: Vec<(u32, u32)>,
    has_shot: Vec<bool>,
    shot_patches: Vec<u32>,
    weights: Rgb,
    interreflection: Rgb,
    overshooting: Interreflection,
    scratch: Vec<f64>,
    max_elements: usize,
    steps: u64,
    shots: u64,
    elements_split: u64,
    work: Work,
    stop: Option<StopReason>,
    output: Output,
    /// Whether the elements' open shares have been estimated (the first step does it).
    open_estimated: bool,
}

impl std::fmt::Debug for ProgressiveSolver<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ProgressiveSolver")
            .field("scene", &self.scene.name)
            .field("params", &self.params)
            .field("elements", &self.element_count())
            .field("patches", &self.patch_count())
            .field("shots", &self.shots)
            .finish()
    }
}

impl<'a> ProgressiveSolver<'a> {
    /// Meshes `scene` into patches and elements and sets the emitters' unshot radiosity. `accel` must be built
    /// over the same scene. Fails on bad parameters (naming the parameter) or a mesh over the memory budget.
    pub fn new(
        scene: &'a Scene,
        accel: &'a Accel,
        params: ProgressiveParams,
        seed: u64,
    ) -> Result<Self, SolveError> {
        let lengths = params.resolve(scene)?;
        let budget = params.memory_budget_mib * 1024.0 * 1024.0;
        let mesh = Mesh::new(scene, lengths.patch_size, lengths.element_size, budget)?;
        let locator = ElementLocator::new(scene, &mesh);
        let pairs = if params.adaptive {
            adaptive_subdivision::neighbour_pairs(scene, &mesh, &locator)
        } else {
            Vec::new()
        };
        let weights = shooting::channel_weights(scene.emitted_power());
        let n_patches = mesh.patches.len();
        let mut s = Self {
            scene,
            accel,
            kernel: Kernel {
                quadrature: params.quadrature,
                visibility: params.visibility,
                indirect_visibility: params.indirect_visibility,
                seed,
            },
            lengths,
            solution: ProgressiveSolution {
                mesh,
                locator,
                reflectance: (0..scene.face_count())
                    .map(|f| scene.reflectance(f))
                    .collect(),
                ambient: Rgb::ZERO,
            },
            pairs,
            has_shot: vec![false; n_patches],
            shot_patches: Vec::new(),
            weights,
            interreflection: ambient::interreflection_factor(scene),
            overshooting: Interreflection::new(scene),
            scratch: Vec::new(),
            max_elements: (budget / BYTES_PER_ELEMENT) as usize,
            steps: 0,
            shots: 0,
            elements_split: 0,
            work: Work::default(),
            stop: None,
            output: Output::new(&params.answer, seed),
            open_estimated: false,
            params,
        };
        s.update_ambient();
        Ok(s)
    }

    fn update_ambient(&mut self) {
        self.solution.ambient = if self.params.ambient {
            ambient::ambient_radiosity(&self.solution.mesh.patches, self.interreflection)
        } else {
            Rgb::ZERO
        };
    }

    /// The stopping rule, checked before each shot.
    fn check_stop(&self) -> Option<StopReason> {
        if self.unshot_fraction() <= self.params.stop_unshot_fraction {
            Some(StopReason::UnshotFraction)
        } else if self.params.max_shots.is_some_and(|m| self.shots >= m) {
            Some(StopReason::MaxShots)
        } else {
            None
        }
    }

    /// Shots taken so far.
    pub fn shots(&self) -> u64 {
        self.shots
    }

    /// Unshot power over emitted power, worst channel (0 if nothing emits). Also [`Stats::residual`].
    pub fn unshot_fraction(&self) -> f64 {
        shooting::unshot_fraction(&self.solution.mesh.patches, self.weights)
    }

    /// Unshot power per channel, Σ_p A_p |ΔB_p| (W).
    pub fn unshot_power(&self) -> Rgb {
        shooting::unshot_power(&self.solution.mesh.patches)
    }

    /// Why the solver stopped, once it has.
    pub fn stop_reason(&self) -> Option<StopReason> {
        self.stop
    }

    /// Number of leaf elements (the solution's pieces).
    pub fn element_count(&self) -> usize {
        self.solution.mesh.leaves.len()
    }

    /// Number of shooting patches.
    pub fn patch_count(&self) -> usize {
        self.solution.mesh.patches.len()
    }

    /// Elements split by adaptive subdivision so far.
    pub fn elements_split(&self) -> u64 {
        self.elements_split
    }

    /// The resolved (element size, patch size, minimum element size), scene units.
    pub fn sizes(&self) -> (f64, f64, f64) {
        (
            self.lengths.element_size,
            self.lengths.patch_size,
            self.lengths.min_element_size,
        )
    }

    /// The leaf elements with their radiosity (without the ambient term), in element order.
    pub fn elements(&self) -> Vec<ElementView> {
        let mesh = &self.solution.mesh;
        mesh.leaves
            .iter()
            .map(|&e| {
                let el = &mesh.elements[e as usize];
                ElementView {
                    face: el.face as usize,
                    polygon: el.polygon,
                    area: el.area,
                    radiosity: mesh.radiosity[e as usize],
                    open: el.open,
                }
            })
            .collect()
    }

    /// Radiosity of every patch: the area mean of its elements.
    pub fn patch_radiosities(&self) -> Vec<Rgb> {
        (0..self.patch_count())
            .map(|p| self.solution.mesh.patch_radiosity(p))
            .collect()
    }

    /// The ambient radiosity B_amb currently added to displayed radiosity (zero when `ambient` is off).
    pub fn ambient(&self) -> Rgb {
        self.solution.ambient
    }

    /// The concrete solution (also available as `&dyn Solution` through [`Solver::solution`]).
    pub fn progressive_solution(&self) -> &ProgressiveSolution {
        &self.solution
    }

    /// The parameters in use.
    pub fn params(&self) -> &ProgressiveParams {
        &self.params
    }

    /// Whether elements carry open shares ([`radlab_kernels::open_fraction`]): only where both visibility
    /// estimates sample the receiver's area does its sealed share enter the form factors; otherwise every open
    /// share stays 1.
    fn open_shares_apply(&self) -> bool {
        self.kernel.visibility.is_area_sampled()
            && self.kernel.indirect_visibility.is_area_sampled()
    }

    /// The settings of adaptive subdivision.
    fn refinement(&self) -> Refinement {
        Refinement {
            threshold: self.params.adaptive_threshold,
            min_element_size: self.lengths.min_element_size,
            max_elements: self.max_elements,
            estimate_open: self.open_shares_apply(),
        }
    }

    /// Shoots once, if the stopping rule allows; returns whether it did, and with `scan`, the contrast scan of
    /// adaptive subdivision after the shot ([`adaptive_subdivision::scan`]), taken on another rayon task while
    /// this one sums the shot over the patches (the two read disjoint data).
    fn shoot_once(&mut self, scan: bool) -> (bool, Option<Vec<u32>>) {
        if let Some(reason) = self.check_stop() {
            self.stop = Some(reason);
            return (false, None);
        }
        let patches = &self.solution.mesh.patches;
        let ambient = match self.params.overshoot {
            Overshoot::None => None,
            Overshoot::Ambient => Some(shooting::lit_ambient(patches, self.overshooting.factor())),
        };
        let Some((j, amount)) =
            shooting::select_shooter(self.scene, patches, self.weights, ambient)
        else {
            self.stop = Some(StopReason::NothingToShoot);
            return (false, None);
        };
        let sent = patches[j].open_area * amount;
        let w = shooting::shoot(
            self.scene,
            self.accel,
            &self.kernel,
            &mut self.solution.mesh,
            j,
            amount,
            &mut self.scratch,
        );
        let refinement = self.refinement();
        let Mesh {
            patches,
            elements,
            radiosity,
            leaves,
            ..
        } = &mut self.solution.mesh;
        let mut book =
            || shooting::book(self.scene, patches, elements, leaves, &self.scratch, amount);
        let (returned, scanned) = if scan {
            let pairs = &self.pairs;
            let (returned, marked) = rayon::join(book, || {
                adaptive_subdivision::scan(pairs, elements, radiosity, &refinement)
            });
            (returned, Some(marked))
        } else {
            (book(), None)
        };
        self.overshooting.record(sent, returned);
        self.work += w;
        if !self.has_shot[j] {
            self.has_shot[j] = true;
            self.shot_patches.push(j as u32);
        }
        self.shots += 1;
        (true, scanned)
    }
}

impl Solver for ProgressiveSolver<'_> {
    /// One step, run on a rayon worker thread (`rayon::scope`; inline when called on one): the step's parallel
    /// loops (a gather per shot, the contrast scan, re-gathers) then start from a pool thread, without handing
    /// work from the caller's thread to the pool and waking it again for each loop.
    fn step(&mut self) -> Result<Step, SolveError> {
        rayon::scope(|_| self.step_on_worker())
    }

    fn solution(&self) -> &dyn Solution {
        match self.params.answer.reconstruction {
            Reconstruction::Constant => &self.solution,
            _ => self,
        }
    }

    fn stats(&self) -> Stats {
        Stats {
            steps: self.steps,
            elements: self.element_count() as u64,
            links: 0,
            form_factors: self.work.form_factors,
            rays: self.work.rays,
            bytes: (self.solution.mesh.bytes()
                + self.solution.locator.bytes()
                + self.solution.reflectance.capacity() * size_of::<Rgb>()
                + self.pairs.capacity() * 8
                + self.has_shot.capacity()
                + self.shot_patches.capacity() * 4
                + self.scratch.capacity() * size_of::<f64>()
                + self.output.bytes()) as u64,
            residual: Some(self.unshot_fraction()),
        }
    }
}

impl ProgressiveSolver<'_> {
    /// [`Solver::step`]'s work.
    fn step_on_worker(&mut self) -> Result<Step, SolveError> {
        if let Some(reason) = self.stop {
            return Ok(reason.step());
        }
        self.output.invalidate();
        self.steps += 1;
        if !self.open_estimated {
            if self.open_shares_apply() {
                self.work.rays +=
                    self.solution
                        .mesh
                        .estimate_open(self.scene, self.accel, self.kernel.seed);
            }
            self.open_estimated = true;
        }
        let mut shot_any = false;
        let mut scanned = None;
        for k in 1..=self.params.shots_per_step {
            let last = k == self.params.shots_per_step;
            let (shot, s) = self.shoot_once(last && self.params.adaptive);
            if !shot {
                break;
            }
            shot_any = true;
            scanned = s;
        }
        if shot_any && self.params.adaptive {
            let refinement = self.refinement();
            let (split, w) = adaptive_subdivision::refine(
                self.scene,
                self.accel,
                &self.kernel,
                &mut self.solution.mesh,
                &self.solution.locator,
                &mut self.pairs,
                &self.shot_patches,
                &refinement,
                scanned,
            )?;
            self.elements_split += split as u64;
            self.work += w;
        }
        self.update_ambient();
        if !self.unshot_power().is_finite() {
            return Err(SolveError::Numerical(
                "the unshot power is no longer finite".into(),
            ));
        }
        if self.stop.is_none() {
            self.stop = self.check_stop();
        }
        Ok(self.stop.map_or(Step::Continue, StopReason::step))
    }
}

/// The output side: the `reconstruction` parameter's data, rebuilt at the first query after a step.
#[derive(Debug)]
struct Output {
    reconstructor: Reconstructor,
    /// Position in `mesh.leaves` of each element (u32::MAX for inner elements), for Gouraud lookups.
    leaf_position: OnceLock<Vec<u32>>,
}

impl Output {
    fn new(params: &AnswerParams, seed: u64) -> Self {
        Self {
            reconstructor: Reconstructor::of(params, seed),
            leaf_position: OnceLock::new(),
        }
    }

    /// Approximate heap bytes of the built answering data.
    fn bytes(&self) -> usize {
        self.reconstructor.bytes() + self.leaf_position.get().map_or(0, |p| p.capacity() * 4)
    }

    fn invalidate(&mut self) {
        self.reconstructor.invalidate();
        self.leaf_position.take();
    }
}

impl ProgressiveSolver<'_> {
    /// Rays and point-to-polygon kernel evaluations spent answering queries by final gather so far (zeros
    /// for the other reconstructions). Not part of [`Solver::stats`], which counts solving only: the runner
    /// charges answering separately, once per evaluation.
    pub fn gather_work(&self) -> (u64, u64) {
        self.output.reconstructor.gather_work()
    }
}

/// Point answers through the `reconstruction` parameter (`constant` answers from [`ProgressiveSolution`]).
/// The ambient term, when on, is added to every element value first.
impl Solution for ProgressiveSolver<'_> {
    fn answer_kernel_evaluations(&self) -> u64 {
        self.output.reconstructor.gather_work().1
    }

    fn radiosity_at(&self, face: FaceId, point: DVec3) -> Rgb {
        if face >= self.scene.faces.len() {
            return Rgb::splat(f64::NAN);
        }
        let sol = &self.solution;
        let mesh = &sol.mesh;
        let located = || sol.locator.locate(mesh, face, point);
        self.output.reconstructor.radiosity_at(
            self.scene,
            self.accel,
            face,
            point,
            || sol.radiosity_at(face, point),
            || {
                let positions = self.output.leaf_position.get_or_init(|| {
                    let mut pos = vec![u32::MAX; mesh.elements.len()];
                    for (k, &e) in mesh.leaves.iter().enumerate() {
                        pos[e as usize] = k as u32;
                    }
                    pos
                });
                located()
                    .map(|e| positions[e as usize])
                    .filter(|&k| k != u32::MAX)
                    .map(|k| k as usize)
            },
            || {
                self.elements()
                    .into_iter()
                    .map(|e| ElementValue {
                        face: e.face,
                        polygon: e.polygon,
                        radiosity: e.radiosity + sol.reflectance[e.face] * sol.ambient,
                        open: e.open,
                    })
                    .collect()
            },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patches_keep_b_equal_shot_plus_unshot_and_elements_regather_exactly() {
        // A closed box with a light and an occluder, adaptive on: after some shots every patch's area-mean
        // radiosity equals what it shot plus what it has left, and every leaf (old or re-gathered) equals
        // E + ρ Σ_j F_ej S_j.
        let mut b = radlab_scene::SceneBuilder::new("box");
        let wall = b
            .add_material(
                radlab_scene::Material::new("wall", Rgb::splat(0.6), Rgb::ZERO).expect("m"),
            )
            .expect("m");
        let light = b
            .add_material(
                radlab_scene::Material::new("light", Rgb::splat(0.2), Rgb::splat(5.0)).expect("m"),
            )
            .expect("m");
        let s = radlab_scene::builtin("furnace-cube?tessellation=3").expect("cube");
        for f in 0..s.face_count() {
            let pts: Vec<DVec3> = s.polygon(f).vertices().to_vec();
            let m = if f == 4 + 9 { light } else { wall };
            b.add_polygon_points(&pts, m, "cube").expect("face");
        }
        // An occluding plate in the middle, facing down.
        b.add_polygon_points(
            &[
                DVec3::new(0.3, 0.3, 0.5),
                DVec3::new(0.3, 0.7, 0.5),
                DVec3::new(0.7, 0.7, 0.5),
                DVec3::new(0.7, 0.3, 0.5),
            ],
            wall,
            "plate",
        )
        .expect("plate");
        let scene = b.build().expect("scene");
        let accel = Accel::new(&scene);
        for overshoot in [Overshoot::None, Overshoot::Ambient] {
            check_invariants(&scene, &accel, overshoot);
        }
    }

    /// B_p = S_p + ΔB_p for every patch and B_e = E + ρ Σ_j F_ej S_j for every leaf after 30 shots.
    fn check_invariants(scene: &Scene, accel: &Accel, overshoot: Overshoot) {
        let params = ProgressiveParams {
            element_size: Some(0.17),
            patch_size: Some(0.34),
            adaptive_threshold: 0.2,
            max_shots: Some(30),
            overshoot,
            ..Default::default()
        };
        let mut solver = ProgressiveSolver::new(scene, accel, params, 3).expect("solver");
        while solver.step().expect("step") == Step::Continue {}
        assert_eq!(solver.stop_reason(), Some(StopReason::MaxShots));
        assert!(solver.elements_split() > 0);
        let mesh = &solver.solution.mesh;
        // Overshooting drives some unshot radiosity negative (that is what it is for); plain shooting leaves
        // only the small negative corrections of adaptive subdivision.
        let most_negative = mesh
            .patches
            .iter()
            .map(|p| p.unshot.min_element() / p.shot.max_element().max(1e-300))
            .fold(0.0, f64::min);
        if overshoot == Overshoot::Ambient {
            assert!(most_negative < -0.1, "{most_negative}");
        } else {
            assert!(most_negative > -0.1, "{most_negative}");
        }
        for (p, patch) in mesh.patches.iter().enumerate() {
            let b = mesh.patch_radiosity(p);
            let d = (b - patch.shot - patch.unshot).abs().max_element();
            assert!(d < 1e-12 * b.max_element().max(1.0), "patch {p}: {d}");
        }
        for &e in &mesh.leaves {
            let el = &mesh.elements[e as usize];
            let f = el.face as usize;
            let mut sum = Rgb::ZERO;
            for &j in &solver.shot_patches {
                let patch = &mesh.patches[j as usize];
                let (ff, _) =
                    shooting::element_patch_factor(scene, accel, &solver.kernel, el, e, patch, j);
                sum += ff * patch.shot;
            }
            let expect = scene.emission(f) + scene.reflectance(f) * sum;
            let d = (expect - mesh.radiosity[e as usize]).abs().max_element();
            assert!(
                d < 1e-12 * expect.max_element().max(1.0),
                "element {e}: {d}"
            );
        }
    }
}

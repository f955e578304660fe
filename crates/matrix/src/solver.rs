//! The matrix radiosity solver driven step by step: assembly of the form-factor matrix in blocks of rows
//! ([`crate::assembly`]), then one iteration of the chosen method per step until the stopping rule of
//! [`crate::linear_system`] is met. The solution is constant per element: B_i at every point of element i.
//!
//! Before assembly, each element's open fraction o_i ([`radlab_kernels::open_fraction`]) is estimated (with
//! area-sampled visibility, the default; with `centre` or `unoccluded` visibility o_i = 1), and the
//! system is solved on the effective areas A_i max(o_i, r_i) (r_i the assembled row sum Σ_j F'_ij): B_i is
//! the radiosity of the element's open part, so an element straddling a contact (half under a floor covering)
//! no longer sends half of its light into the covering's back. Where nothing is sealed, o_i = 1 and the
//! system is the plain one.

use glam::DVec3;
use radlab_answer::{ElementMesh, Reconstructor, element_size, gouraud::ElementValue};
use radlab_kernels::open_fraction::open_fractions;
use radlab_method::{MethodParams, Solution, SolveError, Solver, Stats, Step};
use radlab_scene::{FaceId, Rgb, Scene};
use radlab_visibility::Accel;

use crate::assembly::{self, Assembly, PairSettings};
use crate::conjugate_gradient::ConjugateGradient;
use crate::linear_system::{StopRule, System, relative};
use crate::{Iteration, MatrixParams, gauss_seidel, jacobi};

#[derive(Clone, Copy)]
enum Phase {
    OpenFractions,
    Assembling,
    Solving,
    Done,
}

/// Matrix radiosity over a fixed element mesh. See the crate documentation. Cloning copies the matrix (e.g. to
/// solve one assembled system several ways).
#[derive(Clone)]
pub struct MatrixSolver<'a> {
    scene: &'a Scene,
    accel: &'a Accel,
    params: MatrixParams,
    seed: u64,
    mesh: ElementMesh,
    area: Vec<f64>,
    /// Open fraction o_i of each element (empty until the first step).
    open: Vec<f64>,
    /// Effective area A_i max(o_i, r_i) the system is solved on (the true areas until assembly ends).
    open_area: Vec<f64>,
    /// Rays cast estimating the open fractions.
    open_rays: u64,
    rho: Vec<Rgb>,
    emission: Vec<Rgb>,
    assembly: Assembly,
    radiosity: Vec<Rgb>,
    scratch: Vec<Rgb>,
    cg: Option<ConjugateGradient>,
    rule: StopRule,
    phase: Phase,
    steps: u64,
    iterations: usize,
    residual: Option<f64>,
    hit_cap: bool,
    output: Reconstructor,
}

impl<'a> MatrixSolver<'a> {
    /// Meshes the scene and allocates the matrix, after checking `params` and the memory budget (no
    /// allocation happens for a refused problem). Assembly starts with the first [`Solver::step`].
    pub fn new(
        scene: &'a Scene,
        accel: &'a Accel,
        params: MatrixParams,
        seed: u64,
    ) -> Result<Self, SolveError> {
        params.validate()?;
        let size = element_size(params.element_size, scene)?;
        let budget = (params.memory_budget_mib * 1024.0 * 1024.0) as u64;
        let check = |n: u64| -> Result<(), SolveError> {
            let needed = assembly::required_bytes(n);
            if needed > budget {
                // n ∝ 1/size² on surfaces: start from size·√(n / n_fit) and grow until the mesh fits
                // (the count is cheap to predict, and rounding to whole segments makes it step-wise).
                let coarsest = scene.faces.len() as u64;
                let hint = if assembly::required_bytes(coarsest) > budget {
                    format!(
                        "even one element per face ({coarsest} elements) needs {} bytes; raise \
                         memory_budget_mib (now {})",
                        assembly::required_bytes(coarsest),
                        params.memory_budget_mib
                    )
                } else {
                    let n_fit = ((budget as f64) / 8.0).sqrt().max(1.0);
                    let mut suggest = size * (n as f64 / n_fit).sqrt();
                    let fits = |s: f64| {
                        assembly::required_bytes(assembly::predicted_element_count(scene, s))
                            <= budget
                    };
                    while !fits(suggest) && suggest.is_finite() {
                        suggest *= 1.05;
                    }
                    // Printed rounded to 4 digits: keep it above the size found.
                    suggest *= 1.001;
                    format!(
                        "use a larger element_size (now {size:.4e}; about {suggest:.4e} would fit, the matrix \
                         shrinking with its fourth power) or raise memory_budget_mib (now {})",
                        params.memory_budget_mib
                    )
                };
                return Err(SolveError::over_budget(
                    &format!(
                        "matrix radiosity with {n} elements (a dense {n} × {n} form-factor matrix)"
                    ),
                    needed,
                    budget,
                    &hint,
                ));
            }
            Ok(())
        };
        check(assembly::predicted_element_count(scene, size))?;
        let mesh = ElementMesh::new(scene, size);
        check(mesh.len() as u64)?;
        let n = mesh.len();
        let area: Vec<f64> = mesh.elements.iter().map(|e| e.area).collect();
        let rho: Vec<Rgb> = mesh
            .elements
            .iter()
            .map(|e| scene.reflectance(e.face as usize))
            .collect();
        let emission: Vec<Rgb> = mesh
            .elements
            .iter()
            .map(|e| scene.emission(e.face as usize))
            .collect();
        let assembly = Assembly::new(&mesh, budget)?;
        let rule = StopRule::new(params.tolerance, &rho);
        Ok(Self {
            scene,
            accel,
            seed,
            mesh,
            radiosity: emission.clone(),
            scratch: Vec::with_capacity(n),
            open: Vec::new(),
            open_area: area.clone(),
            open_rays: 0,
            area,
            rho,
            emission,
            assembly,
            cg: None,
            rule,
            phase: Phase::OpenFractions,
            steps: 0,
            iterations: 0,
            residual: None,
            hit_cap: false,
            output: Reconstructor::of(&params.answer, seed),
            params,
        })
    }

    /// Rays and point-to-polygon kernel evaluations spent answering queries by final gather so far (zeros
    /// for the other reconstructions). Not part of [`Solver::stats`], which counts solving only: the runner
    /// charges answering separately, once per evaluation (see the crate documentation).
    pub fn gather_work(&self) -> (u64, u64) {
        self.output.gather_work()
    }

    /// The element mesh the solution lives on.
    pub fn mesh(&self) -> &ElementMesh {
        &self.mesh
    }

    /// Radiosity per element (W/m², linear RGB), indexed like `mesh().elements`. Equal to the emission until
    /// the matrix is assembled.
    pub fn element_radiosity(&self) -> &[Rgb] {
        &self.radiosity
    }

    /// Iterations of the linear solver so far (assembly steps not counted).
    pub fn iterations(&self) -> usize {
        self.iterations
    }

    /// The parameters in use.
    pub fn params(&self) -> &MatrixParams {
        &self.params
    }

    /// The scene being solved.
    pub fn scene(&self) -> &Scene {
        self.scene
    }

    /// Whether the matrix is fully assembled.
    pub fn is_assembled(&self) -> bool {
        self.assembly.is_finished()
    }

    /// Whether the solver stopped because it reached `max_iterations` rather than the tolerance.
    pub fn hit_iteration_cap(&self) -> bool {
        self.hit_cap
    }

    /// Starts the linear solve again from B = E with another iteration method, keeping the assembled matrix
    /// (assembly continues first if it is unfinished). Steps keep counting; iterations restart from zero.
    pub fn restart(&mut self, iteration: Iteration) {
        self.params.iteration = iteration;
        self.radiosity.clone_from(&self.emission);
        self.output.invalidate();
        self.cg = None;
        self.iterations = 0;
        self.residual = None;
        self.hit_cap = false;
        self.phase = if self.open.is_empty() {
            Phase::OpenFractions
        } else if self.assembly.is_finished() {
            Phase::Solving
        } else {
            Phase::Assembling
        };
    }

    /// The form factor F'_ij from element `i` to element `j` as the solver uses it (G_ij / A_i: reciprocal,
    /// with the diagonal reciprocity correction at i = j). Zero before assembly finishes or out of range.
    pub fn form_factor(&self, i: usize, j: usize) -> f64 {
        let n = self.mesh.len();
        if !self.assembly.is_finished() || i >= n || j >= n {
            return 0.0;
        }
        self.assembly.matrix[i * n + j] / self.area[i]
    }

    /// The effective areas the system is solved on, A_i max(o_i, r_i) (the module documentation); the true
    /// areas before assembly ends.
    pub fn open_areas(&self) -> &[f64] {
        &self.open_area
    }

    /// The open fractions o_i of the elements (empty before the first step; all 1 unless visibility is
    /// area-sampled).
    pub fn open_fractions(&self) -> &[f64] {
        &self.open
    }

    /// Irradiance per element over its open part, H_i = Σ_j G_ij B_j / (A_i max(o_i, r_i)), from the current
    /// radiosity (Σ_j F'_ij B_j where nothing is sealed).
    pub fn irradiance(&self) -> Vec<Rgb> {
        let sys = self.system();
        (0..sys.n)
            .map(|i| crate::linear_system::gather(sys.row(i), &self.radiosity) / sys.area[i])
            .collect()
    }

    fn system(&self) -> System<'_> {
        System {
            n: self.mesh.len(),
            g: &self.assembly.matrix,
            area: &self.open_area,
            rho: &self.rho,
            emission: &self.emission,
        }
    }

    fn iterate(&mut self) -> Result<Step, SolveError> {
        let sys = System {
            n: self.mesh.len(),
            g: &self.assembly.matrix,
            area: &self.open_area,
            rho: &self.rho,
            emission: &self.emission,
        };
        let (res, met) = match self.params.iteration {
            Iteration::Jacobi => {
                let (change, norm) = jacobi::iterate(&sys, &mut self.radiosity, &mut self.scratch);
                let res = relative(change, norm);
                (res, self.rule.met(res))
            }
            Iteration::GaussSeidel => {
                let (change, norm) = gauss_seidel::iterate(&sys, &mut self.radiosity);
                let res = relative(change, norm);
                (res, self.rule.met(res))
            }
            Iteration::ConjugateGradient => {
                let cg = self
                    .cg
                    .get_or_insert_with(|| ConjugateGradient::new(&sys, &self.radiosity));
                cg.iterate(&sys, &mut self.radiosity, &self.rule)?
            }
        };
        self.iterations += 1;
        let r = res.max_element();
        if r.is_nan() || !self.radiosity.iter().all(|b| b.is_finite()) {
            return Err(SolveError::Numerical(format!(
                "{:?} produced a non-finite radiosity after {} iterations",
                self.params.iteration, self.iterations
            )));
        }
        self.residual = Some(r);
        if met {
            self.finish();
            return Ok(Step::Converged);
        }
        if self.iterations >= self.params.max_iterations {
            self.hit_cap = true;
            self.finish();
            return Ok(Step::Capped);
        }
        Ok(Step::Continue)
    }

    /// A_i max(o_i, r_i): an element's row sum r_i bounds what its open part can be (it cannot receive
    /// from more than its open area), which keeps ρ_i r_i / max(o_i, r_i) ≤ ρ_i, the contraction the stopping
    /// rule relies on.
    fn effective_areas(&self) -> Vec<f64> {
        let n = self.mesh.len();
        (0..n)
            .map(|i| {
                let a = self.area[i];
                let row: f64 = self.assembly.matrix[i * n..(i + 1) * n].iter().sum::<f64>() / a;
                let o = self.open.get(i).copied().unwrap_or(1.0);
                a * o.max(row).min(1.0)
            })
            .collect()
    }

    /// The elements' values for Gouraud vertices and final gathers, each with its effective open share.
    fn element_values(&self) -> Vec<ElementValue> {
        let mut v = self.mesh.values(&self.radiosity);
        for ((x, &a), &oa) in v.iter_mut().zip(&self.area).zip(&self.open_area) {
            x.open = (oa / a).min(1.0);
        }
        v
    }

    fn finish(&mut self) {
        self.phase = Phase::Done;
        self.cg = None;
        self.scratch = Vec::new();
    }
}

impl Solver for MatrixSolver<'_> {
    fn step(&mut self) -> Result<Step, SolveError> {
        match self.phase {
            Phase::OpenFractions => {
                self.steps += 1;
                // Only area-sampled visibility carries an element's sealed share into its form factors;
                // with one centre ray or none, each element is open or closed as a whole.
                (self.open, self.open_rays) = if self.params.visibility.is_area_sampled() {
                    open_fractions(
                        self.scene,
                        self.accel,
                        &self.mesh.elements,
                        |e| (&e.polygon, e.face as FaceId),
                        self.seed,
                        0,
                    )
                } else {
                    (vec![1.0; self.mesh.len()], 0)
                };
                self.phase = Phase::Assembling;
                Ok(Step::Continue)
            }
            Phase::Assembling => {
                self.steps += 1;
                let settings = PairSettings {
                    quadrature: self.params.quadrature,
                    visibility: self.params.visibility,
                    seed: self.seed,
                };
                if self.assembly.step(&self.mesh, self.accel, &settings) {
                    self.open_area = self.effective_areas();
                    self.phase = Phase::Solving;
                }
                Ok(Step::Continue)
            }
            Phase::Solving => {
                self.steps += 1;
                self.output.invalidate();
                self.iterate()
            }
            Phase::Done if self.hit_cap => Ok(Step::Capped),
            Phase::Done => Ok(Step::Converged),
        }
    }

    fn solution(&self) -> &dyn Solution {
        self
    }

    fn stats(&self) -> Stats {
        let n = self.mesh.len() as u64;
        let vectors = (self.area.len() + self.open.len() + self.open_area.len()) * 8
            + (self.rho.len()
                + self.emission.len()
                + self.radiosity.len()
                + self.scratch.capacity())
                * size_of::<Rgb>()
            + if self.cg.is_some() {
                6 * self.mesh.len() * size_of::<Rgb>()
            } else {
                0
            };
        Stats {
            steps: self.steps,
            elements: n,
            links: self.assembly.nonzero,
            form_factors: self.assembly.form_factors,
            rays: self.assembly.rays + self.open_rays,
            bytes: (self.assembly.matrix.len() * 8
                + vectors
                + self.mesh.bytes()
                + self.output.bytes()) as u64,
            residual: self.residual,
        }
    }
}

impl Solution for MatrixSolver<'_> {
    fn answer_kernel_evaluations(&self) -> u64 {
        self.output.gather_work().1
    }

    /// The radiosity at `point` on `face` as the `reconstruction` parameter answers it: the containing
    /// element's value, Gouraud-interpolated vertex values, or a final gather from every element. NaN for a
    /// face id outside the scene.
    fn radiosity_at(&self, face: FaceId, point: DVec3) -> Rgb {
        if face >= self.scene.faces.len() {
            return Rgb::splat(f64::NAN);
        }
        self.output.radiosity_at(
            self.scene,
            self.accel,
            face,
            point,
            || self.radiosity[self.mesh.locate(face, point)],
            || Some(self.mesh.locate(face, point)),
            || self.element_values(),
        )
    }
}

impl std::fmt::Debug for MatrixSolver<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MatrixSolver")
            .field("elements", &self.mesh.len())
            .field("params", &self.params)
            .field("seed", &self.seed)
            .field("iterations", &self.iterations)
            .finish()
    }
}

//! [`HierarchicalSolver`]: hierarchical radiosity over the quadtrees of a scene's input faces, driven through
//! the [`Solver`] trait, and its [`Solution`]: radiosity constant per leaf, vertex-interpolated or
//! final-gathered (the shared answering layer, [`crate::output`]), at any point of any face.

use radlab_method::{MethodParams, Solution, SolveError, Solver, Stats, Step};
use radlab_scene::{FaceId, Rgb, Scene};
use radlab_visibility::Accel;

use crate::hierarchy::Engine;
use crate::node::Patch;
use crate::output::{SurfaceOutput, locate};
use crate::params::HierarchicalParams;
use crate::patch_transport::PatchKernel;

/// Hierarchical radiosity (Hanrahan, Salzman & Aupperle 1991) over a scene; see the crate documentation.
#[derive(Debug)]
pub struct HierarchicalSolver<'a> {
    scene: &'a Scene,
    accel: &'a Accel,
    engine: Engine<Patch, PatchKernel<'a>>,
    output: SurfaceOutput,
    rays: u64,
}

impl<'a> HierarchicalSolver<'a> {
    /// A solver for `scene` (ray cast through `accel`, built from the same scene) with `params` and `seed`.
    /// Validates the parameters; no work is done until [`Solver::step`].
    pub fn new(
        scene: &'a Scene,
        accel: &'a Accel,
        params: HierarchicalParams,
        seed: u64,
    ) -> Result<Self, SolveError> {
        params.validate()?;
        let min_size = params.resolve_min_size(scene)?;
        let roots = (0..scene.face_count())
            .map(|f| Patch::root(scene, f))
            .collect();
        let kernel = PatchKernel::new(
            accel,
            params.quadrature,
            params.visibility,
            seed,
            params.gather,
        )
        .with_leaf_visibility(params.leaf_visibility)
        .with_open_shares(scene);
        let output = SurfaceOutput::new(&params.answer, seed);
        let engine = Engine::new(roots, kernel, params, min_size)?;
        Ok(Self {
            scene,
            accel,
            engine,
            output,
            rays: 0,
        })
    }

    /// The engine: nodes, links and radiosity, for inspection and tests.
    pub fn engine(&self) -> &Engine<Patch, PatchKernel<'a>> {
        &self.engine
    }

    /// The engine, to drive its passes one by one in unit tests.
    #[cfg(test)]
    pub(crate) fn engine_mut(&mut self) -> &mut Engine<Patch, PatchKernel<'a>> {
        &mut self.engine
    }

    /// The scene solved.
    pub fn scene(&self) -> &Scene {
        self.scene
    }

    /// Leaf radiosity with each leaf's face and area: (face, area, B) per leaf, in node order. B is the
    /// radiosity of the leaf's open part; the leaf sends o A B, o its open share ([`Engine::open_shares`],
    /// 1 unless the leaf is partly sealed).
    pub fn leaves(&self) -> Vec<(FaceId, f64, Rgb)> {
        let e = &self.engine;
        (0..e.nodes().len() as u32)
            .filter(|&i| e.is_leaf(i))
            .map(|i| {
                let p = &e.nodes()[i as usize];
                (p.face, p.area, e.radiosity()[i as usize])
            })
            .collect()
    }

    /// The leaf of `face` containing `point` (the nearest one for points slightly outside).
    pub fn locate(&self, face: FaceId, point: glam::DVec3) -> Option<u32> {
        locate(&self.engine, face, point)
    }
}

impl Solution for HierarchicalSolver<'_> {
    fn answer_kernel_evaluations(&self) -> u64 {
        self.output.gather_work().1
    }

    fn radiosity_at(&self, face: FaceId, point: glam::DVec3) -> Rgb {
        self.output
            .radiosity_at(&self.engine, self.scene, self.accel, face, point)
    }
}

impl Solver for HierarchicalSolver<'_> {
    fn step(&mut self) -> Result<Step, SolveError> {
        let s = self.engine.step_counting_rays(self.accel, &mut self.rays)?;
        self.output.update(&self.engine);
        Ok(s)
    }

    fn solution(&self) -> &dyn Solution {
        self
    }

    fn stats(&self) -> Stats {
        self.engine.stats(self.rays, self.output.bytes())
    }
}

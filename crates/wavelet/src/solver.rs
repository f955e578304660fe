//! [`WaveletSolver`]: wavelet radiosity over the quadtrees of a scene's input faces on radlab-hierarchical's
//! engine, driven through the [`Solver`] trait, answering at points from the leaves' basis functions, their
//! vertex-averaged means or a final gather (the engine's shared output layer).

use radlab_answer::Reconstruction;
use radlab_hierarchical::output::locate;
use radlab_hierarchical::{Engine, Patch, SurfaceOutput};
use radlab_kernels::open_fraction::{POINT_SEAL_RAYS, point_key, point_sealed};
use radlab_method::{MethodParams, Solution, SolveError, Solver, Stats, Step};
use radlab_scene::{FaceId, Rgb, Scene};
use radlab_visibility::Accel;

use crate::basis::Basis;
use crate::params::WaveletParams;
use crate::transport::WaveletTransport;

/// The engine in one basis size (K = M²).
#[derive(Debug)]
pub struct Run<'a, const K: usize> {
    /// The engine with the wavelet transport.
    pub engine: Engine<Patch, WaveletTransport<'a, K>>,
}

/// The engine of whichever basis size the parameters chose.
#[derive(Debug)]
pub enum Engines<'a> {
    /// Haar: one coefficient.
    K1(Run<'a, 1>),
    /// M2, F2: four.
    K4(Run<'a, 4>),
    /// M3, F3: nine.
    K9(Run<'a, 9>),
}

/// Calls `$body` with `$e` bound to the engine, whatever its K.
macro_rules! with_engine {
    ($engines:expr, $e:ident => $body:expr) => {
        match $engines {
            Engines::K1(r) => {
                let $e = &r.engine;
                $body
            }
            Engines::K4(r) => {
                let $e = &r.engine;
                $body
            }
            Engines::K9(r) => {
                let $e = &r.engine;
                $body
            }
        }
    };
}

/// Wavelet radiosity (Gortler, Schröder, Cohen & Hanrahan 1993); see the crate documentation.
#[derive(Debug)]
pub struct WaveletSolver<'a> {
    scene: &'a Scene,
    accel: &'a Accel,
    engines: Engines<'a>,
    output: SurfaceOutput,
    rays: u64,
    seed: u64,
}

fn run<'a, const K: usize>(
    scene: &'a Scene,
    accel: &'a Accel,
    params: &WaveletParams,
    seed: u64,
) -> Result<Run<'a, K>, SolveError> {
    let hp = params.engine_params();
    let min_size = hp.resolve_min_size(scene)?;
    let roots = (0..scene.face_count())
        .map(|f| Patch::root(scene, f))
        .collect();
    let transport = WaveletTransport::<K>::new(
        accel,
        params.basis,
        params.points(),
        params.visibility,
        params.oracle,
        params.gather,
        seed,
    )
    .with_leaf_visibility(params.leaf_visibility);
    // Open shares: the linked engine asks for them; linkless shooting does not estimate them.
    let transport = if params.linkless {
        transport
    } else {
        transport.with_open_shares(scene)
    };
    let mut engine = Engine::new(roots, transport, hp, min_size)?;
    if params.linkless {
        engine.set_linkless(params.link_cache_bytes());
    }
    Ok(Run { engine })
}

impl<'a> WaveletSolver<'a> {
    /// A solver for `scene` (rays through `accel`, built from the same scene) with `params` and `seed`.
    /// Validates the parameters; no work is done until [`Solver::step`].
    pub fn new(
        scene: &'a Scene,
        accel: &'a Accel,
        params: WaveletParams,
        seed: u64,
    ) -> Result<Self, SolveError> {
        params.validate()?;
        let engines = match params.basis {
            Basis::Haar => Engines::K1(run(scene, accel, &params, seed)?),
            Basis::F2 | Basis::M2 => Engines::K4(run(scene, accel, &params, seed)?),
            Basis::F3 | Basis::M3 => Engines::K9(run(scene, accel, &params, seed)?),
        };
        Ok(Self {
            scene,
            accel,
            engines,
            output: SurfaceOutput::new(&params.reconstruction.answer(), seed),
            rays: 0,
            seed,
        })
    }

    /// The engine of the chosen basis size, for inspection and tests.
    pub fn engines(&self) -> &Engines<'a> {
        &self.engines
    }

    /// Turns the engine's row normalisation on or off ([`Engine::normalise_closed_rows`]): for closed scenes
    /// only, each leaf's gathered irradiance is rescaled so that its mean row sums to one.
    pub fn normalise_closed_rows(&mut self, on: bool) {
        match &mut self.engines {
            Engines::K1(r) => r.engine.normalise_closed_rows(on),
            Engines::K4(r) => r.engine.normalise_closed_rows(on),
            Engines::K9(r) => r.engine.normalise_closed_rows(on),
        }
    }

    /// (face, area, mean radiosity) per leaf, in node order.
    pub fn leaves(&self) -> Vec<(FaceId, f64, Rgb)> {
        with_engine!(&self.engines, e => (0..e.nodes().len() as u32)
            .filter(|&i| e.is_leaf(i))
            .map(|i| {
                let p = &e.nodes()[i as usize];
                (p.face, p.area, e.radiosity()[i as usize])
            })
            .collect())
    }
}

impl Solution for WaveletSolver<'_> {
    fn answer_kernel_evaluations(&self) -> u64 {
        self.output.gather_work().1
    }

    /// The reconstruction's answer; at a point of a leaf partly or wholly sealed (open share below 1), a
    /// point probe first ([`point_sealed`]): a sealed point answers its emission only. The shared final
    /// gather makes that test itself, at every point.
    fn radiosity_at(&self, face: FaceId, point: glam::DVec3) -> Rgb {
        with_engine!(&self.engines, e => {
            let gathers = self.output.reconstruction() == Reconstruction::FinalGather;
            let partly_sealed = !gathers && locate(e, face, point)
                .and_then(|i| e.open_shares().get(i as usize).copied())
                .is_some_and(|o| o < 1.0);
            if partly_sealed && face < self.scene.face_count() {
                let key = point_key(self.scene, face, point);
                if point_sealed(self.scene, self.accel, face, point, POINT_SEAL_RAYS, self.seed, key).0 {
                    return self.scene.emission(face);
                }
            }
            self.output.radiosity_at(e, self.scene, self.accel, face, point)
        })
    }
}

impl Solver for WaveletSolver<'_> {
    fn step(&mut self) -> Result<Step, SolveError> {
        let s = match &mut self.engines {
            Engines::K1(r) => r.engine.step_counting_rays(self.accel, &mut self.rays)?,
            Engines::K4(r) => r.engine.step_counting_rays(self.accel, &mut self.rays)?,
            Engines::K9(r) => r.engine.step_counting_rays(self.accel, &mut self.rays)?,
        };
        with_engine!(&self.engines, e => self.output.update(e));
        Ok(s)
    }

    fn solution(&self) -> &dyn Solution {
        self
    }

    fn stats(&self) -> Stats {
        with_engine!(&self.engines, e => e.stats(self.rays, self.output.bytes()))
    }

    /// Linkless shooting's counters (shots, sweeps, link cache hits and misses, …); none when linked.
    fn counters(&self) -> Vec<(&'static str, u64)> {
        with_engine!(&self.engines, e => e.shooting_counters())
    }
}

//! [`VolumeClusterSolver`]: the loose octree built over the scene's faces, materialised in the hierarchical
//! engine down to the input faces (so every face is a node that gathers and sends), one root self-link, then
//! the engine's refinement, gather/push-pull and schedules with the chosen cluster transfer. Output through the
//! engine's shared output layer. [`ClusterSolver`] is the same, generic over the transfer, for tests that
//! read the engine.

use std::sync::Arc;

use glam::DVec3;
use radlab_hierarchical::{Engine, NodeKind, PatchKernel, SurfaceOutput};
use radlab_method::{MethodParams, Solution, SolveError, Solver, Stats, Step};
use radlab_scene::{FaceId, Rgb, Scene};
use radlab_visibility::Accel;

use crate::cluster_node::ClusterNode;
use crate::cluster_transport::{ClusterTransport, TransferMode};
use crate::loose_octree::ClusterTree;
use crate::params::{RowNormalisation, Transfer, VolumeClusterParams};
use crate::transfer_alpha::Alpha;
use crate::transfer_directional::Directional;
use crate::transfer_isotropic::Isotropic;

/// Volume-clustered hierarchical radiosity with transfer mode `M`.
#[derive(Debug)]
pub struct ClusterSolver<'a, M: TransferMode> {
    scene: &'a Scene,
    accel: &'a Accel,
    tree: Arc<ClusterTree>,
    engine: Engine<ClusterNode<'a>, ClusterTransport<'a, M>>,
    output: SurfaceOutput,
    rays: u64,
}

impl<'a, M: TransferMode> ClusterSolver<'a, M> {
    /// Builds the cluster hierarchy over `scene` (rays through `accel`, built from the same scene) and the
    /// root self-link. Cluster-link rays come from the engine's `visibility` parameter.
    pub fn new(
        scene: &'a Scene,
        accel: &'a Accel,
        params: &VolumeClusterParams,
        seed: u64,
    ) -> Result<Self, SolveError> {
        if scene.face_count() == 0 {
            return Err(SolveError::param(
                "scene",
                "the scene has no faces to cluster",
            ));
        }
        let tree = Arc::new(ClusterTree::build(scene));
        let root = ClusterNode::root(Arc::clone(&tree), scene);
        Self::from_roots(scene, accel, params, seed, tree, vec![root], &[(0, 0)])
    }

    /// A solver over the given roots (clusters of `tree`, or patches) and first links `(receiver,
    /// source)` between root indices, with every cluster expanded down to its faces: the general form of
    /// [`ClusterSolver::new`] (one root cluster over the whole scene and its self-link), for experiments and
    /// tests that link chosen clusters.
    pub fn from_roots(
        scene: &'a Scene,
        accel: &'a Accel,
        params: &VolumeClusterParams,
        seed: u64,
        tree: Arc<ClusterTree>,
        roots: Vec<ClusterNode<'a>>,
        first_links: &[(u32, u32)],
    ) -> Result<Self, SolveError> {
        params.validate()?;
        let p = params.engine.clone();
        let min_size = p.resolve_min_size(scene)?;
        let patches = PatchKernel::new(accel, p.quadrature, p.visibility, seed, p.gather)
            .with_leaf_visibility(p.leaf_visibility)
            .with_open_shares(scene);
        let before = accel.rays_cast();
        let enclosures = crate::enclosure::enclosures(scene, accel, seed);
        let transport = ClusterTransport::new(patches, accel, p.visibility, p.quadrature, seed)
            .with_reachable(enclosures.reachable)
            .with_straddle_cone(params.straddle_angle.to_radians());
        let output = SurfaceOutput::new(&p.answer, seed);
        let n_roots = roots.len() as u32;
        let mut engine = Engine::new(roots, transport, p, min_size)?;
        engine.expand(|n| matches!(n, ClusterNode::Cluster(_)))?;
        engine.skip_initial_links();
        engine.normalise_closed_rows(
            enclosures.closed && params.row_normalisation == RowNormalisation::ClosedScenes,
        );
        for &(r, s) in first_links {
            if r >= n_roots || s >= n_roots {
                return Err(SolveError::param(
                    "link",
                    format!("root {r} or {s} does not exist ({n_roots} roots)"),
                ));
            }
            let (r, s) = (engine.roots()[r as usize], engine.roots()[s as usize]);
            engine.add_link(r, s)?;
        }
        let rays = accel.rays_cast().saturating_sub(before);
        let mut s = Self {
            scene,
            accel,
            tree,
            engine,
            output,
            rays,
        };
        s.output.update(&s.engine);
        Ok(s)
    }

    /// The engine, for inspection and tests.
    pub fn engine(&self) -> &Engine<ClusterNode<'a>, ClusterTransport<'a, M>> {
        &self.engine
    }

    /// The cluster hierarchy.
    pub fn tree(&self) -> &ClusterTree {
        &self.tree
    }

    /// Radiosity, area and normal of every input face (the area-mean over its leaves).
    pub fn face_radiosity(&self) -> Vec<(FaceId, f64, Rgb)> {
        (0..self.scene.face_count())
            .filter_map(|f| {
                let i = self.engine.face_node(f)?;
                Some((
                    f,
                    self.scene.faces[f].area,
                    self.engine.radiosity()[i as usize],
                ))
            })
            .collect()
    }

    /// Row sums of the discrete operator in use at every leaf, (face, leaf area, Σ_s K_ls per channel)
    /// (radlab-hierarchical's `Engine::row_sums`): one at every leaf of a closed scene if the transfer were
    /// exact, or where the row normalisation is on; a defect δ becomes δρ/(1 − ρ) in the furnace
    /// B = E/(1 − ρ). Leaves of zero reflectance, or sealed off from every emitter, read zero.
    pub fn row_sums(&self) -> Vec<(FaceId, f64, Rgb)> {
        let e = &self.engine;
        let r = e.row_sums();
        (0..e.nodes().len() as u32)
            .filter(|&i| e.is_leaf(i))
            .filter_map(|i| {
                let node = &e.nodes()[i as usize];
                Some((node.face()?, node.area(), r[i as usize]))
            })
            .collect()
    }

    fn stats(&self) -> Stats {
        self.engine
            .stats(self.rays, self.output.bytes() + self.tree.bytes())
    }

    fn step(&mut self) -> Result<Step, SolveError> {
        let s = self.engine.step_counting_rays(self.accel, &mut self.rays)?;
        self.output.update(&self.engine);
        Ok(s)
    }
}

impl<M: TransferMode> Solution for ClusterSolver<'_, M> {
    fn answer_kernel_evaluations(&self) -> u64 {
        self.output.gather_work().1
    }

    fn radiosity_at(&self, face: FaceId, point: DVec3) -> Rgb {
        self.output
            .radiosity_at(&self.engine, self.scene, self.accel, face, point)
    }
}

impl<M: TransferMode> Solver for ClusterSolver<'_, M> {
    fn step(&mut self) -> Result<Step, SolveError> {
        ClusterSolver::step(self)
    }

    fn solution(&self) -> &dyn Solution {
        self
    }

    fn stats(&self) -> Stats {
        ClusterSolver::stats(self)
    }
}

/// Volume-clustered hierarchical radiosity with the transfer chosen by [`VolumeClusterParams::transfer`]; see
/// the crate documentation.
#[derive(Debug)]
pub enum VolumeClusterSolver<'a> {
    /// `transfer = "isotropic"`.
    Isotropic(ClusterSolver<'a, Isotropic>),
    /// `transfer = "alpha"`.
    Alpha(ClusterSolver<'a, Alpha>),
    /// `transfer = "directional"`.
    Directional(ClusterSolver<'a, Directional>),
}

macro_rules! each {
    ($s:expr, $x:ident => $e:expr) => {
        match $s {
            VolumeClusterSolver::Isotropic($x) => $e,
            VolumeClusterSolver::Alpha($x) => $e,
            VolumeClusterSolver::Directional($x) => $e,
        }
    };
}

impl<'a> VolumeClusterSolver<'a> {
    /// A solver for `scene` with `params` and `seed`; the hierarchy is built here (its cost is the
    /// construction's, reported apart from the steps).
    pub fn new(
        scene: &'a Scene,
        accel: &'a Accel,
        params: VolumeClusterParams,
        seed: u64,
    ) -> Result<Self, SolveError> {
        Ok(match params.transfer {
            Transfer::Isotropic => {
                Self::Isotropic(ClusterSolver::new(scene, accel, &params, seed)?)
            }
            Transfer::Alpha => Self::Alpha(ClusterSolver::new(scene, accel, &params, seed)?),
            Transfer::Directional => {
                Self::Directional(ClusterSolver::new(scene, accel, &params, seed)?)
            }
        })
    }

    /// Radiosity, area and normal of every input face.
    pub fn face_radiosity(&self) -> Vec<(FaceId, f64, Rgb)> {
        each!(self, s => s.face_radiosity())
    }

    /// The cluster hierarchy.
    pub fn tree(&self) -> &ClusterTree {
        each!(self, s => s.tree())
    }
}

impl Solution for VolumeClusterSolver<'_> {
    fn answer_kernel_evaluations(&self) -> u64 {
        each!(self, s => s.answer_kernel_evaluations())
    }

    fn radiosity_at(&self, face: FaceId, point: DVec3) -> Rgb {
        each!(self, s => s.radiosity_at(face, point))
    }
}

impl Solver for VolumeClusterSolver<'_> {
    fn step(&mut self) -> Result<Step, SolveError> {
        each!(self, s => ClusterSolver::step(s))
    }

    fn solution(&self) -> &dyn Solution {
        self
    }

    fn stats(&self) -> Stats {
        each!(self, s => ClusterSolver::stats(s))
    }
}

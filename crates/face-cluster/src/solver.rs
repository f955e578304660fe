//! [`FaceClusterSolver`]: face cluster radiosity (Willmott, Heckbert & Garland 1999) on radlab-hierarchical's
//! generic engine. The face-cluster tree is built over the scene ([`FaceClusterTree::build`]); its roots (one
//! per dual-connected part) are the leaves of a loose octree of volumes (Christensen et al. 1997) whose root
//! is the engine's one root, and the first link is that volume's self-link (refined into links between volumes,
//! roots and each curved root's self-link, as volume clusters refine theirs: Sillion 1995); refinement, gather/push-pull and the schedules are the engine's, light moves
//! by [`VectorTransport`]. Radiosity at a point of a face comes from the deepest engine node holding the face:
//! its patch if the refinement reached the face, else B = E + ρ max(0, n·e) with the irradiance vector e
//! pushed to the deepest face cluster containing it (section 4's final propagation, per queried face).
//! With `reconstruction = "gouraud"`, the irradiance is interpolated instead of the radiosity:
//! at a corner of face f, every face g around that vertex offers the irradiance it gathered, I_g(n_g) with
//! I_g(n) = n·e_g + s_g + t_g (from the deepest node holding g, e at g's centroid), carried to f's normal by the trapezoid rule between
//! the two faces' fields; the corners' means are interpolated over f (bilinear over a quad, linear over a
//! triangle), and B = E + ρ max(0, I) (the formula is at `gouraud_at`). So a face keeps
//! its own orientation: interpolating vertex radiosities taken with vertex normals (Gouraud shading proper)
//! blurs a rough surface's tilts into each other, and was 5.6% from the path-traced reference on the
//! 10⁴-face terrain at ε = 1e-6, against 2.0% for this and 2.4% for constant answers. Interpolation carries
//! light across a shadow's edge onto the dark faces sharing its vertices, as every interpolation does. A
//! face the refinement split into patches keeps the patch solution's own Gouraud values (its quadtree's
//! corners), finer than its vertices but not matched to its neighbours'. The face fields are linear in k and
//! computed at the first query after a step.
//!
//! With `reconstruction = "final-gather"` (the default) a point is answered by one more gather over the
//! face-cluster tree ([`crate::cluster_gather`]; Lischinski, Tampieri & Greenberg 1993's final gather,
//! summed as Barnes & Hut 1986 sum forces): nodes smaller than `gather_opening` times their distance by their
//! power vectors, nearer ones opened down to the faces' exact point-to-polygon factors with visibility rays,
//! emitters always exactly. It reads every face's constant answer (a pass linear in k after each step) and
//! costs about log k kernel evaluations and rays a point, charged to answering. It is the most accurate of
//! the three answers and the default, chosen by the worst scenes of the defaults suite, where Gouraud answers
//! smear light across shadow edges. Its cost shows in `radlab solve`, which answers 16 points a face for its
//! face table and every corner of its mesh: millions of gathers at 10⁶ faces, where Gouraud answers cost
//! seconds. With `near_values = "regathered"` (the default) the faces it gathers one by one near the point, with
//! a factor of at least 0.01, read their values gathered once more at their centroids
//! ([`crate::cluster_gather`]), each at its first use, a gather per face some query comes near; with
//! `gather_values = "gathered"` every face's value is gathered so first (a second bounce everywhere), for k
//! more gathers a solution, and near values re-gather over those. Both are charged to answering.
//! With `gather_opening = 0` and `near_field = "sub-polygons"` the flat gather is radlab-answer's shared final
//! gather over the same values, whose near field re-gathers faces close to the point as sub-polygons
//! ([`NearField`]); its rays, kernel evaluations and bytes are charged to answering as well.
//!
//! Sealed points. A face's irradiance field is its area mean (and gradient), so every answer above carries
//! the lit part's light onto the part of a floor face under a block standing on it, which no light reaches
//! (Baum, Mann, Smith & Winget 1991's shadow leaks): measured at 0.5–2.4 W/m² on the defaults suite's small
//! scenes, where the exact answer is 0. A face is this method's smallest element and has no open share, so
//! the test is made per point: every answer first casts radlab-kernels'
//! [`point_sealed`] probe (cosine rays until one escapes or meets a front face beyond a small gap, up to
//! 128; an open point usually pays one ray, charged to answering as the runner counts the accelerator's
//! rays), and a point whose every ray meets the back of a face, or the front of one whose plane passes
//! within that gap (a block's bottom face just above the floor), answers its emission E: one-sided faces
//! absorb at their backs, so it receives nothing, and light reaches a gap only through its mouth. A point
//! found open only after a closed ray lies beside such a gap, and the tree gather answers it with every node
//! opened and kernel-weighted rays ([`crate::cluster_gather`]). The solution itself (and its energy) is
//! unchanged.

use std::sync::{Arc, OnceLock};

use glam::DVec3;
use radlab_answer::final_gather::{FinalGather, GatherSettings};
use radlab_answer::gouraud::ElementValue;
use radlab_answer::irradiance_gouraud;
use radlab_answer::{AnswerParams, NearValues, Reconstruction};
use radlab_hierarchical::{
    Engine, ErrorNorm, HierarchicalParams, LinearState, NodeKind, PatchKernel, SurfaceOutput,
};
use radlab_kernels::open_fraction::{POINT_SEAL_RAYS, point_key, point_sealed};
use radlab_method::{MethodParams, Solution, SolveError, Solver, Stats, Step};
use radlab_scene::{FaceId, Rgb, Scene, VertexAdjacency};
use radlab_visibility::Accel;
use radlab_volume_cluster::RowNormalisation;
use radlab_volume_cluster::enclosure::enclosures;
use rayon::prelude::*;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::clamped_irradiance::ClampedIrradiance;
use crate::cluster_gather::{
    ClusterGather, DEFAULT_OPENING, DEFAULT_VALUES_OPENING, GatherValues, NearField, TreeFarField,
    area_mean,
};
use crate::face_node::{FaceContext, FaceNode};
use crate::irradiance_gradient::IrradianceField;
use crate::self_exchange::{SELF_RAYS, SelfExchange, SelfExchangeMode};
use crate::vector_transport::VectorTransport;
use crate::{FaceClusterParams, FaceClusterTree};

/// Marks a tree node with no engine node.
const NO_NODE: u32 = u32::MAX;

/// Default ε of the face-cluster method (with the power error norm, as volume clusters): the largest of 1e-4,
/// 7e-5 and 5e-5 at which the Cornell box's signed error against the path tracer is within ±0.3% at 512 points
/// (−0.33%, −0.25%, −0.20%). From 1e-4 to 7e-5 every scene of the defaults suite answered closer (white room
/// 4.7% → 3.8% mean point error) for 6–30% more time (docs/defaults.md).
pub const DEFAULT_EPSILON: f64 = 7e-5;

/// Default directory of cached hierarchies (relative to the working directory of the program that caches).
pub const DEFAULT_CACHE_DIR: &str = "results/.cache/face-cluster";

/// Parameters of the face-cluster method: every parameter of the hierarchical engine but `lazy_linking`
/// ([`HierarchicalParams`]: same names, same checks) with the power error norm and ε = 7e-5 ([`DEFAULT_EPSILON`]) by default, and
/// its own, each declared once on its field (doc comment: help; `schemars` attribute: range; default:
/// `impl Default`). The hierarchy is built with [`FaceClusterParams::default`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(default)]
pub struct FaceClusterSolveParams {
    /// The engine's parameters.
    #[serde(flatten)]
    pub engine: HierarchicalParams,
    /// Directory of cached face-cluster hierarchies, one file per mesh digest, relative to the working
    /// directory; "" builds the hierarchy every run.
    ///
    /// This crate reads and writes no file: the program that builds the solver (radlab's runner) does, and
    /// hands the hierarchy to [`FaceClusterSolver::with_tree`]. Default [`DEFAULT_CACHE_DIR`].
    pub cache_dir: String,
    /// off (the rows are what the vector transport computes) or closed-scenes (16 rays from every face find
    /// whether the scene is closed, a pass linear in the faces; if it is, each leaf's row is rescaled to sum
    /// to one, as an enclosure's form factors do).
    pub row_normalisation: RowNormalisation,
    /// What curved nodes send onto themselves: traced (self_rays rays from every face estimate every node's
    /// self form factor and its children's exchange) or cap (only a concave node's self-link, carrying its
    /// spherical cap's share). See [`SelfExchangeMode`].
    pub self_exchange: SelfExchangeMode,
    /// How a link's irradiance spreads over a cluster receiver: linear (the irradiance and its Jacobian, six
    /// more kernel evaluations a link, so faces take the field at their own centroids) or constant (the value
    /// at the receiver's centroid). See [`IrradianceField`].
    pub irradiance_field: IrradianceField,
    /// Rays per input face, at least, that trace the self-exchange before the solve (65,536 in all at least):
    /// more rays, less noise, for setup time linear in the faces.
    #[schemars(range(min = 1, max = 1024))]
    pub self_rays: u32,
    /// Final-gather only: the values the gather reads: solution (the solution's constant answers, with the
    /// faces near the point re-gathered as `near_values` asks) or gathered (every face's value gathered first
    /// over the tree at values_opening: a second bounce, charged to answering). See [`GatherValues`].
    pub gather_values: GatherValues,
    /// gather_values = "gathered" only: the values' gather's opening.
    #[schemars(range(min = 0), extend("exclusiveMaximum" = 1))]
    pub values_opening: f64,
    /// Final-gather with gather_opening = 0 only: off (every face by its exact factor and its one value) or
    /// sub-polygons (faces nearer the point than their diameter taken as 4 × 4 sub-polygons with their own
    /// rays and re-gathered radiosities, through the shared final gather). See [`NearField`].
    pub near_field: NearField,
}

impl Default for FaceClusterSolveParams {
    fn default() -> Self {
        Self {
            engine: HierarchicalParams {
                error_norm: ErrorNorm::Power,
                epsilon: DEFAULT_EPSILON,
                // One more gather over the tree: chosen by the worst scenes of the defaults suite (Gouraud
                // answers smear light across shadow edges: 21% mean in the furnished room, 37% on a polygon
                // soup, 5% with a 140% worst point on the scanned dragon in its room; docs/defaults.md gives
                // the figures). Gouraud costs no gather and stays a setting.
                // Over the face-cluster tree ([`crate::cluster_gather`]): a node smaller than the opening times
                // its distance is gathered whole by its power vector, with an error of order its square.
                // Near values: the faces near the point that pass on most of a value's error (factor ≥ 0.01)
                // read their values gathered once more, where the clusters' values under a scanned mesh
                // left the floor 16–27% dark (chosen on the suite, docs/defaults.md).
                answer: AnswerParams {
                    near_values: NearValues::Regathered,
                    ..AnswerParams::final_gather(DEFAULT_OPENING)
                },
                ..HierarchicalParams::default()
            },
            cache_dir: DEFAULT_CACHE_DIR.to_string(),
            row_normalisation: RowNormalisation::Off,
            self_exchange: SelfExchangeMode::Traced,
            irradiance_field: IrradianceField::Linear,
            self_rays: SELF_RAYS,
            gather_values: GatherValues::Solution,
            values_opening: DEFAULT_VALUES_OPENING,
            near_field: NearField::Off,
        }
    }
}

impl MethodParams for FaceClusterSolveParams {
    const REFUSED: &'static [(&'static str, &'static str)] = &[(
        "lazy_linking",
        "face clusters start from one self-link of the volume above the hierarchy's roots, so there are no \
         initial links to make lazily; remove the parameter",
    )];

    fn check_combination(&self) -> Result<(), SolveError> {
        let d = Self::default();
        self.engine.check_engine(&d.engine.answer)?;
        // Visibility segments join the two ends' representative points (a hierarchy's samples per node, four
        // points of a patch): more rays than point pairs would repeat segments.
        let points = FaceClusterParams::default().samples_per_node.min(4);
        let rays = self.engine.visibility.rays() as usize;
        if rays > points * points {
            return Err(SolveError::param(
                "visibility",
                format!(
                    "face clusters cast a link's visibility rays between the {points} representative points of \
                     each end, at most {} distinct segments, and {rays} were asked for; use jittered4x4 (the \
                     default), jittered2x2, centre or unoccluded",
                    points * points
                ),
            ));
        }
        // The final gather's settings change nothing under other answers: refuse them there.
        let reconstruction = self.engine.answer.reconstruction;
        if reconstruction != Reconstruction::FinalGather {
            let set = [
                (
                    "gather_values",
                    self.gather_values != d.gather_values,
                    self.gather_values.as_str().to_string(),
                ),
                (
                    "values_opening",
                    self.values_opening != d.values_opening,
                    self.values_opening.to_string(),
                ),
                (
                    "near_field",
                    self.near_field != d.near_field,
                    self.near_field.as_str().to_string(),
                ),
            ];
            if let Some((key, _, v)) = set.into_iter().find(|s| s.1) {
                return Err(SolveError::param(
                    key,
                    format!(
                        "{key} = {v} only applies to final-gather answers, and reconstruction is {}; set \
                         reconstruction = \"final-gather\" or remove {key}",
                        reconstruction.as_str()
                    ),
                ));
            }
        }
        if self.values_opening != d.values_opening && self.gather_values != GatherValues::Gathered {
            return Err(SolveError::param(
                "values_opening",
                format!(
                    "values_opening = {} only applies to gathered values, and gather_values is {}; set \
                     gather_values = \"gathered\" or remove values_opening",
                    self.values_opening,
                    self.gather_values.as_str()
                ),
            ));
        }
        if self.near_field != NearField::Off && self.engine.answer.gather_opening != 0.0 {
            return Err(SolveError::param(
                "near_field",
                format!(
                    "near_field = \"{}\" is a treatment of the flat gather over every face, and \
                     gather_opening is {}; set gather_opening = 0 or remove near_field",
                    self.near_field.as_str(),
                    self.engine.answer.gather_opening
                ),
            ));
        }
        Ok(())
    }
}

/// Face cluster radiosity; see the module documentation.
#[derive(Debug)]
pub struct FaceClusterSolver<'a> {
    scene: &'a Scene,
    accel: &'a Accel,
    ctx: Arc<FaceContext<'a>>,
    engine: Engine<FaceNode<'a>, VectorTransport<'a>>,
    output: SurfaceOutput,
    /// Engine node of each tree node, [`NO_NODE`] where not materialised (indexed by tree node: an array
    /// rather than a hash map, since output asks for it from every face).
    engine_node: Vec<u32>,
    /// Whether point answers are interpolated from vertices (`reconstruction = "gouraud"`).
    gouraud: bool,
    /// Every input face's gathered irradiance (Gouraud output), computed at the first query after a step.
    face_fields: OnceLock<Vec<ClampedIrradiance>>,
    /// The faces around every vertex (Gouraud output), built at the first query.
    vertex_adjacency: OnceLock<VertexAdjacency>,
    /// The final gather's opening (`reconstruction = "final-gather"`), `None` for other answers.
    gather_opening: Option<f64>,
    /// The final gather's values, built at the first query after a step.
    gather: OnceLock<ClusterGather>,
    /// Where the final gather's values come from.
    gather_values: GatherValues,
    /// What the final gather reads for faces near the point, over the solution's values.
    near_values: NearValues,
    /// The values' gather's opening under [`GatherValues::Gathered`].
    values_opening: f64,
    /// How the flat final gather takes near faces.
    near_field: NearField,
    /// The shared final gather over the values, under [`NearField::SubPolygons`], built at the first query
    /// after a step.
    flat: OnceLock<FinalGather>,
    /// Rays and kernel evaluations of final gathers over earlier solutions.
    past_gather_work: (u64, u64),
    seed: u64,
    scanned: usize,
    rays: u64,
}

impl<'a> FaceClusterSolver<'a> {
    /// Builds the hierarchy over `scene` (its cost is the construction's, reported apart from the steps) and
    /// the first links.
    pub fn new(
        scene: &'a Scene,
        accel: &'a Accel,
        params: FaceClusterSolveParams,
        seed: u64,
    ) -> Result<Self, SolveError> {
        let tree = FaceClusterTree::build(scene, &FaceClusterParams::default())
            .map_err(|e| SolveError::param("scene", e.to_string()))?;
        Self::with_tree(scene, accel, &params, seed, tree)
    }

    /// The solver over a hierarchy already built (or read from a cache) for `scene`.
    pub fn with_tree(
        scene: &'a Scene,
        accel: &'a Accel,
        params: &FaceClusterSolveParams,
        seed: u64,
        tree: FaceClusterTree,
    ) -> Result<Self, SolveError> {
        params.validate()?;
        if scene.face_count() == 0 {
            return Err(SolveError::param(
                "scene",
                "the scene has no faces to cluster",
            ));
        }
        if tree.face_order().len() != scene.face_count() {
            return Err(SolveError::param(
                "scene",
                format!(
                    "the face-cluster hierarchy covers {} faces but the scene has {}; rebuild it for this scene",
                    tree.face_order().len(),
                    scene.face_count()
                ),
            ));
        }
        let p = params.engine.clone();
        let min_size = p.resolve_min_size(scene)?;
        let roots = tree.roots();
        let scene_area: f64 = roots.clone().map(|r| tree.node(r).area).sum();
        let tree_nodes = tree.nodes().len();
        let before = accel.rays_cast();
        let mut ctx = FaceContext::new(tree, scene);
        if params.self_exchange == SelfExchangeMode::Traced {
            ctx.exchange = SelfExchange::trace(&ctx.tree, scene, accel, seed, params.self_rays);
        }
        let ctx = Arc::new(ctx);
        let patches = PatchKernel::new(accel, p.quadrature, p.visibility, seed, p.gather)
            .with_leaf_visibility(p.leaf_visibility)
            .with_open_shares(scene);
        let transport = VectorTransport::new(
            patches,
            accel,
            p.visibility,
            p.epsilon,
            if p.error_norm == ErrorNorm::Power {
                scene_area
            } else {
                0.0
            },
        )
        .with_field(params.irradiance_field);
        // A final gather goes over the face-cluster tree ([`ClusterGather`]), not over the engine's patch
        // leaves alone: the engine's output then gives the constant answers the gather reads.
        let gather_opening = (p.answer.reconstruction == Reconstruction::FinalGather)
            .then_some(p.answer.gather_opening);
        let output = SurfaceOutput::new(
            &AnswerParams {
                reconstruction: if gather_opening.is_some() {
                    Reconstruction::Constant
                } else {
                    p.answer.reconstruction
                },
                ..AnswerParams::final_gather(0.0)
            },
            seed,
        );
        let gouraud = p.answer.reconstruction == Reconstruction::Gouraud;
        let root = ctx.root_volume();
        let mut engine = Engine::new(vec![root], transport, p, min_size)?;
        engine.skip_initial_links();
        if params.row_normalisation == RowNormalisation::ClosedScenes {
            engine.normalise_closed_rows(enclosures(scene, accel, seed).closed);
        }
        let top = engine.roots()[0];
        engine.add_link(top, top)?;
        let rays = accel.rays_cast().saturating_sub(before);
        let mut s = Self {
            scene,
            accel,
            ctx,
            engine,
            output,
            engine_node: vec![NO_NODE; tree_nodes],
            gouraud,
            face_fields: OnceLock::new(),
            vertex_adjacency: OnceLock::new(),
            gather_opening,
            gather: OnceLock::new(),
            gather_values: params.gather_values,
            near_values: params.engine.answer.near_values,
            values_opening: params.values_opening,
            near_field: params.near_field,
            flat: OnceLock::new(),
            past_gather_work: (0, 0),
            seed,
            scanned: 0,
            rays,
        };
        s.index_new_nodes();
        s.output.update(&s.engine);
        Ok(s)
    }

    fn index_new_nodes(&mut self) {
        let nodes = self.engine.nodes();
        for (i, n) in nodes.iter().enumerate().skip(self.scanned) {
            if let FaceNode::Cluster(c) = n {
                self.engine_node[c.id as usize] = i as u32;
            }
        }
        self.scanned = nodes.len();
    }

    /// The engine, for inspection and tests.
    pub fn engine(&self) -> &Engine<FaceNode<'a>, VectorTransport<'a>> {
        &self.engine
    }

    /// The face-cluster hierarchy and the per-node sums.
    pub fn context(&self) -> &FaceContext<'a> {
        &self.ctx
    }

    /// Input faces the solve has read (tree leaves split into their faces' patches).
    pub fn face_reads(&self) -> u64 {
        self.ctx.face_reads()
    }

    /// The engine node nearest above face `face` and, if it is a cluster, the irradiance vector there: the
    /// deepest materialised tree node on the path from the face's leaf to its root (O(depth)).
    fn deepest_cluster(&self, face: FaceId) -> Option<u32> {
        let tree = &self.ctx.tree;
        let mut n = tree.leaf_of_face(face);
        loop {
            let i = self.engine_node[n];
            if i != NO_NODE {
                return Some(i);
            }
            n = tree.node(n).parent()?;
        }
    }

    /// Radiosity of every input face: the area mean over its patch leaves where the refinement reached it,
    /// else E + ρ max(0, n·e) from the deepest cluster above it. Linear in k: for output, not for the solve.
    pub fn face_radiosity(&self) -> Vec<(FaceId, f64, Rgb)> {
        (0..self.scene.face_count())
            .map(|f| {
                let face = &self.scene.faces[f];
                (f, face.area, self.radiosity_at(f, face.centroid))
            })
            .collect()
    }

    fn stats(&self) -> Stats {
        // Gouraud output's fields count while they are held (the face fields until the next step).
        let fields = self.face_fields.get().map_or(0, |f| {
            f.capacity() * std::mem::size_of::<ClampedIrradiance>()
        }) + self
            .vertex_adjacency
            .get()
            .map_or(0, VertexAdjacency::bytes)
            + self.gather.get().map_or(0, ClusterGather::bytes)
            + self.flat.get().map_or(0, FinalGather::bytes);
        let mut s = self.engine.stats(
            self.rays,
            self.output.bytes()
                + self.ctx.bytes() as u64
                + (self.engine_node.capacity() * 4) as u64
                + fields as u64,
        );
        s.form_factors += self.engine.kernel().jacobian_evaluations();
        s
    }

    fn step(&mut self) -> Result<Step, SolveError> {
        let s = self.engine.step_counting_rays(self.accel, &mut self.rays)?;
        self.index_new_nodes();
        self.output.update(&self.engine);
        self.face_fields = OnceLock::new();
        if let Some(g) = self.gather.take() {
            self.past_gather_work.0 += g.rays();
            self.past_gather_work.1 += g.kernel_evaluations();
        }
        if let Some(g) = self.flat.take() {
            self.past_gather_work.0 += g.rays();
            self.past_gather_work.1 += g.kernel_evaluations();
        }
        Ok(s)
    }

    /// The gathered irradiance of input face `face`: at the deepest engine node holding it (the area mean
    /// over its leaves where the refinement split the face into patches).
    fn face_irradiance(&self, face: FaceId) -> ClampedIrradiance {
        let h = self.engine.irradiance();
        if let Some(root) = self.engine.face_node(face) {
            let (mut sum, mut area) = (ClampedIrradiance::ZERO, 0.0);
            let mut stack = vec![root];
            while let Some(i) = stack.pop() {
                if self.engine.is_leaf(i) {
                    let a = self.engine.nodes()[i as usize].area();
                    sum.add_scaled(Rgb::splat(a), &h[i as usize]);
                    area += a;
                } else {
                    stack.extend(self.engine.children(i));
                }
            }
            return if area > 0.0 {
                sum.scaled(1.0 / area)
            } else {
                h[root as usize]
            };
        }
        self.deepest_cluster(face)
            .map_or(ClampedIrradiance::ZERO, |i| self.at_face(i, face))
    }

    /// The irradiance of engine node `i` (a cluster) moved to the centroid of input face `face` below it, its
    /// traced light handed down the tree to the face by where the trace's rays landed (spread evenly over the
    /// faces below `i`, an open book's faces took the same light at the crease as at the far edges).
    fn at_face(&self, i: u32, face: FaceId) -> ClampedIrradiance {
        let node = &self.engine.nodes()[i as usize];
        let mut h = self.engine.irradiance()[i as usize]
            .moved(self.scene.faces[face].centroid - node.centroid());
        if let FaceNode::Cluster(c) = node {
            let tree = &self.ctx.tree;
            h.traced = self.ctx.exchange.hand_down_to(
                tree,
                c.id as usize,
                tree.leaf_of_face(face),
                [h.traced, h.from_sibling, h.outside],
            );
            (h.from_sibling, h.outside) = (Rgb::ZERO, Rgb::ZERO);
        }
        h
    }

    /// Every input face's gathered irradiance, computed at the first query after a step (linear in k: for
    /// output only).
    fn face_fields(&self) -> &[ClampedIrradiance] {
        self.face_fields.get_or_init(|| {
            (0..self.scene.face_count())
                .into_par_iter()
                .map(|f| self.face_irradiance(f))
                .collect()
        })
    }

    /// The constant answer at `point` of `face`: the engine's leaf there where the refinement split the face
    /// into patches, else E + ρ max(0, I) with I the irradiance of the deepest cluster above the face, moved to
    /// the point.
    fn constant_at(&self, face: FaceId, point: DVec3) -> Rgb {
        if self.engine.face_node(face).is_some() {
            return self
                .output
                .radiosity_at(&self.engine, self.scene, self.accel, face, point);
        }
        let Some(i) = self.deepest_cluster(face) else {
            return Rgb::ZERO;
        };
        let e = self.at_face(i, face);
        let n = self.scene.faces[face].normal;
        let (rho, em) = (self.scene.reflectance(face), self.scene.emission(face));
        em + rho * e.at(n)
    }

    /// Rays and kernel evaluations the final gather has spent answering so far (charged to answering, not to
    /// the steps).
    pub fn gather_work(&self) -> (u64, u64) {
        let (mut r, mut k) = self.past_gather_work;
        if let Some(g) = self.gather.get() {
            (r, k) = (r + g.rays(), k + g.kernel_evaluations());
        }
        if let Some(g) = self.flat.get() {
            (r, k) = (r + g.rays(), k + g.kernel_evaluations());
        }
        (r, k)
    }

    /// The shared final gather over the values of [`FaceClusterSolver::cluster_gather`]
    /// ([`NearField::SubPolygons`]), answering `point` on `face`. The tree gather at the default opening
    /// gives the far part of near faces' values ([`TreeFarField`]), so a face near a query costs a tree gather
    /// at its centroid rather than a pass over every face. The tree gather's work (and a gathered values'
    /// pass) is counted by it, the flat gather's by the shared gather.
    fn near_field_answer(&self, face: FaceId, point: DVec3) -> Rgb {
        let tree = self.cluster_gather(DEFAULT_OPENING);
        let flat = self.flat.get_or_init(|| {
            FinalGather::new(
                self.scene,
                &tree.elements(self.scene),
                GatherSettings::with_seed(self.seed),
            )
            .with_near_values(self.near_values)
        });
        let far = TreeFarField {
            gather: tree,
            ctx: &self.ctx,
            accel: self.accel,
        };
        flat.radiosity_with(self.scene, self.accel, face, point, Some(&far))
    }

    /// The final gather's values for the current solution: every input face's constant answer at its
    /// centroid (the area mean of a linear irradiance field, so the face's mean radiosity), and the patch
    /// leaves of faces the refinement split (such a face's value is their area mean). Linear in k, once per
    /// solution.
    fn cluster_gather(&self, opening: f64) -> &ClusterGather {
        self.gather.get_or_init(|| {
            let k = self.scene.face_count();
            let patches: std::collections::HashMap<FaceId, Vec<ElementValue>> = (0..k)
                .filter_map(|f| Some((f, self.engine.face_node(f)?)))
                .map(|(f, root)| {
                    let mut leaves = Vec::new();
                    let mut stack = vec![root];
                    while let Some(i) = stack.pop() {
                        if !self.engine.is_leaf(i) {
                            stack.extend(self.engine.children(i));
                        } else if let Some(p) = self.engine.nodes()[i as usize].patch() {
                            leaves.push(ElementValue {
                                face: f,
                                polygon: p.polygon,
                                radiosity: self.engine.radiosity()[i as usize],
                                open: self.engine.open_shares()[i as usize],
                            });
                        }
                    }
                    (f, leaves)
                })
                .collect();
            let values: Vec<Rgb> = (0..k)
                .into_par_iter()
                .map(|f| match patches.get(&f) {
                    Some(leaves) => area_mean(leaves),
                    None => self.constant_at(f, self.scene.faces[f].centroid),
                })
                .collect();
            let gather = match self.gather_values {
                GatherValues::Solution => {
                    ClusterGather::new(&self.ctx, values, patches, opening, self.seed)
                }
                GatherValues::Gathered => ClusterGather::regathered(
                    &self.ctx,
                    self.accel,
                    values,
                    patches,
                    (opening, self.values_opening),
                    self.seed,
                ),
            };
            gather.with_near_values(self.near_values)
        })
    }

    /// Gouraud radiosity of `face` at `point`: the faces' gathered fields I_g(n) = n·e_g + s_g + t_g
    /// interpolated by radlab-answer's [`irradiance_gouraud`] (each corner's faces carried to this face's
    /// normal), then B = E + ρ max(0, I).
    fn gouraud_at(&self, face: FaceId, point: DVec3) -> Rgb {
        let around = self
            .vertex_adjacency
            .get_or_init(|| VertexAdjacency::new(self.scene));
        let irradiance =
            irradiance_gouraud::irradiance_at(self.scene, around, self.face_fields(), face, point);
        let (rho, em) = (self.scene.reflectance(face), self.scene.emission(face));
        em + rho * irradiance.max(Rgb::ZERO)
    }
}

impl Solution for FaceClusterSolver<'_> {
    fn answer_kernel_evaluations(&self) -> u64 {
        self.gather_work().1
    }

    /// A point no light reaches ([`point_sealed`]: under a block standing on the floor) answers its
    /// emission; every other point the reconstruction's answer. The shared final gather
    /// ([`NearField::SubPolygons`]) makes the same test itself.
    fn radiosity_at(&self, face: FaceId, point: DVec3) -> Rgb {
        if face >= self.scene.face_count() {
            return Rgb::ZERO;
        }
        if self.gather_opening.is_some() && self.near_field == NearField::SubPolygons {
            return self.near_field_answer(face, point);
        }
        let key = point_key(self.scene, face, point);
        let (sealed, seal_rays) = point_sealed(
            self.scene,
            self.accel,
            face,
            point,
            POINT_SEAL_RAYS,
            self.seed,
            key,
        );
        if sealed {
            return self.scene.emission(face);
        }
        if let Some(opening) = self.gather_opening {
            // Open only after a closed ray: the point lies in or beside a gap.
            return self.cluster_gather(opening).radiosity_at(
                &self.ctx,
                self.accel,
                face,
                point,
                seal_rays > 1,
            );
        }
        if self.gouraud
            && self
                .engine
                .face_node(face)
                .is_none_or(|i| self.engine.is_leaf(i))
        {
            return self.gouraud_at(face, point);
        }
        self.constant_at(face, point)
    }
}

impl Solver for FaceClusterSolver<'_> {
    fn step(&mut self) -> Result<Step, SolveError> {
        FaceClusterSolver::step(self)
    }

    fn solution(&self) -> &dyn Solution {
        self
    }

    fn stats(&self) -> Stats {
        FaceClusterSolver::stats(self)
    }
}

//! The simulation hierarchy and its links, generic over the node kind and its light model ([`Transport`]):
//! a forest of nodes in one arena (a child is always created after its parent, so increasing ids visit parents
//! first), links stored with their receivers, the radiosity of every node (leaves: the solution B = E + ρ H;
//! inner nodes: the area mean of their children, Σ A_c B_c / A; both over open parts where a leaf is partly
//! sealed, [`crate::open_share`]) and the transport's further exitance state,
//! and the counters the runner reads. Refinement ([`crate::refine`]), gather rows (the crate's `gather_rows` module),
//! solution ([`crate::push_pull`]) and the schedules ([`crate::schedule`]) are methods of [`Engine`].
//!
//! The engine's state is grouped by what reads and writes it: the tree (nodes, parents, children, roots, the
//! node of each input face), the links (the transport's payloads by receiver, and what refinement remembers
//! of them), the gather cache (rows, source rows and the marks that say what to rebuild), the schedule, and
//! the solve state (radiosity, exitance, irradiance, open shares, coarse correction, convergence).

use radlab_method::SolveError;
use radlab_scene::{FaceId, Rgb};

use crate::node::NodeKind;
use crate::params::HierarchicalParams;
use crate::shooting::ShootState;
use crate::transport::{NodeView, Transport};

/// One cached gather entry of a target: the link (receiver node, index in its links) and its coefficient.
pub(crate) type RowEntry<C> = (u32, u32, C);

/// One leaf below a link's source and its normalised weight in what the link sends (double precision: in
/// single precision the weights' sum misses one by 1e-7, which a furnace near ρ = 1 magnifies by 1/(1 − ρ)).
pub(crate) type SourceWeight = (u32, f64);

/// Marks "no node".
pub const NONE: u32 = u32::MAX;

/// Where a schedule stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Phase {
    /// Create initial links (all of them, or lazily from the faces lit so far).
    Link,
    /// Refinement passes.
    Refine,
    /// Gather/push-pull passes.
    Solve,
    /// Nothing left to do.
    Done,
}

/// The hierarchy: a forest of nodes in one arena, parents before children.
#[derive(Debug)]
pub(crate) struct Tree<N> {
    pub(crate) nodes: Vec<N>,
    pub(crate) parent: Vec<u32>,
    /// (first child, number of children); 0 children for a leaf.
    pub(crate) children: Vec<(u32, u32)>,
    pub(crate) roots: Vec<u32>,
    /// Per input face: the node that is the whole face (the shallowest node within it), if created.
    pub(crate) face_nodes: Vec<u32>,
}

/// The links, stored with their receivers, and what refinement remembers about them.
#[derive(Debug)]
pub(crate) struct LinkStore<L> {
    /// Per receiver, its links (the transport's payload, [`Transport::Link`]).
    pub(crate) by_receiver: Vec<Vec<L>>,
    /// Per root: whether its initial links as a source exist yet (lazy linking).
    pub(crate) linked: Vec<bool>,
    /// Per receiver, how many of its first links the last refinement pass kept (kept links stay first;
    /// links made since are appended), valid while `settled_epsilon` is set.
    pub(crate) settled: Vec<u32>,
    /// The threshold of the last refinement pass, until something a decision reads changes (a solve pass
    /// changes the sources' radiosity): a pass at the same threshold then keeps the settled links again
    /// without asking the oracle ([`Engine::refine_pass`]).
    pub(crate) settled_epsilon: Option<f64>,
    /// Links the oracle has been asked about, over all refinement passes.
    pub(crate) decisions: u64,
}

/// What the gather caches between passes: every target's row of (link, coefficient) and every link's
/// source weights, with the marks that say which must be rebuilt.
#[derive(Debug)]
pub(crate) struct GatherCache<C> {
    /// Per gather target: every link evaluated there (its own, or an ancestor's that distributes to faces
    /// or leaves), with the coefficient at the target.
    pub(crate) rows: Vec<Vec<RowEntry<C>>>,
    /// Nodes whose links changed since the rows were last built (and new nodes).
    pub(crate) dirty: Vec<bool>,
    /// Per receiver, per link (aligned with its links): the leaves below the link's source and their
    /// normalised weights in what it sends ([`Transport::source_weight`]); empty when the source is a leaf
    /// or the link sends something else (its transport's emit).
    pub(crate) source_rows: Vec<Vec<Vec<SourceWeight>>>,
    /// Nodes split since the source rows were last built.
    pub(crate) split_since: Vec<bool>,
    /// Per node, the sources of its links when the rows were last built (aligned with the link indices in
    /// the row entries then), so that a rebuild finds the coefficients of links that were kept.
    pub(crate) row_sources: Vec<Vec<u32>>,
}

/// Where the schedule stands.
#[derive(Debug)]
pub(crate) struct ScheduleState {
    pub(crate) phase: Phase,
    pub(crate) stage: u32,
    pub(crate) stage_changed: bool,
    pub(crate) refine_changed: bool,
}

/// The solution and what the iteration knows about it: per-node radiosity, exitance and irradiance, the
/// open shares, the coarse correction, the row normalisation and the convergence estimate.
#[derive(Debug)]
pub(crate) struct SolveState<I, X> {
    pub(crate) radiosity: Vec<Rgb>,
    /// The transport's exitance state per node (pulled up the hierarchy: [`Transport::pull`]).
    pub(crate) exitance: Vec<X>,
    /// Total irradiance per node after the last pass's push (what a node's new children inherit).
    pub(crate) irradiance: Vec<I>,
    /// Per node, the open share estimated while it was a leaf ([`Transport::open_share`]); NaN until then.
    pub(crate) open_raw: Vec<f64>,
    /// Per node, the open share the solution uses ([`Engine::open_shares`]): a leaf's estimate; above, the
    /// area mean of its children's, Σ A_c o_c / A.
    pub(crate) open: Vec<f64>,
    /// Whether some leaf's estimated open share is below one (else every `open` is exactly 1, the next two
    /// are empty and the solution is the plain area-mean one, bit for bit).
    pub(crate) has_open: bool,
    /// Per receiver, per link (aligned with its links): 1/ō_l, ō_l the open share of the link's receiver as
    /// the link's own coefficients weight it (the crate's `open_share` module), 0 where the receiver is sealed.
    pub(crate) link_gain: Vec<Vec<f64>>,
    /// Per node, the factor a partly sealed leaf's gathered irradiance is capped by, min(1, 1/R'), R' its row
    /// sum with the gains (1 at wholly open leaves and above the leaves).
    pub(crate) row_cap: Vec<f64>,
    pub(crate) coarse_mu: Option<(Vec<Rgb>, Vec<X>)>,
    /// Whether leaf irradiance is rescaled so that every row sums to one (a closed scene).
    pub(crate) normalise_rows: bool,
    /// Per node, the factor its irradiance is multiplied by before reflection (empty: none).
    pub(crate) row_scale: Vec<Rgb>,
    pub(crate) coarse_denominator: Rgb,
    /// Number of lit leaves when the coarse mode was computed.
    pub(crate) coarse_support: usize,
    pub(crate) passes_since_change: u32,
    /// Consecutive passes, under one operator, whose change was no smaller than the pass before's.
    pub(crate) growing_passes: u32,
    /// The power the last pass changed, Σ A |ΔB| over the leaves.
    pub(crate) last_diff: Option<f64>,
    pub(crate) last_norm: Option<f64>,
    pub(crate) residual: Option<f64>,
    pub(crate) converged: bool,
}

/// Hierarchical radiosity over nodes of kind `N`, light moved by transport `T`.
#[derive(Debug)]
pub struct Engine<N, T: Transport<N>>
where
    N: NodeKind,
{
    pub(crate) tree: Tree<N>,
    pub(crate) links: LinkStore<T::Link>,
    pub(crate) cache: GatherCache<T::Coefficient>,
    pub(crate) schedule: ScheduleState,
    pub(crate) solve: SolveState<T::Irradiance, T::Exitance>,
    pub(crate) kernel: T,
    pub(crate) params: HierarchicalParams,
    pub(crate) min_size: f64,
    /// Linkless shooting's state, when the engine shoots instead of storing links ([`Engine::set_linkless`]).
    pub(crate) shooting: Option<ShootState<T::Irradiance, T::Link, T::Coefficient>>,
    // Counters.
    pub(crate) steps: u64,
    pub(crate) form_factors: u64,
}

impl<N: NodeKind, T: Transport<N>> Engine<N, T> {
    /// An engine over the given roots (for patches: one per input face), with no links yet. `min_size` is
    /// the resolved minimum element edge. Leaves start at B = E.
    pub fn new(
        roots: Vec<N>,
        kernel: T,
        params: HierarchicalParams,
        min_size: f64,
    ) -> Result<Self, SolveError> {
        if roots.len() >= NONE as usize {
            return Err(SolveError::param(
                "scene",
                format!("{} faces is more than this solver addresses", roots.len()),
            ));
        }
        let n = roots.len();
        let mut engine = Self {
            tree: Tree {
                nodes: Vec::with_capacity(n),
                parent: Vec::with_capacity(n),
                children: Vec::with_capacity(n),
                roots: (0..n as u32).collect(),
                face_nodes: Vec::new(),
            },
            links: LinkStore {
                by_receiver: Vec::with_capacity(n),
                linked: vec![false; n],
                settled: Vec::with_capacity(n),
                settled_epsilon: None,
                decisions: 0,
            },
            cache: GatherCache {
                rows: Vec::with_capacity(n),
                dirty: Vec::with_capacity(n),
                source_rows: Vec::with_capacity(n),
                split_since: Vec::with_capacity(n),
                row_sources: Vec::new(),
            },
            schedule: ScheduleState {
                phase: Phase::Link,
                stage: 0,
                stage_changed: false,
                refine_changed: false,
            },
            solve: SolveState {
                radiosity: Vec::with_capacity(n),
                exitance: Vec::with_capacity(n),
                irradiance: Vec::with_capacity(n),
                open_raw: Vec::with_capacity(n),
                open: Vec::with_capacity(n),
                has_open: false,
                link_gain: Vec::new(),
                row_cap: Vec::new(),
                coarse_mu: None,
                normalise_rows: false,
                row_scale: Vec::new(),
                coarse_denominator: Rgb::ZERO,
                coarse_support: 0,
                passes_since_change: 0,
                growing_passes: 0,
                last_diff: None,
                last_norm: None,
                residual: None,
                converged: false,
            },
            kernel,
            params,
            min_size,
            shooting: None,
            steps: 0,
            form_factors: 0,
        };
        for r in roots {
            engine.push_node(r, NONE, T::Irradiance::default(), 1.0);
        }
        Ok(engine)
    }

    /// Appends a node that receives irradiance `h` (a root: none; a new child: what its parent had) with
    /// open share `open` until its own is estimated (a new child: its parent's), and the radiosity and
    /// exitance that irradiance gives it.
    fn push_node(&mut self, node: N, parent: u32, h: T::Irradiance, open: f64) {
        let id = self.tree.nodes.len() as u32;
        if let Some(f) = node.face()
            && (parent == NONE || self.tree.nodes[parent as usize].face().is_none())
        {
            if self.tree.face_nodes.len() <= f {
                self.tree.face_nodes.resize(f + 1, NONE);
            }
            self.tree.face_nodes[f] = id;
        }
        let (b, x) = self.kernel.reflect(&node, &h, true);
        self.tree.nodes.push(node);
        self.solve.open_raw.push(f64::NAN);
        self.solve.open.push(open);
        self.tree.parent.push(parent);
        self.tree.children.push((0, 0));
        self.links.by_receiver.push(Vec::new());
        self.cache.rows.push(Vec::new());
        self.cache.dirty.push(true);
        self.links.settled.push(0);
        self.cache.source_rows.push(Vec::new());
        self.cache.split_since.push(false);
        self.solve.radiosity.push(b);
        self.solve.exitance.push(x);
        self.solve.irradiance.push(h);
    }

    /// Every node's total irradiance after the last pass's push (the transport's irradiance state); with
    /// open shares, over the node's open part (a leaf absorbs o A (1 − ρ) H: [`Engine::open_shares`]).
    pub fn irradiance(&self) -> &[T::Irradiance] {
        &self.solve.irradiance
    }

    /// The structure, for transports that read a source's contents.
    pub fn view(&self) -> NodeView<'_, N> {
        NodeView {
            nodes: &self.tree.nodes,
            children: &self.tree.children,
        }
    }

    /// The node that is the whole of input face `f` (the shallowest node within it), if the hierarchy has
    /// one.
    pub fn face_node(&self, f: FaceId) -> Option<u32> {
        self.tree.face_nodes.get(f).copied().filter(|&i| i != NONE)
    }

    /// The open share o ∈ [0, 1] of every node: at a leaf, the transport's estimate of the share of its area
    /// light can reach ([`Transport::open_share`]; 0 for a leaf wholly sealed); above, the area mean of its
    /// children's. A leaf's radiosity and irradiance ([`Engine::radiosity`], [`Engine::irradiance`]) are
    /// then those of its open part: it receives o A H and sends o A B (the crate's `open_share` module). Where nothing
    /// is sealed (or the transport estimates nothing) every entry is exactly 1 and B is the area mean.
    pub fn open_shares(&self) -> &[f64] {
        &self.solve.open
    }

    /// The transport's exitance state of every node.
    pub fn exitance(&self) -> &[T::Exitance] {
        &self.solve.exitance
    }

    /// The nodes, by id.
    pub fn nodes(&self) -> &[N] {
        &self.tree.nodes
    }

    /// The root ids.
    pub fn roots(&self) -> &[u32] {
        &self.tree.roots
    }

    /// The children of node `i` (empty for a leaf).
    pub fn children(&self, i: u32) -> std::ops::Range<u32> {
        let (first, count) = self.tree.children[i as usize];
        first..first + count
    }

    /// Whether node `i` is a leaf.
    pub fn is_leaf(&self, i: u32) -> bool {
        self.tree.children[i as usize].1 == 0
    }

    /// The parent of node `i`, if any.
    pub fn parent(&self, i: u32) -> Option<u32> {
        let p = self.tree.parent[i as usize];
        (p != NONE).then_some(p)
    }

    /// Radiosity of every node: the solution at leaves, area means above.
    pub fn radiosity(&self) -> &[Rgb] {
        &self.solve.radiosity
    }

    /// The mean radiosity of the leaves `keep` accepts over the area light reaches, Σ o A B / Σ o A (o the
    /// open shares, [`Engine::open_shares`]): in a closed scene of one reflectance ρ and emission E, the
    /// furnace's E/(1 − ρ) wherever the solution keeps its light, occluders or not. Zero without open area.
    pub fn open_mean_radiosity(&self, keep: impl Fn(&N) -> bool) -> Rgb {
        let (mut sum, mut area) = (Rgb::ZERO, 0.0);
        for (i, node) in self.tree.nodes.iter().enumerate() {
            if self.tree.children[i].1 == 0 && keep(node) {
                let w = node.area() * self.solve.open[i];
                sum += w * self.solve.radiosity[i];
                area += w;
            }
        }
        if area > 0.0 { sum / area } else { Rgb::ZERO }
    }

    /// The radiosity of leaf `i` at `point` on it, as its transport evaluates it from the leaf's radiosity
    /// and exitance ([`Transport::radiosity_at`]; by default the leaf's radiosity, constant over it): what a
    /// point answer reads of the solution.
    pub fn radiosity_at_leaf(&self, i: u32, point: glam::DVec3) -> Rgb {
        let i = i as usize;
        self.kernel.radiosity_at(
            &self.tree.nodes[i],
            self.solve.radiosity[i],
            &self.solve.exitance[i],
            point,
        )
    }

    /// The links gathered by node `i`.
    pub fn links_of(&self, i: u32) -> &[T::Link] {
        &self.links.by_receiver[i as usize]
    }

    /// The transport.
    pub fn kernel(&self) -> &T {
        &self.kernel
    }

    /// The parameters.
    pub fn params(&self) -> &HierarchicalParams {
        &self.params
    }

    /// The minimum element edge in use.
    pub fn min_size(&self) -> f64 {
        self.min_size
    }

    /// Number of leaves (the solution's elements).
    pub fn leaf_count(&self) -> usize {
        self.tree.children.iter().filter(|c| c.1 == 0).count()
    }

    /// Number of links held.
    pub fn link_count(&self) -> usize {
        self.links.by_receiver.iter().map(Vec::len).sum()
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Kernel evaluations so far: each link computed (kept or discarded) counts once, and so does each
    /// re-evaluation of a link's coefficient at a face or leaf below its receiver.
    pub fn form_factors(&self) -> u64 {
        self.form_factors
    }

    /// The solver statistics of this engine, with the rays its owner counted and the bytes it holds besides.
    pub fn stats(&self, rays: u64, extra_bytes: u64) -> radlab_method::Stats {
        radlab_method::Stats {
            steps: self.steps(),
            elements: self.leaf_count() as u64,
            links: self.link_count() as u64,
            form_factors: self.form_factors(),
            rays,
            bytes: self.bytes() + extra_bytes,
            residual: self.residual(),
        }
    }

    /// The latest estimate of the solution's remaining relative error, once a solve pass has run.
    pub fn residual(&self) -> Option<f64> {
        self.solve.residual
    }

    /// Bytes held by nodes, links and per-node state; when shooting without links, also the shooting state,
    /// the link cache and the peak bytes of one refinement level's transient links.
    pub fn bytes(&self) -> u64 {
        let per_node = Self::node_bytes();
        let links: usize = self.links.by_receiver.iter().map(|l| l.capacity()).sum();
        let rows: usize = self.cache.rows.iter().map(|r| r.capacity()).sum();
        let row_sources: usize = self.cache.row_sources.iter().map(|s| s.capacity()).sum();
        let gains: usize = self
            .solve
            .link_gain
            .iter()
            .map(|g| g.capacity())
            .sum::<usize>()
            + self.solve.link_gain.capacity() * 3
            + self.solve.row_cap.capacity();
        let (source_links, source_entries) =
            self.cache
                .source_rows
                .iter()
                .fold((0, 0), |(n, e), ls: &Vec<Vec<SourceWeight>>| {
                    (
                        n + ls.capacity(),
                        e + ls.iter().map(|w| w.capacity()).sum::<usize>(),
                    )
                });
        (self.tree.nodes.len() * per_node
            + source_links * size_of::<Vec<SourceWeight>>()
            + source_entries * size_of::<SourceWeight>()
            + self.tree.face_nodes.capacity() * 4
            + links * size_of::<T::Link>()
            + row_sources * 4
            + gains * size_of::<f64>()
            + self.cache.row_sources.capacity() * size_of::<Vec<u32>>()
            + rows * size_of::<RowEntry<T::Coefficient>>()
            + self.shooting_bytes()) as u64
    }

    /// What one node holds in the engine's per-node arrays, its links, rows and source rows apart.
    fn node_bytes() -> usize {
        size_of::<N>()
            + 4
            + size_of::<(u32, u32)>()
            + size_of::<Vec<T::Link>>()
            + size_of::<Vec<RowEntry<T::Coefficient>>>()
            + size_of::<Vec<Vec<SourceWeight>>>()
            + 4
            + 2
            + 2 * size_of::<Rgb>()
            + 2 * size_of::<f64>()
            + size_of::<T::Exitance>()
            + size_of::<T::Irradiance>()
    }

    /// The memory budget in bytes.
    pub(crate) fn budget_bytes(&self) -> u64 {
        (self.params.memory_budget_mib * 1024.0 * 1024.0).min(u64::MAX as f64) as u64
    }

    /// Errors if `extra_links` more links and `extra_nodes` more nodes would exceed the budget.
    pub(crate) fn check_budget(
        &self,
        extra_links: usize,
        extra_nodes: usize,
    ) -> Result<(), SolveError> {
        self.check_budget_held(self.bytes(), extra_links, extra_nodes)
    }

    /// [`Engine::check_budget`] with the memory held now given as `held` (what [`Engine::bytes`] would
    /// return), for callers that keep count instead of walking every node at each check.
    fn check_budget_held(
        &self,
        held: u64,
        extra_links: usize,
        extra_nodes: usize,
    ) -> Result<(), SolveError> {
        let per_node = Self::node_bytes();
        let need =
            held + (extra_links * size_of::<T::Link>()) as u64 + (extra_nodes * per_node) as u64;
        let budget = self.budget_bytes();
        if need > budget {
            return Err(SolveError::over_budget(
                "the hierarchy's elements and links",
                need,
                budget,
                "raise memory_budget_mib, or raise epsilon or min_element_size (or use fewer input faces: \
                 plain hierarchical radiosity's initial links grow as k², clusters' links about as k)",
            ));
        }
        if self.tree.nodes.len() + extra_nodes >= NONE as usize {
            return Err(SolveError::param(
                "min_element_size",
                "the hierarchy would exceed 2^32 elements; raise min_element_size or epsilon",
            ));
        }
        Ok(())
    }

    /// Creates the children of node `i` (which must be a splittable leaf). Children receive what their parent
    /// received (through the transport's push), so the solution is unchanged by the split.
    pub(crate) fn split_node(&mut self, i: u32) {
        debug_assert!(self.is_leaf(i));
        let kids = self.tree.nodes[i as usize].split();
        let first = self.tree.nodes.len() as u32;
        let h = self.solve.irradiance[i as usize];
        let open = self.solve.open[i as usize];
        for k in kids {
            let hk = self.kernel.push(&self.tree.nodes[i as usize], &k, &h);
            self.push_node(k, i, hk, open);
        }
        self.tree.children[i as usize] = (first, self.tree.nodes.len() as u32 - first);
        self.cache.dirty[i as usize] = true;
        self.cache.split_since[i as usize] = true;
    }

    /// Splits every node for which `split` holds, top down, before any link exists: a method whose
    /// hierarchy above the input faces is built in advance (volume clusters) materialises it this way, so
    /// that every input face is a node that gathers and sends.
    pub fn expand(&mut self, split: impl Fn(&N) -> bool) -> Result<(), SolveError> {
        // No link, row or source row exists yet, so what the nodes hold grows by one node's arrays per node
        // made (and the face index by the faces reached): measured once here and counted on, the check costs
        // O(1) a split. Measuring at every split walked every node each time, O(k²) in all: 74% of a 9.2 s
        // set-up at 1e5 faces.
        let (start, held) = (self.tree.nodes.len(), self.bytes());
        let face_index = self.tree.face_nodes.capacity();
        let mut i = 0;
        while i < self.tree.nodes.len() {
            if self.is_leaf(i as u32) && split(&self.tree.nodes[i]) {
                let made = (self.tree.nodes.len() - start) * Self::node_bytes()
                    + (self.tree.face_nodes.capacity() - face_index) * 4;
                self.check_budget_held(held + made as u64, 0, 8)?;
                self.split_node(i as u32);
            }
            i += 1;
        }
        // The expanded nodes' radiosity and exitance as their leaves' (a node made before its children holds
        // only what its own reflection of zero irradiance gives, which for a transport whose exitance sums
        // its faces' is nothing): the first pass then sends what the leaves emit.
        let (mut b, mut x) = (
            std::mem::take(&mut self.solve.radiosity),
            std::mem::take(&mut self.solve.exitance),
        );
        self.pull(&mut b, &mut x);
        (self.solve.radiosity, self.solve.exitance) = (b, x);
        self.links.settled_epsilon = None;
        self.operator_changed();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use radlab_scene::builtin;
    use radlab_visibility::Accel;

    use super::{Engine, NodeKind, Transport};
    use crate::HierarchicalSolver;
    use crate::params::HierarchicalParams;

    fn node_bytes<N: NodeKind, T: Transport<N>>(_: &Engine<N, T>) -> usize {
        Engine::<N, T>::node_bytes()
    }

    /// The budget check prices a node it is about to make as the memory held ([`Engine::bytes`]) counts one:
    /// with a budget of exactly what the engine holds plus four nodes, four more fit and a fifth does not.
    #[test]
    fn the_budget_prices_new_nodes_as_memory_held_counts_them() {
        let scene = builtin("cornell").expect("cornell");
        let accel = Accel::new(&scene);
        let mut s = HierarchicalSolver::new(&scene, &accel, HierarchicalParams::default(), 3)
            .expect("solver");
        let e = s.engine_mut();
        let per_node = node_bytes(e) as u64;
        let budget = e.bytes() + 4 * per_node;
        // A budget in MiB that converts back to exactly `budget` bytes (a power of two apart).
        e.params.memory_budget_mib = budget as f64 / (1024.0 * 1024.0);
        assert_eq!(e.budget_bytes(), budget);
        assert!(e.check_budget(0, 4).is_ok());
        assert!(e.check_budget(0, 5).is_err());
    }
}

//! The simulation hierarchy and its links, generic over the node kind: a forest of nodes in one arena (a child
//! is always created after its parent, so increasing ids visit parents first), links stored with their
//! receivers, the radiosity of every node (leaves: the solution B = E + ρ H; inner nodes: the area mean of
//! their children, Σ A_c B_c / A), and the counters the runner reads. Refinement ([`crate::refine`]),
//! solution ([`crate::push_pull`]) and the schedules ([`crate::schedule`]) are methods of [`Engine`].

use radlab_scene::{Rgb, SolveError};

use crate::link::{Kernel, Link};
use crate::node::NodeKind;
use crate::params::HierarchicalParams;

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

/// Hierarchical radiosity over nodes of kind `N` with links computed by kernel `K`.
#[derive(Debug)]
pub struct Engine<N, K> {
    pub(crate) nodes: Vec<N>,
    pub(crate) parent: Vec<u32>,
    /// (first child, number of children); 0 children for a leaf.
    pub(crate) children: Vec<(u32, u32)>,
    pub(crate) links: Vec<Vec<Link>>,
    pub(crate) radiosity: Vec<Rgb>,
    /// Per leaf, with [`crate::Gather::Leaf`]: (source, coefficient) for every link on its path to the root.
    pub(crate) rows: Vec<Vec<(u32, f64)>>,
    /// Nodes whose links changed since the rows were last built (and new nodes).
    pub(crate) dirty: Vec<bool>,
    pub(crate) roots: Vec<u32>,
    /// Per root: whether its initial links as a source exist yet (lazy linking).
    pub(crate) linked: Vec<bool>,
    pub(crate) kernel: K,
    pub(crate) params: HierarchicalParams,
    pub(crate) min_size: f64,
    // Schedule state.
    pub(crate) phase: Phase,
    pub(crate) stage: u32,
    pub(crate) stage_changed: bool,
    pub(crate) refine_changed: bool,
    // Solver state.
    pub(crate) coarse_mu: Option<Vec<Rgb>>,
    pub(crate) coarse_denominator: Rgb,
    pub(crate) passes_since_change: u32,
    pub(crate) last_norm: Option<f64>,
    pub(crate) residual: Option<f64>,
    pub(crate) converged: bool,
    // Counters.
    pub(crate) steps: u64,
    pub(crate) form_factors: u64,
}

impl<N: NodeKind, K: Kernel<N>> Engine<N, K> {
    /// An engine over the given roots (for patches: one per input face), with no links yet. `min_size` is
    /// the resolved minimum element edge. Leaves start at B = E.
    pub fn new(
        roots: Vec<N>,
        kernel: K,
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
        let radiosity = roots.iter().map(|r| r.emission()).collect();
        Ok(Self {
            nodes: roots,
            parent: vec![NONE; n],
            children: vec![(0, 0); n],
            links: vec![Vec::new(); n],
            radiosity,
            rows: vec![Vec::new(); n],
            dirty: vec![true; n],
            roots: (0..n as u32).collect(),
            linked: vec![false; n],
            kernel,
            params,
            min_size,
            phase: Phase::Link,
            stage: 0,
            stage_changed: false,
            refine_changed: false,
            coarse_mu: None,
            coarse_denominator: Rgb::ZERO,
            passes_since_change: 0,
            last_norm: None,
            residual: None,
            converged: false,
            steps: 0,
            form_factors: 0,
        })
    }

    /// The nodes, by id.
    pub fn nodes(&self) -> &[N] {
        &self.nodes
    }

    /// The root ids.
    pub fn roots(&self) -> &[u32] {
        &self.roots
    }

    /// The children of node `i` (empty for a leaf).
    pub fn children(&self, i: u32) -> std::ops::Range<u32> {
        let (first, count) = self.children[i as usize];
        first..first + count
    }

    /// Whether node `i` is a leaf.
    pub fn is_leaf(&self, i: u32) -> bool {
        self.children[i as usize].1 == 0
    }

    /// The parent of node `i`, if any.
    pub fn parent(&self, i: u32) -> Option<u32> {
        let p = self.parent[i as usize];
        (p != NONE).then_some(p)
    }

    /// Radiosity of every node: the solution at leaves, area means above.
    pub fn radiosity(&self) -> &[Rgb] {
        &self.radiosity
    }

    /// The links gathered by node `i`.
    pub fn links_of(&self, i: u32) -> &[Link] {
        &self.links[i as usize]
    }

    /// The kernel.
    pub fn kernel(&self) -> &K {
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
        self.children.iter().filter(|c| c.1 == 0).count()
    }

    /// Number of links held.
    pub fn link_count(&self) -> usize {
        self.links.iter().map(Vec::len).sum()
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Link transfers computed so far (each kept or discarded link counts once).
    pub fn form_factors(&self) -> u64 {
        self.form_factors
    }

    /// The latest estimate of the solution's remaining relative error, once a solve pass has run.
    pub fn residual(&self) -> Option<f64> {
        self.residual
    }

    /// Bytes held by nodes, links and per-node state.
    pub fn bytes(&self) -> u64 {
        let per_node = size_of::<N>()
            + 4
            + size_of::<(u32, u32)>()
            + size_of::<Vec<Link>>()
            + size_of::<Vec<(u32, f64)>>()
            + 1
            + 2 * size_of::<Rgb>();
        let links: usize = self.links.iter().map(|l| l.capacity()).sum();
        let rows: usize = self.rows.iter().map(|r| r.capacity()).sum();
        (self.nodes.len() * per_node + links * size_of::<Link>() + rows * size_of::<(u32, f64)>())
            as u64
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
        let per_node = size_of::<N>() + 4 + size_of::<(u32, u32)>() + size_of::<Vec<Link>>() + 48;
        let need = self.bytes()
            + (extra_links * size_of::<Link>()) as u64
            + (extra_nodes * per_node) as u64;
        let budget = self.budget_bytes();
        if need > budget {
            return Err(SolveError::over_budget(
                "hierarchical radiosity's elements and links",
                need,
                budget,
                "raise memory_budget_mib, or raise epsilon or min_element_size (or use fewer input faces: \
                 the initial links grow as k²)",
            ));
        }
        if self.nodes.len() + extra_nodes >= NONE as usize {
            return Err(SolveError::param(
                "min_element_size",
                "the hierarchy would exceed 2^32 elements; raise min_element_size or epsilon",
            ));
        }
        Ok(())
    }

    /// Creates the children of node `i` (which must be a splittable leaf). Children start with the parent's
    /// radiosity, so the solution is unchanged by the split.
    pub(crate) fn split_node(&mut self, i: u32) {
        debug_assert!(self.is_leaf(i));
        let kids = self.nodes[i as usize].split();
        let first = self.nodes.len() as u32;
        let b = self.radiosity[i as usize];
        for k in kids {
            self.nodes.push(k);
            self.parent.push(i);
            self.children.push((0, 0));
            self.links.push(Vec::new());
            self.rows.push(Vec::new());
            self.dirty.push(true);
            self.radiosity.push(b);
        }
        self.children[i as usize] = (first, self.nodes.len() as u32 - first);
        self.rows[i as usize] = Vec::new();
    }
}

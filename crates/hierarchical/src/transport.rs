//! How light moves through a hierarchy: the interface every node kind's light model implements, so that one
//! engine refines, gathers, pushes and pulls patches (Hanrahan, Salzman & Aupperle 1991), volume clusters
//! (Smits, Arvo & Greenberg 1994; Sillion 1995) and face clusters with irradiance vectors (Willmott, Heckbert &
//! Garland 1999) alike.
//!
//! One solution pass of the engine is, for every link r ← s with receiver r and source s,
//!
//!   J_l = emit(l, s)                      what the source sends along the link (the transport's flux: one
//!                                         radiosity per channel for a constant basis),
//!   h_t += deliver(c_{t,l}, J_l)          at every gather target t of the link (r itself, or the faces or
//!                                         leaves below r), with a coefficient c_{t,l} computed once per
//!                                         (target, link) and cached,
//!   h_c += push(p, c, h_p)                from every parent p to each child c, top down,
//!   (B, x)_leaf = reflect(leaf, h)        radiosity (the mean, per channel) and any further exitance state
//!                                         (a higher-order basis: its other coefficients) at each leaf,
//!   (B, x)_p = pull(p, children)          pulled up (by default B_p = Σ A_c B_c / A_p, x_p = Σ x_c).
//!
//! Refinement asks the transport for each link's error (`link_error`, by default the link payload's own:
//! the F, BF and variation oracles of the form-factor [`crate::Link`]), and a point answer asks it for a
//! leaf's radiosity at the point (`radiosity_at`, by default the leaf's mean). What a link carries
//! ([`Transport::Link`], anything implementing [`LinkPayload`]) and what a source sends
//! ([`Transport::Flux`]) are the transport's: a basis of M² functions per element carries M⁴ coefficients
//! per link and sends M² per channel, without a change to the engine.
//!
//! A link r ← s whose transport weighs its source's leaves ([`Transport::weighs_source_leaves`]; patches:
//! a form-factor link to a patch), from an inner node, sends instead the mean of the radiosity of the
//! leaves y below s weighted by [`Transport::source_leaf_weight`] (patches: how much each sees r, A_y F_{y→r};
//! times o_y, the leaf's open share, 1 unless the transport estimates one: [`Transport::open_share`]), not
//! their area mean: the source side sends each leaf's own share, as the receiver side gathers at each leaf.
//!
//! For patches h is irradiance, J the source's radiosity and c = V F (the gather H = Σ V F B); for a
//! face cluster h is an irradiance vector per channel and x a power vector; for a directional cluster h and x
//! are spherical-harmonic coefficients. The transport chooses what each type is.

use std::fmt::Debug;

use glam::DVec3;

use radlab_scene::Rgb;

use crate::node::NodeKind;
use crate::params::Oracle;

/// Per-channel linear state carried by nodes (irradiance, exitance): zero, addition and per-channel scaling,
/// which is all that gather, push, pull and the solver's coarse correction need.
pub trait LinearState: Copy + Default + Send + Sync + Debug {
    /// self += c ⊙ x, channel by channel.
    fn add_scaled(&mut self, c: Rgb, x: &Self);
}

impl LinearState for Rgb {
    fn add_scaled(&mut self, c: Rgb, x: &Self) {
        *self += c * *x;
    }
}

impl LinearState for () {
    fn add_scaled(&mut self, _c: Rgb, _x: &Self) {}
}

/// Per channel, a vector (an irradiance or power vector).
impl LinearState for [glam::DVec3; 3] {
    fn add_scaled(&mut self, c: Rgb, x: &Self) {
        for k in 0..3 {
            self[k] += c[k] * x[k];
        }
    }
}

/// Per channel, nine coefficients (spherical harmonics to order 2).
impl LinearState for [Rgb; 9] {
    fn add_scaled(&mut self, c: Rgb, x: &Self) {
        for (a, b) in self.iter_mut().zip(x) {
            *a += c * *b;
        }
    }
}

/// Where a link's transfer is evaluated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GatherAt {
    /// Once, at the receiver; children get it through push (HSA91's gather; isotropic and directional
    /// clusters; irradiance vectors).
    Receiver,
    /// At each input face below the receiver (the receiver itself if it is a face or lies within one), then
    /// pushed below: an oriented (α) cluster receiver hands each face its own share (Smits et al. 1994).
    Faces,
    /// At each leaf below the receiver, with the kernel integrated over the leaf (exact form-factor sums).
    Leaves,
    /// At the shallowest nodes below the receiver that the transport resolves ([`Transport::resolves`]),
    /// and at the input faces below where no node on the way does, then pushed below: a cluster receiver
    /// whose faces cannot all take the link as one (a normal cone straddling its direction) hands it to its
    /// sub-clusters, and faces are reached one by one only where even those straddle. With a transport that
    /// resolves nothing, the same as [`GatherAt::Faces`].
    Descend,
}

/// What the engine reads of a link, whatever else the transport's link carries ([`Transport::Link`]): its
/// source, whether its ends overlap, and the refinement oracle's estimate of its error. The engine stores
/// links with their receivers, moves them whole and never looks inside: a transport with a higher-order
/// basis carries its M⁴ transfer coefficients here.
pub trait LinkPayload: Clone + Send + Sync + Debug {
    /// The source node's id.
    fn source(&self) -> u32;

    /// Whether the two ends overlap in space (a self-link of a cluster, a cluster and something inside its
    /// bound): the link carries nothing and the refinement must split it (Sillion 1995).
    fn overlap(&self) -> bool {
        false
    }

    /// The refinement oracle's estimate of the link's error under `oracle`, given its light weight
    /// ([`crate::light_weight`]: max over channels of ρ_r B_s over the scene's mean radiosity); the default
    /// of [`Transport::link_error`].
    fn error(&self, oracle: Oracle, weight: f64) -> LinkError;
}

/// A link's error as the refinement reads it ([`crate::decide`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkError {
    /// The estimate e: the link stays when e (times the error norm's factor) is at most ε.
    pub estimate: f64,
    /// The part of the estimate each end alone is responsible for (the F and BF oracles: the smaller of
    /// the two form factors, times the light weight): when it too exceeds ε, both ends are split at once.
    /// `None`: one end is split at a time.
    pub each_end: Option<f64>,
}

/// What the refinement knows of a link's source when it asks for the link's error
/// ([`Transport::link_error`]).
#[derive(Clone, Copy, Debug)]
pub struct SourceLight<'a, N, X> {
    /// The oracle the parameters name.
    pub oracle: Oracle,
    /// The link's light weight: max over channels of ρ_r B_s over the scene's area-mean radiosity
    /// ([`crate::light_weight`]; 0 when nothing is lit).
    pub weight: f64,
    /// The source's radiosity B_s (its mean).
    pub radiosity: Rgb,
    /// The source's exitance state (a higher-order basis: its coefficients beyond the mean).
    pub exitance: &'a X,
    /// The scene's area-mean radiosity (max channel), the light weight's scale.
    pub scale: f64,
    /// The source's children (empty for a leaf, and in linkless shooting), with their radiosity and
    /// exitance: what an estimate with a source-side term compares the source's own state against.
    pub children: &'a [N],
    /// The children's radiosity, aligned with `children`.
    pub child_radiosity: &'a [Rgb],
    /// The children's exitance state, aligned with `children`.
    pub child_exitance: &'a [X],
}

/// What a source sends along a link in one pass ([`Transport::emit`]) and a target receives through its
/// coefficient ([`Transport::deliver`]): for a constant basis one radiosity per channel ([`Rgb`]), for a
/// basis of M² functions per element its M² coefficients per channel.
pub trait SourceFlux: Copy + Default + Send + Sync + Debug + From<Rgb> {
    /// The flux times `s` (the receiver gain of open shares, [`crate::Engine::open_shares`]).
    /// `From<Rgb>` is the flux of a source of uniform radiosity B (what a source weighted over its leaves
    /// sends, [`Transport::source_leaf_weight`]).
    fn scaled(self, s: f64) -> Self;
}

impl SourceFlux for Rgb {
    fn scaled(self, s: f64) -> Self {
        self * s
    }
}

/// A node kind's light model: what a link carries and transfers, how a receiver distributes what it
/// gathers, how push and pull combine parent and children, how a link's error is estimated and how a leaf is
/// evaluated at a point. The hooks with defaults keep the constant (piecewise-constant radiosity) basis of
/// Hanrahan, Salzman & Aupperle 1991; a higher-order basis (Gortler, Schröder, Cohen & Hanrahan 1993) chooses
/// its own link payload, flux, irradiance and exitance types and overrides [`Transport::pull`] and
/// [`Transport::radiosity_at`] (the crate's `tests/transport_contract.rs` shows both).
pub trait Transport<N: NodeKind>: Sync {
    /// What a node gathers and pushes to its children.
    type Irradiance: LinearState;
    /// Exitance state besides the area-mean radiosity the engine always keeps, pulled from children to
    /// parent by [`Transport::pull`] (`()` when radiosity is all a source needs; a higher-order basis's
    /// coefficients beyond the mean).
    type Exitance: LinearState;
    /// A link's coefficient at one gather target, cached between passes.
    type Coefficient: Copy + Send + Sync + Debug;
    /// What a link carries ([`crate::Link`] for the form-factor links of patches and clusters).
    type Link: LinkPayload;
    /// What a source sends along a link in one pass ([`Rgb`] for a constant basis).
    type Flux: SourceFlux;

    /// Whether two root nodes can exchange light at all (a cheap geometric test for the initial links).
    fn may_interact(&self, recv: &N, src: &N) -> bool;

    /// The link carrying light from `src` to `recv` (geometry, visibility and what the oracles read), or
    /// `None` when nothing is transferred. A link whose ends overlap is returned with
    /// [`LinkPayload::overlap`] set: it carries nothing and the refinement must split it.
    fn link(&self, recv: &N, recv_id: u32, src: &N, src_id: u32) -> Option<Self::Link>;

    /// The refinement oracle's estimate of `link`'s error (`recv ← src`), from what the refinement knows
    /// of the source's light (`light`). By default the link's own ([`LinkPayload::error`] under
    /// `light.oracle` and `light.weight`; for [`crate::Link`], the F, BF and variation oracles). A
    /// higher-order basis's oracle reads the source's coefficients there (its exitance).
    fn link_error(
        &self,
        recv: &N,
        src: &N,
        link: &Self::Link,
        light: &SourceLight<'_, N, Self::Exitance>,
    ) -> LinkError {
        let _ = (recv, src);
        link.error(light.oracle, light.weight)
    }

    /// Where the link `recv ← src` is evaluated.
    fn gather_at(&self, recv: &N, src: &N) -> GatherAt;

    /// Whether a [`GatherAt::Descend`] link from `src` is evaluated at `target`, a node strictly between the
    /// link's receiver and the input faces below it, rather than further down. By default nothing is.
    fn resolves(&self, target: &N, src: &N, link: &Self::Link) -> bool {
        let _ = (target, src, link);
        false
    }

    /// The link's coefficient at gather target `target`: the receiver itself (`at_receiver`, from what the
    /// link already holds), or a node, face or leaf below it (a kernel evaluation, counted as a form
    /// factor).
    fn coefficient(
        &self,
        target: &N,
        src: &N,
        link: &Self::Link,
        at_receiver: bool,
    ) -> Self::Coefficient;

    /// What the source sends along `link` (stored with receiver `recv`) this pass, from the per-node radiosity
    /// `b` and exitance `x` (indexed by node id) and the hierarchy `view` (for sources that read their
    /// contents).
    fn emit(
        &self,
        view: &NodeView<'_, N>,
        b: &[Rgb],
        x: &[Self::Exitance],
        recv: u32,
        link: &Self::Link,
    ) -> Self::Flux;

    /// Whether `link` to `recv`, from an inner node, sends instead of its [`Transport::emit`] the mean of the
    /// radiosity of the leaves y below its source weighted by [`Transport::source_leaf_weight`] (the
    /// crate's `gather_rows` module). By default no link does.
    fn weighs_source_leaves(&self, recv: &N, link: &Self::Link) -> bool {
        let _ = (recv, link);
        false
    }

    /// The weight of leaf `leaf` below a link's source in what the link sends to `recv` (patches: how much
    /// the leaf sees the receiver, A_y F_{y→r}, one kernel evaluation), or `None` when it cannot be weighed
    /// (the link then sends its [`Transport::emit`]). Asked only where [`Transport::weighs_source_leaves`]
    /// holds.
    fn source_leaf_weight(&self, leaf: &N, recv: &N) -> Option<f64> {
        let _ = (leaf, recv);
        None
    }

    /// The open share o ∈ [0, 1] of leaf `leaf`: the share of its area light can reach at all
    /// ([`radlab_kernels::open_fraction`]; part of a floor element under a covering sees only the covering's
    /// back), or `None` (the default) when the transport does not estimate it, which is the same as 1. Where
    /// one is below 1 the engine holds every leaf's radiosity and irradiance over its open part
    /// (the crate's `open_share` module). Any rays it casts must go through the accelerator the solver counts rays
    /// on, and its random stream must depend on the leaf only ([`NodeKind::key`]).
    fn open_share(&self, leaf: &N) -> Option<f64> {
        let _ = leaf;
        None
    }

    /// Whether the coefficient of `link` at gather target `target` (from source `src`) measured the target's
    /// own visibility of the source, with rays that start on the target (a patch link below its receiver
    /// with [`crate::LeafVisibility`] rays): it then already leaves out the target's sealed part, and the
    /// target's open-part irradiance is that coefficient over the target's own open share, 1/o_t, not the
    /// link's receiver gain 1/ō_l (the crate's `open_share` module). By default false.
    fn own_visibility(&self, target: &N, src: &N, link: &Self::Link) -> bool {
        let _ = (target, src, link);
        false
    }

    /// The weight of a coefficient in a link's receiver-side open share ō_l = Σ o_t A_t c_t / Σ A_t c_t
    /// (the crate's `open_share` module): its magnitude (a patch: V F). By default 1 (an area-weighted share). Read
    /// only when [`Transport::open_share`] gives shares below 1.
    fn coefficient_weight(&self, c: &Self::Coefficient) -> f64 {
        let _ = c;
        1.0
    }

    /// Adds to `h` what a target with coefficient `c` receives from a link sending `flux`.
    fn deliver(&self, h: &mut Self::Irradiance, c: &Self::Coefficient, flux: Self::Flux);

    /// What child `child` receives of its parent's total irradiance `h` (by default, all of it).
    fn push(&self, parent: &N, child: &N, h: &Self::Irradiance) -> Self::Irradiance {
        let _ = (parent, child);
        *h
    }

    /// A leaf's radiosity (area mean, per channel) and exitance from its total irradiance: B = E + ρ H for
    /// a patch (E omitted when `with_emission` is false, for the solver's linear corrections).
    fn reflect(&self, leaf: &N, h: &Self::Irradiance, with_emission: bool)
    -> (Rgb, Self::Exitance);

    /// An inner node's radiosity and exitance from its children's (`children`, `b` and `x` aligned): by
    /// default the area mean Σ A_c B_c / Σ A_c (zero for no area) and the sum of the exitance. A basis with
    /// more than the mean per element pulls its coefficients by its two-scale relation. (Where some leaf is
    /// partly sealed, [`Transport::open_share`], the engine takes the radiosity as the mean over open areas
    /// and the exitance from this hook.)
    fn pull(
        &self,
        parent: &N,
        children: &[N],
        b: &[Rgb],
        x: &[Self::Exitance],
    ) -> (Rgb, Self::Exitance) {
        let _ = parent;
        let mut sum = Rgb::ZERO;
        let mut area = 0.0;
        let mut xs = Self::Exitance::default();
        for ((c, bc), xc) in children.iter().zip(b).zip(x) {
            let a = c.area();
            sum += a * *bc;
            area += a;
            xs.add_scaled(Rgb::ONE, xc);
        }
        (if area > 0.0 { sum / area } else { Rgb::ZERO }, xs)
    }

    /// The radiosity of leaf `leaf` at `point` (on the leaf), from its radiosity `b` (the mean) and exitance
    /// `x`: by default `b`, constant over the leaf. What an answering layer reads at a point
    /// ([`crate::Engine::radiosity_at_leaf`]).
    fn radiosity_at(&self, leaf: &N, b: Rgb, x: &Self::Exitance, point: DVec3) -> Rgb {
        let _ = (leaf, x, point);
        b
    }

    /// A leaf's radiosity and exitance under unit irradiance from every direction, without emission (a
    /// patch: B = ρ): the furnace mode the engine's coarse correction removes in one pass.
    fn uniform_response(&self, leaf: &N) -> (Rgb, Self::Exitance);

    /// A leaf's radiosity and exitance when it sends B = 1 on every channel, whatever its reflectance: the
    /// source state with which a gather measures the discrete operator's row sums Σ_s K_ls
    /// ([`crate::Engine::normalise_closed_rows`]). `None` (the default) when the transport does not say; row
    /// normalisation is then unavailable.
    fn unit_response(&self, leaf: &N) -> Option<(Rgb, Self::Exitance)> {
        let _ = leaf;
        None
    }
}

/// Read-only access to the hierarchy's structure, for transports whose sources read their contents.
#[derive(Clone, Copy, Debug)]
pub struct NodeView<'e, N> {
    /// Nodes by id.
    pub nodes: &'e [N],
    /// (first child, number of children) by id.
    pub children: &'e [(u32, u32)],
}

impl<N: NodeKind> NodeView<'_, N> {
    /// The input-face nodes in the subtree of `i` (the shallowest node within each face), in id order of
    /// the walk.
    pub fn faces_below(&self, i: u32, out: &mut Vec<u32>) {
        let mut stack = vec![i];
        while let Some(j) = stack.pop() {
            if self.nodes[j as usize].face().is_some() {
                out.push(j);
                continue;
            }
            let (first, count) = self.children[j as usize];
            stack.extend((first..first + count).rev());
        }
    }
}

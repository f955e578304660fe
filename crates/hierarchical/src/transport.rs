//! How light moves through a hierarchy: the interface every node kind's light model implements, so that one
//! engine refines, gathers, pushes and pulls patches (Hanrahan, Salzman & Aupperle 1991), volume clusters
//! (Smits, Arvo & Greenberg 1994; Sillion 1995) and face clusters with irradiance vectors (Willmott, Heckbert &
//! Garland 1999) alike.
//!
//! One solution pass of the engine is, for every link r ← s with receiver r and source s,
//!
//!   J_l = emit(l, s)                      what the source sends along the link (per channel),
//!   h_t += deliver(c_{t,l}, J_l)          at every gather target t of the link (r itself, or the faces or
//!                                         leaves below r), with a coefficient c_{t,l} computed once per
//!                                         (target, link) and cached,
//!   h_c += push(p, c, h_p)                from every parent p to each child c, top down,
//!   (B, x)_leaf = reflect(leaf, h)        radiosity (and any further exitance state) at each leaf,
//!   B_p = Σ A_c B_c / A_p,  x_p = Σ x_c   pulled up.
//!
//! A link r ← s that sends its source's radiosity ([`Transport::sends_source_radiosity`]), from an inner
//! node of patches to a patch, sends instead the mean of the radiosity of the leaves y below s weighted by
//! how much each sees r (o_y A_y F_{y→r}, o_y the leaf's open share, 1 unless the transport estimates one:
//! [`Transport::open_share`]), not their area mean: the source side sends each leaf's own share, as
//! the receiver side gathers at each leaf.
//!
//! For patches h is irradiance, J the source's radiosity and c = V F (the gather H = Σ V F B); for a
//! face cluster h is an irradiance vector per channel and x a power vector; for a directional cluster h and x
//! are spherical-harmonic coefficients. The transport chooses what each type is.

use std::fmt::Debug;

use radlab_scene::Rgb;

use crate::link::Link;
use crate::node::NodeKind;

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

/// A node kind's light model: what a link transfers, how a receiver distributes what it gathers, how push and
/// pull combine parent and children, and the geometry and visibility of links.
pub trait Transport<N: NodeKind>: Sync {
    /// What a node gathers and pushes to its children.
    type Irradiance: LinearState;
    /// Exitance state besides the area-mean radiosity the engine always keeps, summed from children to
    /// parent (`()` when radiosity is all a source needs).
    type Exitance: LinearState;
    /// A link's coefficient at one gather target, cached between passes.
    type Coefficient: Copy + Send + Sync + Debug;

    /// Whether two root nodes can exchange light at all (a cheap geometric test for the initial links).
    fn may_interact(&self, recv: &N, src: &N) -> bool;

    /// The link carrying light from `src` to `recv` (geometry, visibility and what the oracles read), or
    /// `None` when nothing is transferred. A link whose ends overlap is returned with [`Link::overlap`] set:
    /// it carries nothing and the refinement must split it.
    fn link(&self, recv: &N, recv_id: u32, src: &N, src_id: u32) -> Option<Link>;

    /// Where the link `recv ← src` is evaluated.
    fn gather_at(&self, recv: &N, src: &N) -> GatherAt;

    /// Whether a [`GatherAt::Descend`] link from `src` is evaluated at `target`, a node strictly between the
    /// link's receiver and the input faces below it, rather than further down. By default nothing is.
    fn resolves(&self, target: &N, src: &N, link: &Link) -> bool {
        let _ = (target, src, link);
        false
    }

    /// The link's coefficient at gather target `target`: the receiver itself (`at_receiver`, from what the
    /// link already holds), or a node, face or leaf below it (a kernel evaluation, counted as a form
    /// factor).
    fn coefficient(&self, target: &N, src: &N, link: &Link, at_receiver: bool)
    -> Self::Coefficient;

    /// What the source sends along `link` (stored with receiver `recv`) this pass, from the per-node radiosity
    /// `b` and exitance `x` (indexed by node id) and the hierarchy `view` (for sources that read their
    /// contents).
    fn emit(
        &self,
        view: &NodeView<'_, N>,
        b: &[Rgb],
        x: &[Self::Exitance],
        recv: u32,
        link: &Link,
    ) -> Rgb;

    /// Whether `link` sends its source's radiosity (its [`Transport::emit`] is the source's entry of `b`), so
    /// that where the source is an inner node whose leaves and the receiver are patches
    /// ([`NodeKind::patch`]) the engine sends in its place the mean of the leaves' radiosity weighted by how
    /// much each sees the receiver, A_y F_{y→r} (the crate's `gather_rows` module). By default every link not
    /// [`Link::clustered`].
    fn sends_source_radiosity(&self, link: &Link) -> bool {
        !link.clustered
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

    /// The weight of a coefficient in a link's receiver-side open share ō_l = Σ o_t A_t c_t / Σ A_t c_t
    /// (the crate's `open_share` module): its magnitude (a patch: V F). By default 1 (an area-weighted share). Read
    /// only when [`Transport::open_share`] gives shares below 1.
    fn coefficient_weight(&self, c: &Self::Coefficient) -> f64 {
        let _ = c;
        1.0
    }

    /// Adds to `h` what a target with coefficient `c` receives from a link sending `flux`.
    fn deliver(&self, h: &mut Self::Irradiance, c: &Self::Coefficient, flux: Rgb);

    /// What child `child` receives of its parent's total irradiance `h` (by default, all of it).
    fn push(&self, parent: &N, child: &N, h: &Self::Irradiance) -> Self::Irradiance {
        let _ = (parent, child);
        *h
    }

    /// A leaf's radiosity (area mean, per channel) and exitance from its total irradiance: B = E + ρ H for
    /// a patch (E omitted when `with_emission` is false, for the solver's linear corrections).
    fn reflect(&self, leaf: &N, h: &Self::Irradiance, with_emission: bool)
    -> (Rgb, Self::Exitance);

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

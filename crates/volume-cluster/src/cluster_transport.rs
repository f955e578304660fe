//! The transport of volume-clustered hierarchical radiosity: patch–patch links exactly as plain hierarchical
//! radiosity computes them (receiver quadrature of the point-to-polygon factor × sampled visibility, gathered
//! per leaf), and links with a cluster end as point approximations ([`crate::cluster_link`]) whose source side
//! and receiver side are what distinguishes the three transfer modes ([`TransferMode`]: isotropic, α,
//! directional). For a cluster link with visibility V, unit direction d from source to receiver centroid and
//! distance r, a receiving point of normal n gets
//!
//!   H = V J_S(d) max(0, n·(−d)) / (π r²),
//!
//! where J_S(d) = A_s max(0, n_s·d) B_s for a patch source, and for a cluster source the mode's estimate of
//! Σ_i A_i max(0, n_i·d) B_i. A patch receiver takes the mean of the factor V max(0, n·(−d))/(π r²) over its
//! Gauss points (d, r from the source's centroid to each point; the rule its patch links use, so a face's row
//! sums to one wherever the point approximations are exact) and pushes it to its pieces unchanged: a link above
//! the input-face level is never re-evaluated per leaf.

use std::fmt::Debug;

use glam::DVec3;
use radlab_hierarchical::{
    GatherAt, LinearState, Link, NodeKind, NodeView, Patch, PatchKernel, Transport,
};
use radlab_kernels::form_factor::{VisibilitySampling, receiver_points};
use radlab_scene::Rgb;
use radlab_visibility::Accel;

use crate::cluster_link::{centroid_geometry, cluster_link};
use crate::cluster_node::ClusterNode;

/// What a transfer mode decides: where a cluster receiver's links are evaluated, what a cluster source sends,
/// and how irradiance moves below a cluster.
pub trait TransferMode: Sync + Send + Debug + Default {
    /// Irradiance state of a node.
    type Irradiance: LinearState;
    /// Exitance state besides radiosity.
    type Exitance: LinearState;
    /// A link's coefficient at a gather target.
    type Coefficient: Copy + Send + Sync + Debug;
    /// Where the link from `src` to cluster `recv` is evaluated: by default at `recv` if it resolves the link
    /// ([`TransferMode::resolves`]), else below it where clusters do, or at the faces.
    fn gather_at_cluster(recv: &ClusterNode<'_>, src: &ClusterNode<'_>, flat: f64) -> GatherAt {
        if Self::resolves(recv, src, flat) {
            GatherAt::Receiver
        } else {
            GatherAt::Descend
        }
    }
    /// Whether cluster `target` (a link's receiver or a cluster below it) takes the link from `src` as a
    /// whole (by default never: links reach the faces). `flat` is the widest normal cone (half-angle, radians)
    /// that takes a link straddling its faces as a whole ([`crate::VolumeClusterParams::straddle_angle`]).
    fn resolves(target: &ClusterNode<'_>, src: &ClusterNode<'_>, flat: f64) -> bool {
        let _ = (target, src, flat);
        false
    }
    /// A scalar coefficient (irradiance per unit flux) at a patch target.
    fn scalar(c: f64) -> Self::Coefficient;
    /// The coefficient at cluster `target` (the link's receiver or a cluster below it, one that resolves the
    /// link under the same `flat`): `g` = V/(π r²), direction `d` from the source's centroid to the target's,
    /// centroid distance `r`.
    fn at_cluster(
        target: &ClusterNode<'_>,
        g: f64,
        d: DVec3,
        r: f64,
        flat: f64,
    ) -> Self::Coefficient;
    /// J_S(d) of cluster `src`.
    fn cluster_flux(
        view: &NodeView<'_, ClusterNode<'_>>,
        b: &[Rgb],
        x: &[Self::Exitance],
        src: u32,
        d: DVec3,
    ) -> Rgb;
    /// h += c ⊗ flux.
    fn deliver(h: &mut Self::Irradiance, c: &Self::Coefficient, flux: Rgb);
    /// What a child receives of its parent's irradiance.
    fn push(
        parent: &ClusterNode<'_>,
        child: &ClusterNode<'_>,
        h: &Self::Irradiance,
    ) -> Self::Irradiance;
    /// Radiosity and exitance of a leaf patch from its irradiance (E included when `with_emission`).
    fn reflect(
        leaf: &ClusterNode<'_>,
        h: &Self::Irradiance,
        with_emission: bool,
    ) -> (Rgb, Self::Exitance);
    /// A leaf's radiosity and exitance under unit irradiance, without emission (B = ρ).
    fn uniform(leaf: &ClusterNode<'_>) -> (Rgb, Self::Exitance);
    /// A leaf's exitance when it sends B = 1.
    fn unit(leaf: &ClusterNode<'_>) -> Self::Exitance;
}

/// A transfer whose states are scalar irradiance and radiosity (isotropic clusters): only where a cluster
/// receiver's links are evaluated, the coefficient there and what a cluster source sends differ; the scalar
/// gather, push (children inherit the parent's irradiance unchanged) and reflection are shared.
pub trait ScalarTransfer: Sync + Send + Debug + Default {
    /// Where links to a cluster receiver are evaluated.
    const AT_CLUSTER: GatherAt;
    /// The coefficient at a cluster receiver: link coefficient `g` = V/(π r²), direction `d` source → receiver.
    fn at_cluster(g: f64, d: DVec3) -> f64;
    /// J_S(d) of cluster `src` from the radiosity `b` of every node.
    fn cluster_flux(view: &NodeView<'_, ClusterNode<'_>>, b: &[Rgb], src: u32, d: DVec3) -> Rgb;
}

impl<S: ScalarTransfer> TransferMode for S {
    type Irradiance = Rgb;
    type Exitance = ();
    type Coefficient = f64;

    fn gather_at_cluster(_recv: &ClusterNode<'_>, _src: &ClusterNode<'_>, _flat: f64) -> GatherAt {
        <S as ScalarTransfer>::AT_CLUSTER
    }

    fn scalar(c: f64) -> f64 {
        c
    }

    fn at_cluster(_target: &ClusterNode<'_>, g: f64, d: DVec3, _r: f64, _flat: f64) -> f64 {
        <S as ScalarTransfer>::at_cluster(g, d)
    }

    fn cluster_flux(
        view: &NodeView<'_, ClusterNode<'_>>,
        b: &[Rgb],
        _x: &[()],
        src: u32,
        d: DVec3,
    ) -> Rgb {
        <S as ScalarTransfer>::cluster_flux(view, b, src, d)
    }

    fn deliver(h: &mut Rgb, c: &f64, flux: Rgb) {
        *h += *c * flux;
    }

    fn push(_parent: &ClusterNode<'_>, _child: &ClusterNode<'_>, h: &Rgb) -> Rgb {
        *h
    }

    fn reflect(leaf: &ClusterNode<'_>, h: &Rgb, with_emission: bool) -> (Rgb, ()) {
        (reflect_node(leaf, *h, with_emission), ())
    }

    fn uniform(leaf: &ClusterNode<'_>) -> (Rgb, ()) {
        (leaf.reflectance(), ())
    }

    fn unit(_leaf: &ClusterNode<'_>) {}
}

/// The transport, generic over the transfer mode.
#[derive(Debug)]
pub struct ClusterTransport<'a, M> {
    patches: PatchKernel<'a>,
    accel: &'a Accel,
    visibility: VisibilitySampling,
    seed: u64,
    mode: M,
    /// Per input face: whether it shares a region of free space with an emitter ([`crate::enclosure`]);
    /// empty when not computed (every face reachable).
    reachable: Vec<bool>,
    /// Gauss points per side of the receiver rule over a patch (radlab-kernels' `receiver_points`).
    quadrature: u32,
    /// The widest normal cone (half-angle, radians) that takes a link straddling its faces as a whole; 0 by
    /// default ([`ClusterTransport::with_straddle_cone`]).
    straddle_cone: f64,
}

impl<'a, M: TransferMode> ClusterTransport<'a, M> {
    /// A transport whose patch links use `patches` and whose cluster links cast `visibility` rays and are
    /// evaluated at a patch over `quadrature` Gauss points per side.
    pub fn new(
        patches: PatchKernel<'a>,
        accel: &'a Accel,
        visibility: VisibilitySampling,
        quadrature: u32,
        seed: u64,
    ) -> Self {
        Self {
            patches,
            accel,
            visibility,
            seed,
            mode: M::default(),
            reachable: Vec::new(),
            quadrature,
            straddle_cone: 0.0,
        }
    }

    /// The same transport, letting a cluster whose normal cone is at most `half_angle` radians wide take a
    /// link that straddles its faces as a whole, by their mean clamped cosine, where an oriented receiver
    /// would otherwise hand it down to the faces along the line where they turn away from the source.
    pub fn with_straddle_cone(mut self, half_angle: f64) -> Self {
        self.straddle_cone = half_angle;
        self
    }

    /// The same transport, giving no irradiance to faces whose entry in `reachable` (by face id) is false:
    /// faces sealed off from every emitter ([`crate::enclosure::reachable_faces`]).
    pub fn with_reachable(mut self, reachable: Vec<bool>) -> Self {
        self.reachable = reachable;
        self
    }

    /// Whether light can reach `node` (a cluster, or a patch of a reachable face).
    pub fn reaches(&self, node: &ClusterNode<'_>) -> bool {
        node.face()
            .is_none_or(|f| self.reachable.get(f).copied().unwrap_or(true))
    }

    /// The transfer mode.
    pub fn mode(&self) -> &M {
        &self.mode
    }
}

impl<'a, M: TransferMode> Transport<ClusterNode<'a>> for ClusterTransport<'a, M> {
    type Irradiance = M::Irradiance;
    type Exitance = M::Exitance;
    type Coefficient = M::Coefficient;
    type Link = Link;
    type Flux = Rgb;

    fn may_interact(&self, _recv: &ClusterNode<'a>, _src: &ClusterNode<'a>) -> bool {
        true
    }

    fn link(
        &self,
        recv: &ClusterNode<'a>,
        recv_id: u32,
        src: &ClusterNode<'a>,
        src_id: u32,
    ) -> Option<Link> {
        match (recv, src) {
            (ClusterNode::Patch(r), ClusterNode::Patch(s)) => self.patches.patch_link(r, s, src_id),
            _ => cluster_link(
                self.accel,
                self.visibility,
                self.seed,
                recv,
                recv_id,
                src,
                src_id,
            ),
        }
    }

    fn gather_at(&self, recv: &ClusterNode<'a>, src: &ClusterNode<'a>) -> GatherAt {
        match (recv, src) {
            (ClusterNode::Patch(_), ClusterNode::Patch(_)) => self.patches.patch_gather_at(),
            (ClusterNode::Cluster(_), _) => M::gather_at_cluster(recv, src, self.straddle_cone),
            (ClusterNode::Patch(_), ClusterNode::Cluster(_)) => GatherAt::Receiver,
        }
    }

    fn resolves(&self, target: &ClusterNode<'a>, src: &ClusterNode<'a>, _link: &Link) -> bool {
        matches!(target, ClusterNode::Cluster(_)) && M::resolves(target, src, self.straddle_cone)
    }

    fn own_visibility(&self, target: &ClusterNode<'a>, src: &ClusterNode<'a>, link: &Link) -> bool {
        matches!(
            (target, src),
            (ClusterNode::Patch(_), ClusterNode::Patch(_))
        ) && self.patches.patch_own_visibility(link)
    }

    fn coefficient(
        &self,
        target: &ClusterNode<'a>,
        src: &ClusterNode<'a>,
        link: &Link,
        at_receiver: bool,
    ) -> M::Coefficient {
        if !link.clustered
            && let (ClusterNode::Patch(t), ClusterNode::Patch(s)) = (target, src)
        {
            return M::scalar(self.patches.patch_coefficient(t, s, link, at_receiver));
        }
        match target {
            ClusterNode::Cluster(_) => {
                let (d, r2) = centroid_geometry(target.centroid(), src.centroid());
                // Below the receiver, the link's visibility over the target's own distance.
                let g = if at_receiver {
                    link.coefficient
                } else if r2 > 0.0 {
                    link.visibility as f64 / (std::f64::consts::PI * r2)
                } else {
                    0.0
                };
                M::at_cluster(target, g, d, r2.sqrt(), self.straddle_cone)
            }
            ClusterNode::Patch(p) => {
                // The point approximation averaged over the patch's Gauss points (the rule its patch links
                // use): a face's row then sums exact point-to-polygon factors and point approximations at the
                // same points, so the row sums to one wherever the approximations are exact. At the centroid
                // instead, a long face (a sliver) mixed its patch links' means with centroid values: +5.8% in
                // a ρ = 0.9 furnace. The link's visibility is kept; faces sealed off from every emitter get
                // nothing ([`crate::enclosure`]).
                if !self.reaches(target) {
                    return M::scalar(0.0);
                }
                let s = src.centroid();
                let v = link.visibility as f64;
                let g: f64 = receiver_points(&p.polygon, self.quadrature)
                    .iter()
                    .map(|(x, w)| {
                        let (d, r2) = centroid_geometry(*x, s);
                        if r2 > 0.0 {
                            w * p.normal.dot(-d).max(0.0) / (std::f64::consts::PI * r2)
                        } else {
                            0.0
                        }
                    })
                    .sum();
                M::scalar(v * g)
            }
        }
    }

    fn emit(
        &self,
        view: &NodeView<'_, ClusterNode<'a>>,
        b: &[Rgb],
        x: &[M::Exitance],
        recv: u32,
        link: &Link,
    ) -> Rgb {
        let s = link.source as usize;
        if !link.clustered {
            return b[s];
        }
        let (d, _) = centroid_geometry(
            view.nodes[recv as usize].centroid(),
            view.nodes[s].centroid(),
        );
        match &view.nodes[s] {
            ClusterNode::Patch(p) => b[s] * (p.area * p.normal.dot(d).max(0.0)),
            ClusterNode::Cluster(_) => M::cluster_flux(view, b, x, link.source, d),
        }
    }

    fn weighs_source_leaves(&self, recv: &ClusterNode<'a>, link: &Link) -> bool {
        PatchKernel::sends_source_radiosity(link) && recv.patch().is_some()
    }

    fn source_leaf_weight(&self, leaf: &ClusterNode<'a>, recv: &ClusterNode<'a>) -> Option<f64> {
        Some(self.patches.source_weight(leaf.patch()?, recv.patch()?))
    }

    fn open_share(&self, leaf: &ClusterNode<'a>) -> Option<f64> {
        Transport::<Patch>::open_share(&self.patches, leaf.patch()?)
    }

    fn deliver(&self, h: &mut M::Irradiance, c: &M::Coefficient, flux: Rgb) {
        M::deliver(h, c, flux);
    }

    fn push(
        &self,
        parent: &ClusterNode<'a>,
        child: &ClusterNode<'a>,
        h: &M::Irradiance,
    ) -> M::Irradiance {
        M::push(parent, child, h)
    }

    fn reflect(
        &self,
        leaf: &ClusterNode<'a>,
        h: &M::Irradiance,
        with_emission: bool,
    ) -> (Rgb, M::Exitance) {
        if self.reaches(leaf) {
            M::reflect(leaf, h, with_emission)
        } else {
            // Sealed off from every emitter: whatever a cluster link's mean visibility lets through is not
            // light that can arrive here.
            M::reflect(leaf, &M::Irradiance::default(), with_emission)
        }
    }

    fn unit_response(&self, leaf: &ClusterNode<'a>) -> Option<(Rgb, M::Exitance)> {
        Some((Rgb::ONE, M::unit(leaf)))
    }

    fn uniform_response(&self, leaf: &ClusterNode<'a>) -> (Rgb, M::Exitance) {
        if self.reaches(leaf) {
            M::uniform(leaf)
        } else {
            (Rgb::ZERO, M::Exitance::default())
        }
    }
}

/// B = E + ρ h of a patch-like node (a cluster leaf cannot occur: clusters always split).
pub fn reflect_node(leaf: &ClusterNode<'_>, h: Rgb, with_emission: bool) -> Rgb {
    radlab_hierarchical::reflect_scalar(leaf.emission(), leaf.reflectance(), h, with_emission)
}

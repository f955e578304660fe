//! The oriented (α) cluster transfer (Smits, Arvo & Greenberg 1994's α links; Sillion 1995's oriented
//! clusters): a cluster source radiates the intensity Σ_i B_i A_i max(0, n_i·d)/π of its faces toward the
//! receiver, J = Σ_i A_i max(0, n_i·d) B_i, and a cluster receiver gives each contained face j its own share
//! V J max(0, n_j·u)/(π r²) (u toward the source). Both sums are evaluated exactly, but through the clusters'
//! normal cones ([`crate::normal_cone`]) rather than face by face:
//!
//! - source: J(S, d) = P_S·d where every face of S faces d (P_S = Σ A_i B_i n_i, pulled up the hierarchy),
//!   0 where none does, and the sum of J over S's children (clusters and faces) where S's cone straddles d:
//!   cost the number of straddling clusters on the way down, not S's faces;
//! - receiver: a link every face below the receiving cluster faces adds to the cluster's irradiance vector
//!   (faces take n·E at push), one every face turns away from carries nothing, and only a straddling link is
//!   evaluated at each face below (with the face's own Gauss points, distance and direction, and the link's
//!   visibility; faces sealed off from every emitter get nothing, [`crate::enclosure`]).
//!
//! Before the cones every (face, link above it) pair was evaluated, O(k log k) pairs or more, and every
//! source face was summed per link per pass. A vector gathered at the cluster uses the cluster centroid's
//! distance and direction for all its faces where the face-by-face gather used each face's own.

use glam::DVec3;
use radlab_hierarchical::{GatherAt, NodeKind, NodeView};
use radlab_scene::Rgb;

use crate::cluster_node::ClusterNode;
use crate::cluster_transport::TransferMode;
use crate::normal_cone::{
    ALPHA_FAR_RATIO, OrientedCoefficient, OrientedIrradiance, Side, dot3, oriented_at_cluster,
    oriented_deliver, oriented_gather_at, oriented_push, oriented_reflect, power_vector,
};

/// Oriented clusters.
#[derive(Clone, Copy, Debug, Default)]
pub struct Alpha;

/// J = Σ_i A_i max(0, n_i·d) B_i of node `i`, exact, through the normal cones.
fn alpha_flux(
    view: &NodeView<'_, ClusterNode<'_>>,
    b: &[Rgb],
    x: &[[DVec3; 3]],
    i: u32,
    d: DVec3,
) -> Rgb {
    match &view.nodes[i as usize] {
        ClusterNode::Patch(p) => b[i as usize] * (p.area * p.normal.dot(d).max(0.0)),
        ClusterNode::Cluster(c) => match c.data().cone.side(d) {
            Side::Front => dot3(&x[i as usize], d).max(Rgb::ZERO),
            Side::Back => Rgb::ZERO,
            Side::Straddle => {
                let (first, count) = view.children[i as usize];
                (first..first + count).fold(Rgb::ZERO, |j, c| j + alpha_flux(view, b, x, c, d))
            }
        },
    }
}

impl TransferMode for Alpha {
    type Irradiance = OrientedIrradiance;
    type Exitance = [DVec3; 3];
    type Coefficient = OrientedCoefficient;

    fn gather_at_cluster(recv: &ClusterNode<'_>, src: &ClusterNode<'_>) -> GatherAt {
        oriented_gather_at(recv, src, ALPHA_FAR_RATIO)
    }

    fn scalar(c: f64) -> OrientedCoefficient {
        OrientedCoefficient::Scalar(c)
    }

    fn at_cluster(target: &ClusterNode<'_>, g: f64, d: DVec3, r: f64) -> OrientedCoefficient {
        oriented_at_cluster(target, g, d, r)
    }

    fn cluster_flux(
        view: &NodeView<'_, ClusterNode<'_>>,
        b: &[Rgb],
        x: &[[DVec3; 3]],
        src: u32,
        d: DVec3,
    ) -> Rgb {
        alpha_flux(view, b, x, src, d)
    }

    fn deliver(h: &mut OrientedIrradiance, c: &OrientedCoefficient, flux: Rgb) {
        oriented_deliver(h, c, flux);
    }

    fn push(
        parent: &ClusterNode<'_>,
        child: &ClusterNode<'_>,
        h: &OrientedIrradiance,
    ) -> OrientedIrradiance {
        oriented_push(parent, child, h)
    }

    fn reflect(
        leaf: &ClusterNode<'_>,
        h: &OrientedIrradiance,
        with_emission: bool,
    ) -> (Rgb, [DVec3; 3]) {
        oriented_reflect(leaf, h, with_emission)
    }

    fn uniform(leaf: &ClusterNode<'_>) -> (Rgb, [DVec3; 3]) {
        let b = leaf.reflectance();
        (b, power_vector(leaf, b))
    }

    fn unit(leaf: &ClusterNode<'_>) -> [DVec3; 3] {
        power_vector(leaf, Rgb::ONE)
    }
}

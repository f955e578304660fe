//! The isotropic cluster transfer (Smits, Arvo & Greenberg 1994's β links; Sillion 1995's isotropic
//! clusters): a cluster end acts as a sphere of projected area A/4 in every direction. A cluster source sends
//! J = B̄ A/4 (B̄ its area-mean radiosity); a cluster receiver collects (A/4) · V J/(π r²) and spreads it over its
//! area, H = V J/(4π r²), handed to its children unchanged at push time. O(1) per link and O(k + n) per pass.
//! Biased: a flat cluster facing a light receives a quarter of what it should; a closed convex cluster's true
//! projected area is its silhouette, which A/4 matches only on average over directions.

use glam::DVec3;
use radlab_hierarchical::{GatherAt, NodeKind, NodeView};
use radlab_scene::Rgb;

use crate::cluster_node::ClusterNode;
use crate::cluster_transport::ScalarTransfer;

/// Isotropic clusters.
#[derive(Clone, Copy, Debug, Default)]
pub struct Isotropic;

impl ScalarTransfer for Isotropic {
    const AT_CLUSTER: GatherAt = GatherAt::Receiver;

    fn at_cluster(g: f64, _d: DVec3) -> f64 {
        g / 4.0
    }

    fn cluster_flux(view: &NodeView<'_, ClusterNode<'_>>, b: &[Rgb], src: u32, _d: DVec3) -> Rgb {
        b[src as usize] * (view.nodes[src as usize].area() / 4.0)
    }
}

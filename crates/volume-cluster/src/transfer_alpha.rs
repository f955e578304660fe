//! The oriented (α) cluster transfer (Smits, Arvo & Greenberg 1994's α links; Sillion 1995's oriented
//! clusters): a cluster source radiates the intensity Σ_i B_i A_i max(0, n_i·d)/π of its faces toward the
//! receiver (d from the source's centroid to the receiver's), J = Σ_i A_i max(0, n_i·d) B_i, summed exactly;
//! a cluster receiver hands each contained face its own share A_i max(0, n_i·(−d)) through the normal cones'
//! receiver ([`crate::normal_cone::Oriented`]); faces sealed off from every emitter get nothing
//! ([`crate::enclosure`]).
//!
//! - Source: where every face of S faces d, J = P_S·d with the power vector P_S = Σ_i A_i B_i n_i (summed from
//!   children to parent like radiosity); where every face turns away, J = 0; only a source whose normal cone
//!   straddles d sums its faces, so a pass costs O(1) per link but for straddling sources. This is what sets
//!   α apart from the directional transfer, whose straddling sources answer from spherical harmonics.
//! - Receiver: a link every face below the receiving cluster faces adds its field to the cluster's irradiance
//!   vector, to first order about the centroid, and each face takes n_i·E at push (its share, exact in
//!   direction, second order in the cluster's size over the distance in position); a link every face turns
//!   away from carries nothing; a straddling link descends to the clusters below that it does not straddle,
//!   reaching faces one by one only where it straddles down to them.
//!
//! The receiver used to evaluate every link into a cluster at each face below it, over the face's Gauss
//! points: exact in position too, but its cost was the sum over links of the faces below each receiver, and
//! the solve time grew as k^1.6 on the concentric spheres above 10⁴ faces (the per-(face, link) cache held as
//! much). Through the cones a link into a cluster costs O(1) where it does not straddle.

use glam::DVec3;
use radlab_hierarchical::{NodeKind, NodeView};
use radlab_scene::Rgb;

use crate::cluster_node::ClusterNode;
use crate::normal_cone::{Oriented, OrientedSource, Side, cone_of, dot3, power_vector};

/// The exact source of α clusters: the power vector where the cone does not straddle, the faces' sum where
/// it does.
#[derive(Clone, Copy, Debug, Default)]
pub struct ExactSource;

/// Oriented (α) clusters.
pub type Alpha = Oriented<ExactSource>;

impl OrientedSource for ExactSource {
    type Exitance = [DVec3; 3];

    fn cluster_flux(
        view: &NodeView<'_, ClusterNode<'_>>,
        b: &[Rgb],
        x: &[[DVec3; 3]],
        src: u32,
        d: DVec3,
    ) -> Rgb {
        match cone_of(&view.nodes[src as usize]).side(d) {
            Side::Front => dot3(&x[src as usize], d).max(Rgb::ZERO),
            Side::Back => Rgb::ZERO,
            Side::Straddle => {
                let mut faces = Vec::new();
                view.faces_below(src, &mut faces);
                let mut j = Rgb::ZERO;
                for f in faces {
                    let node = &view.nodes[f as usize];
                    if let Some(n) = node.normal() {
                        j += b[f as usize] * (node.area() * n.dot(d).max(0.0));
                    }
                }
                j
            }
        }
    }

    fn exitance(leaf: &ClusterNode<'_>, b: Rgb) -> [DVec3; 3] {
        power_vector(leaf, b)
    }
}

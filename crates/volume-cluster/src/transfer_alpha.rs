//! The oriented (α) cluster transfer (Smits, Arvo & Greenberg 1994's α links; Sillion 1995's oriented
//! clusters): a cluster source radiates the intensity Σ_i B_i A_i max(0, n_i·d)/π of its faces toward the
//! receiver (d from the source's centroid to the receiver's), J = Σ_i A_i max(0, n_i·d) B_i; a cluster receiver
//! hands each contained face j its own share, H_j = V J max(0, n_j·(−d_x))/(π r_x²) averaged over the face's
//! Gauss points x (d_x, r_x from the source's centroid to x; V the link's visibility), evaluated once per
//! (face, link) and cached; faces sealed off from every emitter get nothing ([`crate::enclosure`]).
//!
//! Both sides take the normal cones' exact shortcuts ([`crate::normal_cone`]), which change no value:
//!
//! - source: where every face of S faces d, J = P_S·d with the power vector P_S = Σ_i A_i B_i n_i (summed from
//!   children to parent like radiosity); where every face turns away, J = 0; only a source whose cone
//!   straddles d sums its faces, so a pass costs O(1) per link but for straddling sources;
//! - receiver: where the source's centroid lies behind the plane of every face of the receiving cluster at
//!   every point of it (the cone of directions from the cluster's bounding sphere to the source, half-angle
//!   asin(R/r), entirely behind the normal cone), every H_j is zero and the link is gathered once at the
//!   cluster with coefficient zero; every other link is evaluated face by face.
//!
//! A receiver every face of which faces the source is still gathered face by face: H_j = n_j · V J Σ_x w_x
//! (s − x)/(π |s − x|³) is linear in n_j but not in the face's position, so no per-cluster sum of the links
//! reproduces each face's own distance and direction. The directional transfer's receiver gathers such links
//! at the cluster as a field to first order about its centroid: second order in the cluster's size over the
//! distance (about 1.5 (R/r)² at a face, 3.3% on a plate of 200 faces under a light at R/r = 0.14), where this
//! transfer is exact per face.

use glam::DVec3;
use radlab_hierarchical::{NodeKind, NodeView};
use radlab_scene::Rgb;

use crate::cluster_node::ClusterNode;
use crate::cluster_transport::{TransferMode, reflect_node};
use crate::normal_cone::{Side, cone_of, dot3, power_vector};

/// Oriented clusters.
#[derive(Clone, Copy, Debug, Default)]
pub struct Alpha;

/// Whether `src`'s centroid lies behind the plane of every face of cluster `recv` at every point of its box:
/// then no face below `recv` receives anything from it under the face-by-face gather.
fn behind_every_face(recv: &ClusterNode<'_>, src: &ClusterNode<'_>) -> bool {
    let ClusterNode::Cluster(_) = recv else {
        return false;
    };
    let c = recv.centroid();
    let v = src.centroid() - c;
    let r = v.length();
    let (lo, hi) = recv.bbox();
    // Bounding radius about the centroid: its farthest box corner.
    let radius = (0..8)
        .map(|k| {
            let corner = DVec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            );
            (corner - c).length()
        })
        .fold(0.0, f64::max);
    if !(r > radius) {
        return false;
    }
    // n·(s − x) = r n·u − n·(x − c) ≤ r n·u + R for every face normal n and point x within R of c: it is
    // at most zero for every n in the cone when the cone's largest n·u, cos(φ − θ), is at most −R/r.
    cone_of(recv).behind(v / r, radius / r)
}

impl TransferMode for Alpha {
    type Irradiance = Rgb;
    type Exitance = [DVec3; 3];
    type Coefficient = f64;

    /// A cluster behind every face of which the source lies takes the link (as nothing).
    fn resolves(target: &ClusterNode<'_>, src: &ClusterNode<'_>) -> bool {
        behind_every_face(target, src)
    }

    fn scalar(c: f64) -> f64 {
        c
    }

    /// Only links behind every face are gathered at a cluster: they carry nothing.
    fn at_cluster(_target: &ClusterNode<'_>, _g: f64, _d: DVec3, _r: f64) -> f64 {
        0.0
    }

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

    fn deliver(h: &mut Rgb, c: &f64, flux: Rgb) {
        *h += *c * flux;
    }

    fn push(_parent: &ClusterNode<'_>, _child: &ClusterNode<'_>, h: &Rgb) -> Rgb {
        *h
    }

    fn reflect(leaf: &ClusterNode<'_>, h: &Rgb, with_emission: bool) -> (Rgb, [DVec3; 3]) {
        let b = reflect_node(leaf, *h, with_emission);
        (b, power_vector(leaf, b))
    }

    fn uniform(leaf: &ClusterNode<'_>) -> (Rgb, [DVec3; 3]) {
        let b = leaf.reflectance();
        (b, power_vector(leaf, b))
    }

    fn unit(leaf: &ClusterNode<'_>) -> [DVec3; 3] {
        power_vector(leaf, Rgb::ONE)
    }
}

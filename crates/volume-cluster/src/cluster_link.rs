//! A link with a cluster at one end or both: a point approximation between the two nodes' area centroids,
//! a visibility fraction from rays between points on the nodes' contents, and conservative form-factor bounds
//! for the refinement oracles.
//!
//! - Overlap: if the ends' boxes intersect (a self-link, a cluster and anything inside or touching its box),
//!   the point approximation is meaningless and the link carries nothing until refined (Sillion 1995).
//! - Transfer (point approximation, Sillion 1995 eq. 5; Smits, Arvo & Greenberg 1994): with d the unit vector
//!   from source centroid to receiver centroid and r their distance, a receiver point of normal n gets the
//!   irradiance V J max(0, n·(−d)) / (π r²) from a source sending J = Σ_i A_i max(0, n_i·d) B_i (per
//!   channel); the link stores V/(π r²) and each transfer mode decides what J and the receiver's share are.
//! - Bounds (Smits et al. 1994, as Christensen restates them): with d_min the distance between the two boxes,
//!   every cosine ≤ 1 gives F_rs ≤ A_s/(π d_min²) and F_sr ≤ A_r/(π d_min²) (each capped at 1); these stand in
//!   for the patch links' form factors in the `f`, `bf` and `variation` oracles, so a link is refined until the
//!   bound on the power it carries, ρ_r B_s A_r F_rs relative to the scene's, is below ε.
//! - Visibility: rays between points on the faces of the two ends, never between empty box corners, each pair
//!   weighted by its kernel cos θ cos θ'/r² as for patches (a pair behind either face weighs nothing). A point
//!   on a cluster is drawn area-proportionally among its faces (O(log k)), redrawn up to eight times until its
//!   face looks toward the other end's centroid. Because the rays start and end on faces, occlusion inside
//!   either cluster along the segment (a face behind another, seen from the other end) counts; what a one-
//!   number visibility cannot express is which faces are shadowed: every face of a receiving cluster gets the
//!   link's mean (Sillion & Drettakis 1995's "shelf of books" energy gain), the α transfer included (its
//!   faces get their own cosine and distance, not their own visibility). The product of a mean visibility and
//!   a mean source flux can carry light into a sealed interior inside a receiving cluster; faces sealed off
//!   from every emitter are found once and given no irradiance ([`crate::enclosure`]).

use glam::DVec3;
use radlab_hierarchical::{Link, NodeKind, link_stream};
use radlab_kernels::form_factor::{VisibilitySampling, pair_kernel};
use radlab_scene::{FaceId, sampling};
use radlab_visibility::{Accel, PACKET_SEGMENTS, Segment};

use crate::cluster_node::ClusterNode;

/// Distance between two boxes (0 if they intersect).
pub fn box_distance(a: (DVec3, DVec3), b: (DVec3, DVec3)) -> f64 {
    let gap = (a.0 - b.1).max(b.0 - a.1).max(DVec3::ZERO);
    gap.length()
}

/// Direction (source → receiver) and squared distance between two nodes' centroids.
pub fn centroid_geometry(recv: DVec3, src: DVec3) -> (DVec3, f64) {
    let v = recv - src;
    (v.normalize_or_zero(), v.length_squared())
}

/// A point on the node's contents, its face and the face's normal, looking toward `toward` if one of eight
/// draws does.
pub(crate) fn sample_point(
    node: &ClusterNode<'_>,
    toward: DVec3,
    rng: &mut sampling::Rng,
) -> (DVec3, FaceId, DVec3) {
    let mut last = (node.centroid(), 0, DVec3::ZERO);
    for _ in 0..8 {
        let (u0, u1, u2) = (
            sampling::uniform(rng),
            sampling::uniform(rng),
            sampling::uniform(rng),
        );
        let (p, f, n) = match node {
            ClusterNode::Patch(p) => (p.polygon.sample_uniform(u1, u2), p.face, p.normal),
            ClusterNode::Cluster(c) => {
                let f = c.tree.face_at(c.id, u0);
                (
                    c.scene.polygon(f).sample_uniform(u1, u2),
                    f,
                    c.scene.faces[f].normal,
                )
            }
        };
        last = (p, f, n);
        if n.dot(toward - p) > 0.0 {
            break;
        }
    }
    last
}

/// The link `recv ← src` when at least one end is a cluster.
pub fn cluster_link(
    accel: &Accel,
    visibility: VisibilitySampling,
    seed: u64,
    recv: &ClusterNode<'_>,
    recv_id: u32,
    src: &ClusterNode<'_>,
    src_id: u32,
) -> Option<Link> {
    let (rb, sb) = (recv.bbox(), src.bbox());
    let d_min = box_distance(rb, sb);
    let (_, r2) = centroid_geometry(recv.centroid(), src.centroid());
    if recv_id == src_id || d_min <= 0.0 || r2 <= 0.0 {
        return Some(Link::overlapping(src_id));
    }
    // A patch end with the whole other box behind its plane exchanges nothing.
    let behind = |p: &radlab_hierarchical::Patch, (lo, hi): (DVec3, DVec3)| {
        (0..8).all(|k| {
            let c = DVec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            );
            p.normal.dot(c - p.centroid) <= 0.0
        })
    };
    if recv.as_patch().is_some_and(|p| behind(p, sb))
        || src.as_patch().is_some_and(|p| behind(p, rb))
    {
        return None;
    }
    let v = match visibility.rays() {
        0 => 1.0,
        n => {
            let (kr, ks) = (recv.key(), src.key());
            let (a, b) = if kr <= ks { (recv, src) } else { (src, recv) };
            let mut rng = sampling::rng(seed, link_stream(kr, ks));
            let (ca, cb) = (a.centroid(), b.centroid());
            facing_fraction_visible(
                accel,
                n,
                |rng| (sample_point(a, cb, rng), sample_point(b, ca, rng)),
                &mut rng,
            )
        }
    };
    let pi_d2 = std::f64::consts::PI * d_min * d_min;
    let f_rs = (src.area() / pi_d2).min(1.0);
    let f_sr = (recv.area() / pi_d2).min(1.0);
    Some(Link {
        source: src_id,
        coefficient: v / (std::f64::consts::PI * r2),
        f_recv: f_rs as f32,
        f_src: f_sr as f32,
        spread: f_rs.max(f_sr) as f32,
        visibility: v as f32,
        overlap: false,
        clustered: true,
    })
}
/// A sampled point, its face and the face's normal.
type PointOnFace = (DVec3, FaceId, DVec3);

/// The kernel-weighted fraction of `n` sampled point pairs that see each other, Σ w v / Σ w with
/// w = cos θ cos θ' / r² (radlab-kernels' `pair_kernel`): the same estimator as the patches' visibility
/// fraction, so a pair behind either face (zero kernel) is no sample of visibility and near-horizon pairs
/// weigh what they carry. No facing pair gives 0.
fn facing_fraction_visible(
    accel: &Accel,
    n: u32,
    mut pair: impl FnMut(&mut sampling::Rng) -> (PointOnFace, PointOnFace),
    rng: &mut sampling::Rng,
) -> f64 {
    // The facing pairs and their kernels, a packet at a time, then their visibility as one packet; summed in
    // the order drawn.
    let (mut seen, mut facing) = (0.0, 0.0);
    let mut weights = [0.0; PACKET_SEGMENTS];
    let mut segments = [Segment {
        p: DVec3::ZERO,
        fp: 0,
        q: DVec3::ZERO,
        fq: 0,
    }; PACKET_SEGMENTS];
    let mut visible = [false; PACKET_SEGMENTS];
    let mut drawn = 0;
    while drawn < n {
        let mut len = 0;
        while drawn < n && len < PACKET_SEGMENTS {
            drawn += 1;
            let ((p, fp, np), (q, fq, nq)) = pair(rng);
            let w = pair_kernel(p, np, q, nq);
            if w > 0.0 {
                weights[len] = w;
                segments[len] = Segment { p, fp, q, fq };
                len += 1;
            }
        }
        accel.visible_many(&segments[..len], &mut visible[..len]);
        for (&w, &v) in weights.iter().zip(&visible).take(len) {
            facing += w;
            if v {
                seen += w;
            }
        }
    }
    if facing > 0.0 { seen / facing } else { 0.0 }
}

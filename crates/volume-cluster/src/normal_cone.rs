//! Normal cones of clusters and the oriented receiver they make exact and cheap. A cluster's normal cone is
//! the smallest cone about the area-weighted mean normal a = Σ A_i n_i/|Σ A_i n_i| holding every face
//! normal, half-angle θ = max_i ∠(a, n_i) (Shirman & Abi-Ezzi 1993's cone of normals, here an exact bound
//! over the cluster's faces). For a unit direction u at angle φ from a:
//!
//! - φ + θ ≤ π/2: every face has n_i·u ≥ 0, so Σ_i A_i B_i max(0, n_i·u) = P·u with the power vector
//!   P = Σ_i A_i B_i n_i (exact: a cluster source facing u is a vector source);
//! - φ − θ ≥ π/2: every face has n_i·u ≤ 0, and nothing is exchanged in direction u;
//! - otherwise the cone straddles the plane normal to u, and the faces must be taken one by one.
//!
//! On the receiver side the same test on the arrival direction u = −d (d from the source's centroid to the
//! receiver's) decides how a link to a cluster is gathered. Links that every face faces add their irradiance
//! field E(x) = V J (s − x)/(π |s − x|³) (s the source's centroid) to the cluster's, kept as its value and
//! gradient at the cluster's centroid c, E(c) = V J u/(π r²) and ∇E(c) = V J (3 u uᵀ − I)/(π r³), moved to
//! each child's centroid at push, E(c') = E(c) + ∇E (c' − c); a face of normal n at x takes n·E(x): the sum
//! over such links of V J max(0, n·u_x)/(π r_x²) with no term clamped (Sillion 1995's oriented clusters with
//! the irradiance-vector push of Willmott, Heckbert & Garland 1999), to second order in the cluster's size
//! over r, where the face-by-face gather it replaces evaluated each face's own distance and direction. Links
//! behind every face carry nothing. A straddling link descends: each child cluster takes the same test toward
//! the source from its own centroid and gathers the link's field there (at its own distance, so to second order
//! in its own size) if it does not straddle, and hands it further down if it does; only faces below clusters
//! that straddle all the way down are evaluated one by one (Smits, Arvo & Greenberg 1994's α gather). A flat
//! or gently curved cluster straddles only links near its own plane, and of a straddling cluster only the
//! children along the line where its surface turns away from the source straddle again (on a smooth
//! surface about √m faces of a cluster of m faces are evaluated instead of m; measured on the concentric
//! spheres at 3e4 faces, 26 M kernel evaluations instead of 168 M).
//!
//! That frontier still grows with the number of faces: a link straddling a receiver of m faces costs about √m
//! evaluations, so on a finer mesh the same links cost more. A straddled cluster whose cone is at most a set
//! half-angle θ wide (`straddle_angle`) therefore takes the link whole: every face below it receives
//! V J c̄/(π r²), c̄ the faces' mean clamped cosine toward the source, estimated from the cone and the faces'
//! mean normal ([`NormalCone::mean_clamped_cosine`]; within sin(2θ)/2 of a face square to the link for
//! θ ≤ 45°, and within a twentieth of that on the tessellated caps of the crate's tests). The descent then
//! stops at clusters of a given angular size, whose number along the line where the surface turns away does
//! not grow with the mesh.

use std::f64::consts::FRAC_PI_2;

use std::fmt::Debug;

use glam::{DMat3, DVec3};
use radlab_hierarchical::{LinearState, NodeKind, NodeView};
use radlab_scene::Rgb;

use crate::cluster_node::ClusterNode;
use crate::cluster_transport::{TransferMode, reflect_node};

/// The cone of a cluster's face normals.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalCone {
    /// Unit axis (the area-weighted mean normal).
    pub axis: DVec3,
    /// Half-angle in radians: π when nothing is known (every direction straddles).
    pub half_angle: f64,
    /// The faces' area-mean normal Σ A_i n_i / Σ A_i (length at most one): its dot product with a direction
    /// is their area-mean cosine toward it.
    pub mean_normal: DVec3,
}

/// Where a direction lies relative to a cone's faces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// Every face has n·u ≥ 0.
    Front,
    /// Every face has n·u ≤ 0.
    Back,
    /// Some faces each way.
    Straddle,
}

impl NormalCone {
    /// A cone that knows nothing: every direction straddles.
    pub const UNKNOWN: Self = Self {
        axis: DVec3::Z,
        half_angle: std::f64::consts::PI,
        mean_normal: DVec3::ZERO,
    };

    /// The cone of unit normals `n` weighted by areas `a`.
    pub fn of(normals: impl Iterator<Item = (f64, DVec3)> + Clone) -> Self {
        let sum: DVec3 = normals.clone().map(|(a, n)| a * n).sum();
        let total: f64 = normals.clone().map(|(a, _)| a).sum();
        let mean_normal = if total > 0.0 {
            sum / total
        } else {
            DVec3::ZERO
        };
        if !(sum.length() > 1e-9 * total) {
            return Self {
                mean_normal,
                ..Self::UNKNOWN
            };
        }
        let axis = sum.normalize();
        let half_angle = normals.map(|(_, n)| angle(axis, n)).fold(0.0, f64::max);
        Self {
            axis,
            half_angle,
            mean_normal,
        }
    }

    /// The side of unit direction `u`.
    pub fn side(&self, u: DVec3) -> Side {
        let phi = angle(self.axis, u);
        if phi + self.half_angle <= FRAC_PI_2 {
            Side::Front
        } else if phi - self.half_angle >= FRAC_PI_2 {
            Side::Back
        } else {
            Side::Straddle
        }
    }

    /// The faces' area-mean clamped cosine toward unit `u`, (1/A) Σ_i A_i max(0, n_i·u), from the cone
    /// alone: their mean cosine m = `mean_normal`·u is exact, and the cosines are taken as spread evenly over
    /// the widest range about m within the range the cone allows, [cos(φ + θ), cos(φ − θ)] (φ the angle
    /// between the axis and u): over [l, h] ∋ 0 the mean of max(0, x) is h²/(2(h − l)). The truth and this
    /// estimate both lie between Jensen's max(0, m) and the two-point spread h_c (m − l_c)/(h_c − l_c) over
    /// the cone's range [l_c, h_c], so the error is at most that gap, whose largest value (at m = 0) is
    /// h_c |l_c|/(h_c + |l_c|), relative to a face square to u: where u straddles the cone (|φ − π/2| < θ)
    /// both ends are below sin 2θ for θ ≤ 45°, so the error is below sin(2θ)/2 (and below 1/2 for any cone).
    /// Exact where the cone faces u whole (m) or turns from it whole (0).
    pub fn mean_clamped_cosine(&self, u: DVec3) -> f64 {
        let phi = angle(self.axis, u);
        let hi = (phi - self.half_angle).max(0.0).cos();
        let lo = (phi + self.half_angle).min(std::f64::consts::PI).cos();
        let m = self.mean_normal.dot(u).clamp(lo, hi);
        let w = (m - lo).min(hi - m);
        let (l, h) = (m - w, m + w);
        if l >= 0.0 {
            m
        } else if h <= 0.0 {
            0.0
        } else {
            h * h / (2.0 * (h - l))
        }
    }
}

/// The angle between two unit vectors, robust near 0 and π.
fn angle(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

/// The cone of a node: a patch's is its normal (half-angle 0), a cluster's from the tree.
pub fn cone_of(node: &ClusterNode<'_>) -> NormalCone {
    match node {
        ClusterNode::Patch(p) => NormalCone {
            axis: p.normal,
            half_angle: 0.0,
            mean_normal: p.normal,
        },
        ClusterNode::Cluster(c) => c.data().cone,
    }
}

/// Per channel, the power vector Σ A B n of a patch of radiosity `b`.
pub fn power_vector(leaf: &ClusterNode<'_>, b: Rgb) -> [DVec3; 3] {
    match leaf.normal() {
        Some(n) => std::array::from_fn(|k| leaf.area() * b[k] * n),
        None => [DVec3::ZERO; 3],
    }
}

/// P·d per channel.
pub fn dot3(p: &[DVec3; 3], d: DVec3) -> Rgb {
    Rgb::new(p[0].dot(d), p[1].dot(d), p[2].dot(d))
}

/// Irradiance of a node under the oriented receiver: scalar at patches; at clusters, per channel, the
/// irradiance field of the links every face below faces, to first order about the cluster's centroid c.
#[derive(Clone, Copy, Debug)]
pub struct OrientedIrradiance {
    /// Irradiance of a patch.
    pub scalar: Rgb,
    /// Per channel, E(c) = Σ V J u/(π r²) (clusters).
    pub vector: [DVec3; 3],
    /// Per channel, its gradient ∇E(c) = Σ V J (3 u uᵀ − I)/(π r³) (symmetric).
    pub gradient: [DMat3; 3],
}

impl Default for OrientedIrradiance {
    /// Zero (glam's `DMat3::default()` is the identity, not zero).
    fn default() -> Self {
        Self {
            scalar: Rgb::ZERO,
            vector: [DVec3::ZERO; 3],
            gradient: [DMat3::ZERO; 3],
        }
    }
}

impl LinearState for OrientedIrradiance {
    fn add_scaled(&mut self, c: Rgb, x: &Self) {
        self.scalar += c * x.scalar;
        self.vector.add_scaled(c, &x.vector);
        for k in 0..3 {
            self.gradient[k] += c[k] * x.gradient[k];
        }
    }
}

/// A coefficient of the oriented receiver: scalar at a patch, a vector at a cluster.
#[derive(Clone, Copy, Debug)]
pub enum OrientedCoefficient {
    /// Irradiance per unit flux at a patch.
    Scalar(f64),
    /// At a cluster that faces u with every face, the field e = V u/(π r²) and 1/r, from which deliver
    /// forms the gradient V (3 u uᵀ − I)/(π r³) = (3 e eᵀ/|e| − |e| I)/r (zero if every face faces away;
    /// 32 bytes rather than the 96 of a vector and a matrix, in every cached row entry).
    Field(DVec3, f64),
}

/// The source half of an oriented transfer: what a cluster sends toward d, from its exitance state. The
/// receiver half, the normal cones', is [`Oriented`]'s.
pub trait OrientedSource: Sync + Send + Debug + Default {
    /// What a node sends besides its radiosity, summed from children to parent.
    type Exitance: LinearState;
    /// J_S(d) = Σ_i A_i B_i max(0, n_i·d) of cluster `src`, or the transfer's estimate of it.
    fn cluster_flux(
        view: &NodeView<'_, ClusterNode<'_>>,
        b: &[Rgb],
        x: &[Self::Exitance],
        src: u32,
        d: DVec3,
    ) -> Rgb;
    /// The exitance of a leaf patch of radiosity `b`.
    fn exitance(leaf: &ClusterNode<'_>, b: Rgb) -> Self::Exitance;
}

/// An oriented transfer: source `S`, the normal cones' receiver.
#[derive(Clone, Copy, Debug, Default)]
pub struct Oriented<S>(pub S);

impl<S: OrientedSource> TransferMode for Oriented<S> {
    type Irradiance = OrientedIrradiance;
    type Exitance = S::Exitance;
    type Coefficient = OrientedCoefficient;

    /// A cluster takes a link as a whole (its field, or nothing) if every face below it faces the source's
    /// centroid or every face faces away, or, straddled, if its normal cone is no wider than `flat` (its
    /// faces' mean clamped cosine, [`NormalCone::mean_clamped_cosine`]); any other straddling link descends
    /// to the clusters below ([`radlab_hierarchical::GatherAt::Descend`]), or to the faces. At any distance:
    /// the first-order field's error at a face is second order in R/r (the cluster's bounding radius over the
    /// distance), about 2 (R/r)² of its value (a plate facing a source square on: (1 + δ²/r²)^(−2) ≈
    /// 1 − 2δ²/r², the first-order term vanishing; measured 3.3% at R/r = 0.14), and cancels to first order on
    /// the mean over the cluster. (Gathered at the cluster only below R/r = 0.07, within 1% of a face-by-face
    /// gather, no link qualified on the concentric spheres up to k = 1e4.)
    fn resolves(target: &ClusterNode<'_>, src: &ClusterNode<'_>, flat: f64) -> bool {
        let u = (src.centroid() - target.centroid()).normalize_or_zero();
        let cone = cone_of(target);
        cone.side(u) != Side::Straddle || cone.half_angle <= flat
    }

    fn scalar(c: f64) -> OrientedCoefficient {
        OrientedCoefficient::Scalar(c)
    }

    /// The irradiance field of a point source, V (s − x)/(π |s − x|³), at the cluster's centroid, with its
    /// gradient formed at deliver; at a straddled cluster no wider than `flat`, V/(π r²) times its faces'
    /// mean clamped cosine, handed to every face alike.
    fn at_cluster(
        target: &ClusterNode<'_>,
        g: f64,
        d: DVec3,
        r: f64,
        flat: f64,
    ) -> OrientedCoefficient {
        let u = -d;
        let cone = cone_of(target);
        match cone.side(u) {
            Side::Front if r > 0.0 => OrientedCoefficient::Field(g * u, 1.0 / r),
            Side::Straddle if cone.half_angle <= flat => {
                OrientedCoefficient::Scalar(g * cone.mean_clamped_cosine(u))
            }
            _ => OrientedCoefficient::Field(DVec3::ZERO, 0.0),
        }
    }

    fn cluster_flux(
        view: &NodeView<'_, ClusterNode<'_>>,
        b: &[Rgb],
        x: &[S::Exitance],
        src: u32,
        d: DVec3,
    ) -> Rgb {
        S::cluster_flux(view, b, x, src, d)
    }

    fn deliver(h: &mut OrientedIrradiance, c: &OrientedCoefficient, flux: Rgb) {
        match c {
            OrientedCoefficient::Scalar(s) => h.scalar += *s * flux,
            OrientedCoefficient::Field(e, inv_r) => {
                let g = e.length();
                if g > 0.0 {
                    let t = *inv_r
                        * (3.0 / g * DMat3::from_cols(e.x * *e, e.y * *e, e.z * *e)
                            - g * DMat3::IDENTITY);
                    for k in 0..3 {
                        h.vector[k] += flux[k] * *e;
                        h.gradient[k] += flux[k] * t;
                    }
                }
            }
        }
    }

    /// A cluster's field moved to the child's centroid, E(c') = E(c) + ∇E (c' − c), to a child cluster;
    /// n·E(x) at a patch's centroid x (the mean over the patch of a linear field) to a patch, unclamped so
    /// that the operator stays linear (a clamp stalls the solver's convergence test; n·E is a first-order
    /// expansion of a sum of non-negative terms, negative only where the expansion is off by more than its
    /// value); a patch's scalar to its pieces.
    fn push(
        parent: &ClusterNode<'_>,
        child: &ClusterNode<'_>,
        h: &OrientedIrradiance,
    ) -> OrientedIrradiance {
        let ClusterNode::Cluster(_) = parent else {
            return *h;
        };
        let dx = child.centroid() - parent.centroid();
        let field: [DVec3; 3] = std::array::from_fn(|k| h.vector[k] + h.gradient[k] * dx);
        match child.normal() {
            Some(n) => OrientedIrradiance {
                scalar: h.scalar + dot3(&field, n),
                ..OrientedIrradiance::default()
            },
            None => OrientedIrradiance {
                scalar: h.scalar,
                vector: field,
                gradient: h.gradient,
            },
        }
    }

    fn reflect(
        leaf: &ClusterNode<'_>,
        h: &OrientedIrradiance,
        with_emission: bool,
    ) -> (Rgb, S::Exitance) {
        let b = reflect_node(leaf, h.scalar, with_emission);
        (b, S::exitance(leaf, b))
    }

    fn uniform(leaf: &ClusterNode<'_>) -> (Rgb, S::Exitance) {
        let b = leaf.reflectance();
        (b, S::exitance(leaf, b))
    }

    fn unit(leaf: &ClusterNode<'_>) -> S::Exitance {
        S::exitance(leaf, Rgb::ONE)
    }
}

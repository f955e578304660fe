//! The directional cluster transfer: each cluster keeps directional descriptions of what it sends and what it
//! receives, so a link costs O(1) and faces are reached only through push (the role of Christensen,
//! Lischinski, Stollnitz & Salesin 1997's tabulated cluster radiance). radlab's description is spherical
//! harmonics to order 2 (nine coefficients per channel; Sillion et al. 1991, Ramamoorthi & Hanrahan 2001)
//! rather than direction bins: both sides are sums of clamped cosines, which order 2 represents within a few
//! percent, while a 32-bin table misplaces a face's lobe by up to half a bin (about 20°).
//!
//! - Source: J_S(d) = Σ_i A_i B_i max(0, n_i·d) ≈ max(0, Σ_lm X_lm Y_lm(d)), X = Σ_i A_i B_i Â_l Y_lm(n_i),
//!   pulled up the hierarchy by summing children (exact), each leaf patch contributing its own lobe.
//! - Receiver: a cluster stores the irradiance it receives as a function of a surface normal n,
//!   H(n) = Σ_links V J/(π r²) max(0, n·(−d)) ≈ Σ_lm C_lm Y_lm(n), C += V J/(π r²) Â_l Y_lm(−d); pushed to
//!   child clusters unchanged, and turned into scalar irradiance max(0, Σ C_lm Y_lm(n_f)) where it reaches a
//!   face of normal n_f. Unlike an irradiance vector, opposite contributions do not cancel.
//!
//! Biased by the order-2 truncation (a single lobe peaks 6% high and leaks 9% of its peak sideways); exact
//! push; O(k + n) per pass.

use glam::DVec3;
use radlab_hierarchical::{GatherAt, LinearState, NodeKind, NodeView};
use radlab_scene::Rgb;

use crate::cluster_node::ClusterNode;
use crate::cluster_transport::{TransferMode, reflect_node};
use crate::spherical_harmonics::{clamped_cosine, evaluate};

/// Directional clusters.
#[derive(Clone, Copy, Debug, Default)]
pub struct Directional;

/// Irradiance of a node: scalar (patches) and as a function of the normal (clusters).
#[derive(Clone, Copy, Debug, Default)]
pub struct DirectionalIrradiance {
    /// Irradiance of a patch.
    pub scalar: Rgb,
    /// Spherical-harmonic coefficients of H(n), per channel (clusters).
    pub sh: [Rgb; 9],
}

impl LinearState for DirectionalIrradiance {
    fn add_scaled(&mut self, c: Rgb, x: &Self) {
        self.scalar += c * x.scalar;
        self.sh.add_scaled(c, &x.sh);
    }
}

/// A coefficient: scalar at a patch, a lobe at a cluster.
#[derive(Clone, Copy, Debug)]
pub enum DirectionalCoefficient {
    /// Irradiance per unit flux at a patch.
    Scalar(f64),
    /// The lobe V/(π r²) Â_l Y_lm(−d).
    Lobe([f64; 9]),
}

/// Evaluates per-channel coefficients at direction `w`.
fn evaluate_rgb(c: &[Rgb; 9], w: DVec3) -> Rgb {
    Rgb::new(
        evaluate(&c.map(|v| v.x), w),
        evaluate(&c.map(|v| v.y), w),
        evaluate(&c.map(|v| v.z), w),
    )
}

/// The exitance lobe of a patch of radiosity `b`: A B Â_l Y_lm(n).
fn patch_lobe(leaf: &ClusterNode<'_>, b: Rgb) -> [Rgb; 9] {
    match leaf.normal() {
        Some(n) => clamped_cosine(n).map(|c| b * (c * leaf.area())),
        None => [Rgb::ZERO; 9],
    }
}

impl TransferMode for Directional {
    type Irradiance = DirectionalIrradiance;
    type Exitance = [Rgb; 9];
    type Coefficient = DirectionalCoefficient;
    const AT_CLUSTER: GatherAt = GatherAt::Receiver;

    fn scalar(c: f64) -> DirectionalCoefficient {
        DirectionalCoefficient::Scalar(c)
    }

    fn at_cluster(g: f64, d: DVec3) -> DirectionalCoefficient {
        DirectionalCoefficient::Lobe(clamped_cosine(-d).map(|c| g * c))
    }

    fn cluster_flux(
        _view: &NodeView<'_, ClusterNode<'_>>,
        _b: &[Rgb],
        x: &[[Rgb; 9]],
        src: u32,
        d: DVec3,
    ) -> Rgb {
        evaluate_rgb(&x[src as usize], d).max(Rgb::ZERO)
    }

    fn deliver(h: &mut DirectionalIrradiance, c: &DirectionalCoefficient, flux: Rgb) {
        match c {
            DirectionalCoefficient::Scalar(s) => h.scalar += *s * flux,
            DirectionalCoefficient::Lobe(l) => {
                for (a, k) in h.sh.iter_mut().zip(l) {
                    *a += *k * flux;
                }
            }
        }
    }

    fn push(
        parent: &ClusterNode<'_>,
        child: &ClusterNode<'_>,
        h: &DirectionalIrradiance,
    ) -> DirectionalIrradiance {
        match (parent, child.normal()) {
            // Cluster to patch: the irradiance function at the patch's normal.
            (ClusterNode::Cluster(_), Some(n)) => DirectionalIrradiance {
                scalar: h.scalar + evaluate_rgb(&h.sh, n).max(Rgb::ZERO),
                sh: [Rgb::ZERO; 9],
            },
            _ => *h,
        }
    }

    fn reflect(
        leaf: &ClusterNode<'_>,
        h: &DirectionalIrradiance,
        with_emission: bool,
    ) -> (Rgb, [Rgb; 9]) {
        let b = reflect_node(leaf, h.scalar, with_emission);
        (b, patch_lobe(leaf, b))
    }

    fn uniform(leaf: &ClusterNode<'_>) -> (Rgb, [Rgb; 9]) {
        let b = leaf.reflectance();
        (b, patch_lobe(leaf, b))
    }
}

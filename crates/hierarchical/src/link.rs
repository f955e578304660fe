//! The form-factor link: what a link of the patch and cluster transports carries ([`Link`], their
//! [`crate::Transport::Link`]): the transfer coefficient of the gather H_r += K_rs B_s (for patches
//! K_rs = V_rs F_rs, the crate's `patch_transport` module) and what the refinement oracles read (Hanrahan,
//! Salzman & Aupperle 1991; Stamminger et al. 1997): both unoccluded form factors F_rs and F_sr, the spread
//! of the kernel samples over the receiver, and the visibility fraction V_rs. Its error estimate is the
//! oracle's ([`crate::oracle::estimate`]: F, BF or variation).
//!
//! The random stream of a link's rays is a hash of its two nodes' keys (which depend on what the nodes are,
//! not on when they were made), ordered, so the link and its reverse see the same rays, and a run is
//! identical for any thread count and any schedule.

use glam::DVec3;
use radlab_scene::sampling;

use crate::params::Oracle;
use crate::transport::{LinkError, LinkPayload};

/// A transport link, stored with its receiver.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Link {
    /// The source node.
    pub source: u32,
    /// Transfer coefficient: irradiance at the receiver per unit radiosity of the source (V F_rs).
    pub coefficient: f64,
    /// Unoccluded form factor from the receiver to the source, F_rs.
    pub f_recv: f32,
    /// Unoccluded form factor from the source to the receiver, F_sr.
    pub f_src: f32,
    /// Spread of the kernel samples over the receiver (the largest sample when partly visible).
    pub spread: f32,
    /// Visibility fraction V_rs.
    pub visibility: f32,
    /// The two ends overlap in space (a self-link, or a cluster and something inside its bound): the link
    /// carries nothing and must be refined (Sillion 1995).
    pub overlap: bool,
    /// A point-approximated transfer between node centroids (a cluster link), not a kernel quadrature;
    /// `coefficient` then holds V/(π r²).
    pub clustered: bool,
}

impl Link {
    /// A link between overlapping ends: no transfer, and the largest possible estimate for the oracles.
    pub fn overlapping(source: u32) -> Self {
        Self {
            source,
            coefficient: 0.0,
            f_recv: f32::INFINITY,
            f_src: f32::INFINITY,
            spread: f32::INFINITY,
            visibility: 1.0,
            overlap: true,
            clustered: true,
        }
    }
}

impl LinkPayload for Link {
    fn source(&self) -> u32 {
        self.source
    }

    fn overlap(&self) -> bool {
        self.overlap
    }

    /// The F, BF or variation oracle ([`crate::oracle::estimate`]); for F and BF each end's own part is
    /// the smaller form factor times the light weight (1 for F).
    fn error(&self, oracle: Oracle, weight: f64) -> LinkError {
        let w = if oracle == Oracle::F { 1.0 } else { weight };
        LinkError {
            estimate: crate::oracle::estimate(oracle, self, weight),
            each_end: (oracle != Oracle::Variation)
                .then(|| (self.f_recv.min(self.f_src) as f64) * w),
        }
    }
}

/// The random stream of the link between nodes with keys `a` and `b` ([`NodeKind::key`]); symmetric.
pub fn link_stream(a: u64, b: u64) -> u64 {
    let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
    sampling::mix64(lo ^ sampling::mix64(hi))
}

/// Direction from `a` to `b`, normalised (zero if they coincide).
pub fn direction(a: DVec3, b: DVec3) -> DVec3 {
    (b - a).normalize_or_zero()
}

//! Refinement oracles and the choice of which end of a link to split (Hanrahan, Salzman & Aupperle 1991; Stamminger et al. 1997).
//!
//! The estimate e of a link r ← s is its transport's ([`crate::Transport::link_error`]); for the form-factor
//! [`Link`] of patches and clusters it is, by [`Oracle`]:
//!
//! - F:         e = max(F_rs, F_sr)                      (Hanrahan, Salzman & Aupperle 1991, "F refinement")
//! - BF:        e = max(F_rs, F_sr) · max_c(ρ_r B_s)/B̄   (HSA91, "BF refinement"; B̄ the scene's area-mean radiosity)
//! - variation: e = spread_k F_{dA(x_k)→s} · max_c(ρ_r B_s)/B̄   (Stamminger et al. 1997, sampling)
//!
//! A link with e ≤ ε stays. Otherwise the end with the larger projected area toward the other is split (HSA91;
//! ties within rounding go to the larger area, then to the receiver, so the choice does not depend on scale),
//! or the other end if that one has reached the minimum size; both ends are split at once only where both
//! must be: when each end's own factor alone exceeds the threshold (min(F_rs, F_sr)·w > ε) or the link is a
//! self-link. A link whose ends are both at the minimum size stays.
//!
//! Clusters (Sillion 1995; Smits, Arvo & Greenberg 1994): a link whose ends overlap in space carries nothing
//! and is always refined — a self-link into all pairs of children, each child's self-link included; another
//! overlapping pair by splitting its larger end. While a source cluster contains an emitter, the source end is
//! split, so emitters are reached as surfaces before anything they light is resolved.

use crate::link::{Link, direction};
use crate::node::NodeKind;
use crate::params::Oracle;
use crate::transport::LinkError;
use radlab_scene::Rgb;

/// What to do with one link in a refinement pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action {
    /// It meets the oracle (or cannot be refined): keep it.
    Keep,
    /// Replace it by links from the source to the receiver's children.
    SplitReceiver,
    /// Replace it by links from the source's children to the receiver.
    SplitSource,
    /// Replace it by links between all pairs of children.
    SplitBoth,
}

/// Whether `a < b` by more than rounding (relative 1e-9), so that symmetric configurations tie at any scale.
fn clearly_less(a: f64, b: f64) -> bool {
    a < b - 1e-9 * a.abs().max(b.abs())
}

/// The light weight w of a link for the BF and variation oracles: max over channels of ρ_r B_s, over the
/// scene's area-mean radiosity `scale` (0 when nothing is lit).
pub fn light_weight(reflectance: Rgb, source_radiosity: Rgb, scale: f64) -> f64 {
    if scale > 0.0 {
        (reflectance * source_radiosity).max_element() / scale
    } else {
        0.0
    }
}

/// The oracle's estimate e for a form-factor link, given its light weight (ignored by [`Oracle::F`]).
pub fn estimate(oracle: Oracle, link: &Link, weight: f64) -> f64 {
    let f = link.f_recv.max(link.f_src) as f64;
    match oracle {
        Oracle::F => f,
        Oracle::Bf => f * weight,
        Oracle::Variation => link.spread as f64 * weight,
    }
}

/// Decides the fate of link `recv ← src`: `error` is the transport's estimate of its error
/// ([`crate::Transport::link_error`]), `None` for a link whose ends overlap. `norm` multiplies the estimate:
/// 1 for the radiosity norm, A_r / A_scene for the power norm ([`crate::ErrorNorm`]).
pub fn decide<N: NodeKind>(
    epsilon: f64,
    min_size: f64,
    recv: &N,
    src: &N,
    self_link: bool,
    error: Option<LinkError>,
    norm: f64,
) -> Action {
    let can_r = recv.can_split(min_size);
    let can_s = src.can_split(min_size);
    let Some(error) = error else {
        return match (self_link, can_r, can_s) {
            (true, true, _) => Action::SplitBoth,
            (true, false, _) | (false, false, false) => Action::Keep,
            (false, true, false) => Action::SplitReceiver,
            (false, false, true) => Action::SplitSource,
            (false, true, true) => {
                if clearly_less(recv.area(), src.area()) {
                    Action::SplitSource
                } else {
                    Action::SplitReceiver
                }
            }
        };
    };
    let e = error.estimate * norm;
    if e.is_nan() || e <= epsilon {
        return Action::Keep;
    }
    if self_link {
        return if can_r {
            Action::SplitBoth
        } else {
            Action::Keep
        };
    }
    if can_s && !src.sends_own_emission() && src.emission().max_element() > 0.0 {
        return Action::SplitSource;
    }
    let both = error.each_end.is_some_and(|m| m * norm > epsilon);
    if both && can_r && can_s {
        return Action::SplitBoth;
    }
    let d = direction(recv.bound().centre, src.bound().centre);
    let receiver_larger = !clearly_less(recv.projected_area(d), src.projected_area(-d))
        && !clearly_less(recv.area(), src.area());
    match (receiver_larger, can_r, can_s) {
        (true, true, _) | (false, true, false) => Action::SplitReceiver,
        (false, _, true) | (true, false, true) => Action::SplitSource,
        _ => Action::Keep,
    }
}

//! The irradiance a link brings to a face cluster as a linear field over the receiver instead of one value
//! at its centroid c:
//!
//!   e(y) ≈ e(c) + J (y − c),   J = ∂e/∂y,
//!
//! the irradiance Jacobian (Arvo 1994, "The irradiance Jacobian for partially occluded polyhedral sources";
//! Holzschuch & Sillion 1995 use such gradients to bound a link's error). Without it every face of a cluster
//! takes the irradiance at the cluster's centroid, an error of first order in the cluster's size: on a flat
//! floor of 10⁴ faces under an area light (ρ = 0.01, so the light is all direct) the faces' answers stayed
//! 3.2% (constant) and 1.8% (Gouraud) from the path-traced reference at ε = 1e-6, converging only as fast as
//! the links split the floor.
//!
//! J is taken by central differences of the link's own unoccluded kernel, J e_k = (f(c + h e_k) − f(c −
//! h e_k)) / 2h along the three axes with h half the receiver's bounding radius (the secant across the
//! cluster, which a linear field over the cluster should match, rather than the tangent at c), six more
//! evaluations of the kernel per link, counted with the rest:
//! - a near single face: its exact irradiance vector (the point-to-polygon form) at each point;
//! - the point form: −d(y) (a·d(y))/(a·d(c)) / (π |y − s|²), with d(y) the unit vector from the source's
//!   centroid s and a the source's cone axis, so the source's cosine turns as its power vector would if its
//!   radiosity were even (a volume, or a source some face of which turns away from the link, sends what it
//!   sends in every nearby direction: the ratio is left out).
//!
//! The link's visibility multiplies J as it does e (one fraction per link), and a link whose point transfer
//! is capped (close clusters, g = V/max(A_R, A_S)) has none. Push carries it: a child at centroid c' receives
//! its parent's e(c') = e(c) + J (c' − c) and J. At a cluster leaf the reflected power p = p_E + M e uses
//! e(c) alone (the moment Σ ρ_i A_i n_i n_iᵀ J (c_i − c) is not stored; it vanishes on a flat cluster, whose
//! Σ A_i (c_i − c) is zero); faces take e at their own centroids.

use glam::{DMat3, DVec3};
use serde::{Deserialize, Serialize};

/// How a link's irradiance spreads over a cluster receiver.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum IrradianceField {
    /// One irradiance for the whole receiver, taken at its centroid (Willmott, Heckbert & Garland 1999).
    Constant,
    /// The irradiance at the centroid and its Jacobian: a linear field over the receiver. The default.
    #[default]
    Linear,
}

impl IrradianceField {
    /// The name used in parameters.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Constant => "constant",
            Self::Linear => "linear",
        }
    }
}

/// Kernel evaluations one Jacobian takes (two per axis).
pub const JACOBIAN_EVALUATIONS: u64 = 6;

/// The secant Jacobian of `f` about `c` over ±`h` along each axis: column k is (f(c + h e_k) − f(c −
/// h e_k)) / 2h. `None` when `f` is undefined at a sample (`None`) or `h` is not positive.
pub fn central_jacobian(f: impl Fn(DVec3) -> Option<DVec3>, c: DVec3, h: f64) -> Option<DMat3> {
    if !(h > 0.0 && h.is_finite()) {
        return None;
    }
    let col = |axis: DVec3| Some((f(c + axis * h)? - f(c - axis * h)?) / (2.0 * h));
    let j = DMat3::from_cols(col(DVec3::X)?, col(DVec3::Y)?, col(DVec3::Z)?);
    j.is_finite().then_some(j)
}

/// The point form's irradiance direction and falloff at `y` from a source at `s`: −d (a·d)/(a·d_c) /
/// (π |y − s|²) with d the unit vector from `s` to `y`, or −d / (π |y − s|²) without an `axis` a; `None` at
/// the source or where the source's cosine a·d is not positive. `d_c` is the direction to the receiver's
/// centroid, where the ratio is one.
pub fn point_field(y: DVec3, s: DVec3, axis: Option<DVec3>, d_c: DVec3) -> Option<DVec3> {
    let v = y - s;
    let r2 = v.length_squared();
    if r2 <= 0.0 {
        return None;
    }
    let d = v / r2.sqrt();
    let ratio = match axis {
        Some(a) => {
            let (at_y, at_c) = (a.dot(d), a.dot(d_c));
            if at_y <= 0.0 || at_c <= 0.0 {
                return None;
            }
            at_y / at_c
        }
        None => 1.0,
    };
    Some(-d * (ratio / (std::f64::consts::PI * r2)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The central difference of a quadratic field is its exact Jacobian at the centre (the second-order
    /// terms cancel), to rounding.
    #[test]
    fn central_differences_are_exact_on_a_quadratic_field() {
        let f = |y: DVec3| {
            Some(DVec3::new(
                y.x * y.y + 3.0 * y.z,
                y.x * y.x - y.z,
                2.0 * y.y * y.z + y.x,
            ))
        };
        let c = DVec3::new(0.3, -1.2, 2.0);
        let j = central_jacobian(f, c, 0.25).expect("defined");
        let want = DMat3::from_cols(
            DVec3::new(c.y, 2.0 * c.x, 1.0),
            DVec3::new(c.x, 0.0, 2.0 * c.z),
            DVec3::new(3.0, -1.0, 2.0 * c.y),
        );
        assert!(j.abs_diff_eq(want, 1e-12), "{j} vs {want}");
        assert!(central_jacobian(f, c, 0.0).is_none());
        assert!(central_jacobian(|_| None, c, 0.25).is_none());
    }

    /// Under a small source facing straight down at height h, a floor point at horizontal offset x gets
    /// n·e = h²/(π r⁴) (both cosines h/r over r²). The link sends the source's cosine at the receiver's
    /// centroid, h/r_c, and the point field carries the rest and the change of both: its value times h/r_c
    /// is the closed form at the centroid, and its Jacobian's derivative of n·e along x, times h/r_c, is the
    /// closed form's, −4 h² x/(π r⁶) at x = 0.3 (within the central difference's error at h = 1e-4).
    #[test]
    fn the_point_field_turns_the_source_s_cosine() {
        let (s, h) = (DVec3::new(0.0, 0.0, 2.0), 2.0);
        let axis = Some(DVec3::NEG_Z);
        let y = DVec3::new(0.3, 0.0, 0.0);
        let d_c = (y - s).normalize();
        let r2: f64 = 0.09 + h * h;
        let sent = h / r2.sqrt();
        let n = DVec3::Z;
        let e = point_field(y, s, axis, d_c).expect("in front");
        let want = h * h / (std::f64::consts::PI * r2 * r2);
        assert!(
            (sent * n.dot(e) - want).abs() <= 1e-15,
            "{} vs {want}",
            sent * n.dot(e)
        );
        let j = central_jacobian(|p| point_field(p, s, axis, d_c), y, 1e-4).expect("defined");
        let slope = sent * n.dot(j.col(0));
        let want = -4.0 * h * h * 0.3 / (std::f64::consts::PI * r2 * r2 * r2);
        assert!(
            (slope - want).abs() <= 1e-7 * want.abs(),
            "{slope} vs {want}"
        );
        assert!(point_field(DVec3::new(0.0, 0.0, 3.0), s, axis, d_c).is_none());
    }
}

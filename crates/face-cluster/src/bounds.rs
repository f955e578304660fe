//! The bounds a face-cluster node carries, each merged from its children's in O(1):
//!
//! - a normal cone (axis a, half-angle θ) holding every face normal; the union of two cones is the smallest
//!   cone holding both, θ = (θ₁ + ∠(a₁, a₂) + θ₂)/2 with the axis turned from a₁ toward a₂ by θ − θ₁
//!   (Shirman & Abi-Ezzi 1993, section 3), or the full sphere θ = π when that reaches past π;
//! - an oriented box in the node's fitted frame (the eigenvectors of its vertex scatter, see
//!   [`crate::moments`]), holding its children's boxes: the 16 corners of the two child boxes projected on
//!   the node's axes (Gottschalk, Lin & Manocha 1996 fit boxes to the points; a box of boxes is the O(1)
//!   bound that stays valid);
//! - a bounding sphere, the smallest sphere holding the two child spheres.

use glam::DVec3;
use serde::{Deserialize, Serialize};

/// A cone of directions: every direction d with ∠(d, axis) ≤ half_angle.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct NormalCone {
    /// Unit axis.
    pub axis: DVec3,
    /// Half-angle in radians, in [0, π] (π: every direction).
    pub half_angle: f64,
}

impl NormalCone {
    /// The cone of one direction.
    pub fn of_normal(n: DVec3) -> Self {
        Self {
            axis: n,
            half_angle: 0.0,
        }
    }

    /// Whether `d` (unit) lies in the cone, with an angular slack `tol` in radians.
    pub fn contains(&self, d: DVec3, tol: f64) -> bool {
        angle_between(self.axis, d) <= self.half_angle + tol
    }

    /// The smallest cone holding both (Shirman & Abi-Ezzi 1993).
    pub fn union(&self, o: &Self) -> Self {
        let between = angle_between(self.axis, o.axis);
        if between + o.half_angle <= self.half_angle {
            return *self;
        }
        if between + self.half_angle <= o.half_angle {
            return *o;
        }
        let half = 0.5 * (self.half_angle + between + o.half_angle);
        if half >= std::f64::consts::PI {
            return Self {
                axis: self.axis,
                half_angle: std::f64::consts::PI,
            };
        }
        // Turn self.axis toward o.axis by (half − θ₁) in their common plane.
        let turn = half - self.half_angle;
        let perp = o.axis - self.axis * self.axis.dot(o.axis);
        let perp = if perp.length() > 1e-12 {
            perp.normalize()
        } else {
            // Opposite axes: any perpendicular plane will do; pick one deterministically.
            self.axis.any_orthonormal_vector()
        };
        let axis = (self.axis * turn.cos() + perp * turn.sin()).normalize();
        // Widen by a few ulps of angle so rounding in the turn cannot leave a normal outside.
        Self {
            axis,
            half_angle: (half + 4.0 * f64::EPSILON).min(std::f64::consts::PI),
        }
    }
}

/// The angle between two unit vectors, accurate near 0 and π (atan2 of |a × b| and a·b).
pub fn angle_between(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

/// A box with its own orthonormal axes.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct OrientedBox {
    /// Centre.
    pub centre: DVec3,
    /// Right-handed orthonormal axes; in a node's fitted frame the last is the plane normal.
    pub axes: [DVec3; 3],
    /// Half-extents along the axes (≥ 0).
    pub half_extents: DVec3,
}

impl OrientedBox {
    /// The box with these axes holding `points`.
    pub fn fit(axes: [DVec3; 3], points: impl IntoIterator<Item = DVec3>) -> Self {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for p in points {
            let q = DVec3::new(axes[0].dot(p), axes[1].dot(p), axes[2].dot(p));
            lo = lo.min(q);
            hi = hi.max(q);
        }
        let mid = 0.5 * (lo + hi);
        Self {
            centre: axes[0] * mid.x + axes[1] * mid.y + axes[2] * mid.z,
            axes,
            half_extents: 0.5 * (hi - lo),
        }
    }

    /// The eight corners.
    pub fn corners(&self) -> [DVec3; 8] {
        let h = self.half_extents;
        std::array::from_fn(|i| {
            let s = |bit: usize| if i & (1 << bit) == 0 { -1.0 } else { 1.0 };
            self.centre
                + self.axes[0] * (s(0) * h.x)
                + self.axes[1] * (s(1) * h.y)
                + self.axes[2] * (s(2) * h.z)
        })
    }

    /// Whether `p` is inside, with slack `tol` (a length) on every side.
    pub fn contains(&self, p: DVec3, tol: f64) -> bool {
        let d = p - self.centre;
        (0..3).all(|i| self.axes[i].dot(d).abs() <= self.half_extents[i] + tol)
    }

    /// Half the diagonal: the radius of the sphere about the centre holding the box.
    pub fn radius(&self) -> f64 {
        self.half_extents.length()
    }

    /// The box's area projected along unit direction `d`: 4 Σ_{i<j} h_i h_j |a_k·d| (k the third axis), an
    /// upper bound on the projected area of anything inside it.
    pub fn projected_area(&self, d: DVec3) -> f64 {
        let h = self.half_extents;
        4.0 * (h.y * h.z * self.axes[0].dot(d).abs()
            + h.x * h.z * self.axes[1].dot(d).abs()
            + h.x * h.y * self.axes[2].dot(d).abs())
    }
}

/// A sphere.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sphere {
    /// Centre.
    pub centre: DVec3,
    /// Radius (≥ 0).
    pub radius: f64,
}

impl Sphere {
    /// A sphere about `centre` holding `points`.
    pub fn about(centre: DVec3, points: &[DVec3]) -> Self {
        let radius = points
            .iter()
            .map(|&p| (p - centre).length())
            .fold(0.0, f64::max);
        Self { centre, radius }
    }

    /// The smallest sphere holding both.
    pub fn union(&self, o: &Self) -> Self {
        let d = o.centre - self.centre;
        let dist = d.length();
        if dist + o.radius <= self.radius {
            return *self;
        }
        if dist + self.radius <= o.radius {
            return *o;
        }
        let radius = 0.5 * (dist + self.radius + o.radius);
        let centre = self.centre + d * ((radius - self.radius) / dist);
        // A relative ulp of slack against rounding in the centre.
        Self {
            centre,
            radius: radius * (1.0 + 4.0 * f64::EPSILON),
        }
    }

    /// Whether `p` is inside, with slack `tol`.
    pub fn contains(&self, p: DVec3, tol: f64) -> bool {
        (p - self.centre).length() <= self.radius + tol
    }
}

#[cfg(test)]
mod tests {
    use glam::dvec3;

    use super::*;

    #[test]
    fn cone_union_is_the_smallest_cone_holding_both() {
        let a = NormalCone::of_normal(DVec3::Z);
        let b = NormalCone::of_normal(DVec3::X);
        let u = a.union(&b);
        assert!((u.half_angle - std::f64::consts::FRAC_PI_4).abs() < 1e-12);
        assert!((u.axis - dvec3(1.0, 0.0, 1.0).normalize()).length() < 1e-12);
        assert!(u.contains(DVec3::Z, 1e-12) && u.contains(DVec3::X, 1e-12));
        // Opposite normals need the full half-space on either side: θ = π/2 around any perpendicular axis.
        let o = a.union(&NormalCone::of_normal(-DVec3::Z));
        assert!((o.half_angle - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert!(o.axis.dot(DVec3::Z).abs() < 1e-12);
    }

    #[test]
    fn sphere_union_holds_both() {
        let a = Sphere {
            centre: DVec3::ZERO,
            radius: 1.0,
        };
        let b = Sphere {
            centre: dvec3(4.0, 0.0, 0.0),
            radius: 1.0,
        };
        let u = a.union(&b);
        assert!(
            (u.radius - 3.0).abs() < 1e-12 && (u.centre - dvec3(2.0, 0.0, 0.0)).length() < 1e-12
        );
        assert_eq!(
            a.union(&Sphere {
                centre: DVec3::X * 0.5,
                radius: 0.1
            }),
            a
        );
    }
}

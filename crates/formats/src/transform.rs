//! Affine placement of scene objects and meshes: p′ = t + R (s ⊙ p). Scale first (uniform or per axis), then
//! one rotation by `angle` degrees about `axis` through the origin (right-hand rule; Rodrigues' formula via a
//! unit quaternion), then translation. A transform with a negative scale determinant is a mirror: polygons
//! placed by it have their vertex order reversed so their normals keep facing the same side of the surface.

use glam::{DMat3, DQuat, DVec3};

/// Scale, then rotate, then translate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// Per-axis scale factors (non-zero, finite).
    pub scale: DVec3,
    /// Rotation axis (non-zero, finite; need not be unit length).
    pub axis: DVec3,
    /// Rotation angle in degrees about `axis`, right-hand rule.
    pub angle_deg: f64,
    /// Translation.
    pub translate: DVec3,
}

impl Default for Transform {
    /// The identity.
    fn default() -> Self {
        Self {
            scale: DVec3::ONE,
            axis: DVec3::Y,
            angle_deg: 0.0,
            translate: DVec3::ZERO,
        }
    }
}

impl Transform {
    /// Checks every field; the message names the bad one.
    pub fn validate(&self) -> Result<(), String> {
        if !self.scale.is_finite() || self.scale.to_array().contains(&0.0) {
            return Err(format!(
                "scale {} must be finite and non-zero in every axis",
                self.scale
            ));
        }
        if !self.axis.is_finite() || self.axis.length_squared() == 0.0 {
            return Err(format!(
                "rotation axis {} must be a finite, non-zero vector",
                self.axis
            ));
        }
        if !self.angle_deg.is_finite() {
            return Err(format!(
                "rotation angle {} must be finite (degrees)",
                self.angle_deg
            ));
        }
        if !self.translate.is_finite() {
            return Err(format!("translate {} must be finite", self.translate));
        }
        Ok(())
    }

    /// The linear part R·S as a matrix.
    pub fn linear(&self) -> DMat3 {
        let axis = self.axis.normalize_or(DVec3::Y);
        let r = DMat3::from_quat(DQuat::from_axis_angle(axis, self.angle_deg.to_radians()));
        r * DMat3::from_diagonal(self.scale)
    }

    /// The transformed point.
    pub fn apply(&self, p: DVec3) -> DVec3 {
        self.linear() * p + self.translate
    }

    /// A function applying the transform, with the matrix computed once.
    pub fn applier(&self) -> impl Fn(DVec3) -> DVec3 + use<> {
        let (m, t) = (self.linear(), self.translate);
        move |p| m * p + t
    }

    /// Whether the transform mirrors (negative determinant), so polygon winding must be reversed.
    pub fn reverses_orientation(&self) -> bool {
        self.scale.x * self.scale.y * self.scale.z < 0.0
    }

    /// Whether it is exactly the identity.
    pub fn is_identity(&self) -> bool {
        self.scale == DVec3::ONE && self.angle_deg == 0.0 && self.translate == DVec3::ZERO
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn order_is_scale_rotate_translate() {
        let t = Transform {
            scale: DVec3::splat(2.0),
            axis: DVec3::Z,
            angle_deg: 90.0,
            translate: DVec3::new(10.0, 0.0, 0.0),
        };
        // (1,0,0) → scale (2,0,0) → rotate 90° about z (0,2,0) → translate (10,2,0).
        let p = t.apply(DVec3::X);
        assert!((p - DVec3::new(10.0, 2.0, 0.0)).length() < 1e-12, "{p}");
        assert!(!t.reverses_orientation());
        let m = Transform {
            scale: DVec3::new(-1.0, 1.0, 1.0),
            ..Transform::default()
        };
        assert!(m.reverses_orientation());
        assert!(Transform::default().is_identity());
    }
}

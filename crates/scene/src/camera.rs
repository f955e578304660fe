//! A pinhole camera: the ray through image position (x, y) leaves the eye along
//! w + (2x/width − 1) tan(fov_y/2) (width/height) u + (1 − 2y/height) tan(fov_y/2) v, normalised (u, v, w the
//! camera's orthonormal frame; x right, y down, in pixels). Rendering through it is `radlab_answer::render_solution`.

use glam::DVec3;

use crate::Ray;

/// A pinhole camera.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub eye: DVec3,
    /// A point it looks at.
    pub target: DVec3,
    /// Up direction (need not be orthogonal to the view direction).
    pub up: DVec3,
    /// Vertical field of view in degrees.
    pub fov_y_deg: f64,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl Camera {
    /// Checks the camera is usable; the message names the field.
    pub fn validate(&self) -> Result<(), crate::SceneError> {
        let bad = |field: &str, message: &str| {
            Err(crate::SceneError::Invalid {
                field: format!("camera.{field}"),
                message: message.into(),
            })
        };
        if !(self.eye.is_finite() && self.target.is_finite() && self.up.is_finite()) {
            return bad("eye/target/up", "coordinates must be finite numbers");
        }
        if (self.target - self.eye).length_squared() == 0.0 {
            return bad("target", "must differ from eye");
        }
        if self.up.cross(self.target - self.eye).length_squared() == 0.0 {
            return bad("up", "must not be parallel to the view direction");
        }
        if !(self.fov_y_deg > 0.0 && self.fov_y_deg < 179.0) {
            return bad(
                "fov",
                "vertical field of view must be between 0 and 179 degrees",
            );
        }
        if self.width == 0 || self.height == 0 || self.width > 16384 || self.height > 16384 {
            return bad(
                "width/height",
                "image size must be between 1 and 16384 pixels",
            );
        }
        Ok(())
    }

    /// The ray through continuous pixel coordinates (x right, y down; pixel (i, j) covers [i, i+1) × [j, j+1)).
    pub fn ray(&self, x: f64, y: f64) -> Ray {
        self.frame().ray(x, y)
    }

    /// The camera's orthonormal frame and image-plane extent, computed once for casting many rays.
    pub fn frame(&self) -> CameraFrame {
        let w = (self.target - self.eye).normalize();
        let u = w.cross(self.up).normalize();
        let v = u.cross(w);
        let half_h = (0.5 * self.fov_y_deg.to_radians()).tan();
        let half_w = half_h * self.width as f64 / self.height as f64;
        CameraFrame {
            eye: self.eye,
            w,
            u,
            v,
            half_w,
            half_h,
            width: self.width as f64,
            height: self.height as f64,
        }
    }
}

/// A [`Camera`]'s frame (view direction w, right u, up v), half extents of its image plane at distance 1 and
/// image size: [`CameraFrame::ray`] gives [`Camera::ray`]'s rays, bit for bit, without recomputing them.
#[derive(Clone, Copy, Debug)]
pub struct CameraFrame {
    eye: DVec3,
    w: DVec3,
    u: DVec3,
    v: DVec3,
    half_w: f64,
    half_h: f64,
    width: f64,
    height: f64,
}

impl CameraFrame {
    /// The ray through continuous pixel coordinates (see [`Camera::ray`]).
    #[inline]
    pub fn ray(&self, x: f64, y: f64) -> Ray {
        let sx = (2.0 * x / self.width - 1.0) * self.half_w;
        let sy = (1.0 - 2.0 * y / self.height) * self.half_h;
        Ray::new(self.eye, (self.w + sx * self.u + sy * self.v).normalize())
    }
}

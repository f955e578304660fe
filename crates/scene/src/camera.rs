//! A pinhole camera and primary-ray rendering of any [`Solution`]: each pixel shows the radiance
//! L = B/π (W/m²/sr) of the first surface its ray hits (a diffuse surface's radiance is its radiosity over π),
//! averaged over jittered sub-pixel samples. Surfaces are one-sided: a face seen from behind is black, as in the
//! path tracer. Rows are rendered in parallel; sample positions derive from
//! (seed, pixel), so the image does not depend on the thread count.

use glam::DVec3;
use rayon::prelude::*;

use crate::{Accel, Ray, Rgb, Scene, Solution, sampling};

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

/// A linear RGB image, row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Pixels, row-major.
    pub pixels: Vec<Rgb>,
}

impl Image {
    /// The pixel at column x, row y.
    pub fn get(&self, x: u32, y: u32) -> Rgb {
        self.pixels[(y * self.width + x) as usize]
    }
}

/// Renders the radiance B/π of `solution` seen through `camera`, `spp` jittered samples per pixel
/// (1 = pixel centres). Rays that escape the scene are black. `progress(pixels_done, pixels_total)` is
/// called from worker threads after each row: with a final gather every sample is a gather, so an image
/// can take minutes.
pub fn render_solution(
    scene: &Scene,
    accel: &Accel,
    camera: &Camera,
    solution: &dyn Solution,
    spp: u32,
    seed: u64,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Image {
    let (w, h) = (camera.width, camera.height);
    let spp = spp.max(1);
    let total = (w * h) as usize;
    let done = std::sync::atomic::AtomicUsize::new(0);
    let mut pixels = vec![Rgb::ZERO; total];
    pixels
        .par_chunks_mut(w as usize)
        .enumerate()
        .for_each(|(y, row)| {
            for (x, px) in row.iter_mut().enumerate() {
                let mut sum = Rgb::ZERO;
                let mut r = sampling::rng(seed, (y as u64) * w as u64 + x as u64);
                for s in 0..spp {
                    let (jx, jy) = if spp == 1 && s == 0 {
                        (0.5, 0.5)
                    } else {
                        (sampling::uniform(&mut r), sampling::uniform(&mut r))
                    };
                    let ray = camera.ray(x as f64 + jx, y as f64 + jy);
                    if let Some(hit) = accel.intersect(&ray)
                        && scene.faces[hit.face].normal.dot(ray.dir) < 0.0
                    {
                        sum += solution.radiosity_at(hit.face, hit.point) / std::f64::consts::PI;
                    }
                }
                *px = sum / spp as f64;
            }
            let n = row.len();
            progress(
                done.fetch_add(n, std::sync::atomic::Ordering::AcqRel) + n,
                total,
            );
        });
    Image {
        width: w,
        height: h,
        pixels,
    }
}

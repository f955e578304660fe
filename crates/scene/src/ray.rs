//! A ray x(t) = origin + t dir, 0 ≤ t ≤ tmax, with a unit direction: what a camera shoots and what the
//! visibility engine casts.

use glam::DVec3;

/// A ray with unit direction and a maximum distance.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    /// Origin.
    pub origin: DVec3,
    /// Unit direction.
    pub dir: DVec3,
    /// Largest distance considered (`f64::INFINITY` for none).
    pub tmax: f64,
}

impl Ray {
    /// A ray of unlimited length.
    pub fn new(origin: DVec3, dir: DVec3) -> Self {
        Self {
            origin,
            dir,
            tmax: f64::INFINITY,
        }
    }
}

//! Ray casting over the scene's faces: closest hit and point-to-point visibility, on an obvhs compressed
//! wide BVH (CwBvh, Ylitie et al. 2017) built with PLOC and reinsertion.
//!
//! Geometry is converted to f32 relative to the centre of the scene's bounds, so precision is relative to the
//! scene's size and independent of where it sits. Rays that start or end on a surface ignore the faces they
//! start and end on (by id) and keep a small gap scaled to the scene's size, so points lying exactly on
//! surfaces, touching surfaces and shared edges are handled without self-intersection. Quads are split into two
//! triangles; each triangle maps back to its face. Every ray cast is counted (relaxed atomic), so solvers can
//! report rays in their stats. `Accel` is `Sync`: cast from any number of rayon threads.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use glam::{DVec3, Vec3A};
use obvhs::{
    BvhBuildParams,
    cwbvh::{CwBvh, builder::build_cwbvh_from_tris},
    ray::{Ray as BvhRay, RayHit},
    triangle::Triangle,
};

use crate::{FaceId, Scene};

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

/// The closest surface a ray hits.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// The face hit.
    pub face: FaceId,
    /// Distance along the ray.
    pub t: f64,
    /// The hit point, snapped onto the face's plane in f64.
    pub point: DVec3,
}

/// BVH build quality. Radiosity scenes are enclosures, where rays start inside the geometry: there the
/// reinsertion pass of the slower presets pays for itself many times over (ARCHITECTURE.md's measurements:
/// about 5× faster closest-hit queries for `Quality` than `Fast` in a 100k-triangle room).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AccelPreset {
    /// obvhs `fast_build`: quickest build, slowest traversal.
    Fast,
    /// obvhs `medium_build`.
    Medium,
    /// obvhs `very_slow_build` (spatial pre-splits, full reinsertion): the default.
    #[default]
    Quality,
}

impl AccelPreset {
    fn params(self) -> BvhBuildParams {
        match self {
            AccelPreset::Fast => BvhBuildParams::fast_build(),
            AccelPreset::Medium => BvhBuildParams::medium_build(),
            AccelPreset::Quality => BvhBuildParams::very_slow_build(),
        }
    }
}

/// Relative gap (to the scene's bounding diagonal) kept between a ray's ends and the surfaces it starts and
/// ends on. f32 resolves about 6e-8 of the scene's size; this is ~150 times that.
pub const RAY_GAP_REL: f64 = 1e-5;

/// The scene's acceleration structure and ray counter.
pub struct Accel {
    bvh: CwBvh,
    tris: Vec<Triangle>,
    tri_face: Vec<u32>,
    normals: Vec<DVec3>,
    plane_d: Vec<f64>,
    offset: DVec3,
    gap: f64,
    rays: AtomicU64,
    build_time: Duration,
}

impl std::fmt::Debug for Accel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Accel")
            .field("triangles", &self.tris.len())
            .field("gap", &self.gap)
            .finish()
    }
}

impl Accel {
    /// Builds with the default preset.
    pub fn new(scene: &Scene) -> Self {
        Self::with_preset(scene, AccelPreset::default())
    }

    /// Builds with a chosen preset.
    pub fn with_preset(scene: &Scene, preset: AccelPreset) -> Self {
        let (lo, hi) = scene.bounds();
        let offset = 0.5 * (lo + hi);
        let to32 = |p: DVec3| Vec3A::from((p - offset).as_vec3());
        let mut tris = Vec::with_capacity(scene.faces.len() * 2);
        let mut tri_face = Vec::with_capacity(scene.faces.len() * 2);
        for (f, face) in scene.faces.iter().enumerate() {
            let v = |k: usize| to32(scene.vertices[face.indices[k] as usize]);
            tris.push(Triangle {
                v0: v(0),
                v1: v(1),
                v2: v(2),
            });
            tri_face.push(f as u32);
            if face.vertex_count() == 4 {
                tris.push(Triangle {
                    v0: v(0),
                    v1: v(2),
                    v2: v(3),
                });
                tri_face.push(f as u32);
            }
        }
        let mut build_time = Duration::default();
        let start = std::time::Instant::now();
        let bvh = build_cwbvh_from_tris(&tris, preset.params(), &mut build_time);
        let build_time = start.elapsed();
        let normals = scene.faces.iter().map(|f| f.normal).collect();
        let plane_d = scene
            .faces
            .iter()
            .map(|f| f.normal.dot(f.centroid))
            .collect();
        Self {
            bvh,
            tris,
            tri_face,
            normals,
            plane_d,
            offset,
            gap: RAY_GAP_REL * scene.diagonal().max(f64::MIN_POSITIVE),
            rays: AtomicU64::new(0),
            build_time,
        }
    }

    /// The gap kept at ray ends, in scene units.
    pub fn gap(&self) -> f64 {
        self.gap
    }

    /// Wall time the BVH build took.
    pub fn build_time(&self) -> Duration {
        self.build_time
    }

    /// Rays cast so far, over all threads.
    pub fn rays_cast(&self) -> u64 {
        self.rays.load(Ordering::Relaxed)
    }

    /// Number of triangles in the BVH (quads count two).
    pub fn triangle_count(&self) -> usize {
        self.tris.len()
    }

    /// Approximate heap bytes held.
    pub fn bytes(&self) -> usize {
        self.bvh.nodes.len() * 80
            + self.bvh.primitive_indices.len() * 4
            + self.tris.len() * (size_of::<Triangle>() + 4)
            + self.normals.len() * (size_of::<DVec3>() + 8)
    }

    fn bvh_ray(&self, origin: DVec3, dir: DVec3, tmin: f64, tmax: f64) -> BvhRay {
        let o = Vec3A::from((origin - self.offset).as_vec3());
        let d = Vec3A::from(dir.as_vec3());
        let tmax = if tmax.is_finite() {
            tmax as f32
        } else {
            f32::INFINITY
        };
        BvhRay::new(o, d, tmin as f32, tmax)
    }

    /// Closest hit along the ray, if any.
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.closest(ray.origin, ray.dir, 0.0, ray.tmax, usize::MAX)
    }

    /// Closest hit along a ray leaving face `from` at `origin` (a point on that face): the face itself is
    /// ignored and hits closer than the gap are ignored.
    pub fn intersect_from(&self, from: FaceId, origin: DVec3, dir: DVec3) -> Option<Hit> {
        self.closest(origin, dir, self.gap, f64::INFINITY, from)
    }

    fn closest(
        &self,
        origin: DVec3,
        dir: DVec3,
        tmin: f64,
        tmax: f64,
        skip: FaceId,
    ) -> Option<Hit> {
        self.rays.fetch_add(1, Ordering::Relaxed);
        let ray = self.bvh_ray(origin, dir, tmin, tmax);
        let mut hit = RayHit::none();
        let found = self.bvh.ray_traverse(ray, &mut hit, |r, id| {
            let tri = self.bvh.primitive_indices[id] as usize;
            if self.tri_face[tri] as usize == skip {
                return f32::INFINITY;
            }
            self.tris[tri].intersect(r)
        });
        if !found {
            return None;
        }
        let tri = self.bvh.primitive_indices[hit.primitive_id as usize] as usize;
        let face = self.tri_face[tri] as usize;
        // Refine t in f64 against the face's plane for an accurate hit point.
        let n = self.normals[face];
        let denom = n.dot(dir);
        let mut t = hit.t as f64;
        if denom.abs() > 1e-12 {
            let t64 = (self.plane_d[face] - n.dot(origin)) / denom;
            if t64.is_finite() && (t64 - t).abs() < 1e-3 * t.max(self.gap) + 4.0 * self.gap {
                t = t64;
            }
        }
        Some(Hit {
            face,
            t,
            point: origin + t * dir,
        })
    }

    /// Whether the segment between `p` and `q` is unobstructed, for points that may lie on surfaces: a gap
    /// at both ends keeps the surfaces they lie on from occluding.
    pub fn visible(&self, p: DVec3, q: DVec3) -> bool {
        self.visible_ignoring(p, q, usize::MAX, usize::MAX)
    }

    /// Whether the segment from `p` on face `fp` to `q` on face `fq` is unobstructed; the two end faces
    /// are ignored (pass `usize::MAX` for a point on no face).
    pub fn visible_between(&self, p: DVec3, fp: FaceId, q: DVec3, fq: FaceId) -> bool {
        self.visible_ignoring(p, q, fp, fq)
    }

    fn visible_ignoring(&self, p: DVec3, q: DVec3, fp: FaceId, fq: FaceId) -> bool {
        let d = q - p;
        let len = d.length();
        if !(len > 2.0 * self.gap) {
            return true;
        }
        self.rays.fetch_add(1, Ordering::Relaxed);
        let dir = d / len;
        let ray = self.bvh_ray(p, dir, self.gap, len - self.gap);
        self.bvh.ray_traverse_miss(ray, |r, id| {
            let tri = self.bvh.primitive_indices[id] as usize;
            let f = self.tri_face[tri] as usize;
            if f == fp || f == fq {
                return f32::INFINITY;
            }
            self.tris[tri].intersect(r)
        })
    }
}

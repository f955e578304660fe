//! The points a per-point method is asked about, validated and indexed by their exact coordinates, and the
//! random stream of any other point derived from its coordinates.
//!
//! A per-point Monte Carlo method (path tracing, the irradiance cache, photon maps, bidirectional path tracing)
//! traces at a fixed set of query points {(f_i, x_i)} and must answer B(f, x) there by the running estimate
//! of point i: the lookup is by face and the exact bit patterns of x's coordinates (a hash map, O(1)). At a
//! point off the set it estimates afresh, from a random stream keyed by the point, h(f, x) =
//! mix64(x ⊕ mix64(y ⊕ mix64(z ⊕ f))) (Steele, Lea & Flood 2014's SplitMix64 finaliser, `mix64`), so an answer
//! is reproducible whatever order points are asked in. Query points must lie on one of the scene's faces and
//! be finite; anything else is refused with the `points` key named.

use std::collections::HashMap;

use glam::DVec3;
use radlab_method::SolveError;
use radlab_scene::{FaceId, Scene, sampling::mix64};

use crate::point_estimator::SurfacePoint;

/// The exact key of a point: its face and the bit patterns of its coordinates.
type PointKey = (FaceId, [u64; 3]);

fn point_key(face: FaceId, p: DVec3) -> PointKey {
    (face, [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
}

/// A hash of a point's face and coordinates: the key of its random stream when it is not a query point.
pub fn coordinate_hash(face: FaceId, p: DVec3) -> u64 {
    mix64(p.x.to_bits() ^ mix64(p.y.to_bits() ^ mix64(p.z.to_bits() ^ face as u64)))
}

/// The random stream of a point off the query set: [`coordinate_hash`] with the top bit set, so it never
/// coincides with a query point's index used as a stream.
pub fn coordinate_stream(face: FaceId, p: DVec3) -> u64 {
    coordinate_hash(face, p) | 1 << 63
}

/// The query points of a per-point method, validated against the scene and indexed by exact coordinates.
#[derive(Clone, Debug, Default)]
pub struct QueryPoints {
    points: Vec<SurfacePoint>,
    index: HashMap<PointKey, usize>,
}

impl QueryPoints {
    /// Indexes `points`; an error naming the `points` key if one is not a finite point on one of `scene`'s
    /// faces.
    pub fn new(scene: &Scene, points: Vec<SurfacePoint>) -> Result<Self, SolveError> {
        if let Some((i, p)) = points
            .iter()
            .enumerate()
            .find(|(_, p)| p.face >= scene.faces.len() || !p.point.is_finite())
        {
            return Err(SolveError::param(
                "points",
                format!(
                    "point {i} (face {}, {:?}) is not a finite point on one of the scene's {} faces",
                    p.face,
                    p.point,
                    scene.faces.len()
                ),
            ));
        }
        let index = points
            .iter()
            .enumerate()
            .map(|(i, p)| (point_key(p.face, p.point), i))
            .collect();
        Ok(Self { points, index })
    }

    /// The points, in their given order.
    pub fn points(&self) -> &[SurfacePoint] {
        &self.points
    }

    /// How many points there are.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The index of the query point at exactly (`face`, `point`), if it is one.
    pub fn find(&self, face: FaceId, point: DVec3) -> Option<usize> {
        self.index.get(&point_key(face, point)).copied()
    }

    /// Bytes held: the points and their index.
    pub fn bytes(&self) -> usize {
        self.points.capacity() * size_of::<SurfacePoint>()
            + self.index.capacity() * (size_of::<PointKey>() + size_of::<usize>())
    }
}

impl std::ops::Index<usize> for QueryPoints {
    type Output = SurfacePoint;

    fn index(&self, i: usize) -> &SurfacePoint {
        &self.points[i]
    }
}

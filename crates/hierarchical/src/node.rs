//! Nodes of the simulation hierarchy. A node kind says what the solver needs and nothing more: its area,
//! a bounding sphere, its orientation (a normal for a planar element, none for a volume cluster), its
//! area-mean reflectance and emission, its projected area toward a direction, and how it splits. The solver
//! (refinement, gather, push-pull, schedules) works on any [`NodeKind`]; this crate provides [`Patch`], a
//! quadtree element of an input face (Hanrahan, Salzman & Aupperle 1991: quads split into four at their edge
//! midpoints and centre, triangles into four at their edge midpoints). Volume clusters (Smits et al. 1994;
//! Sillion 1995) are another kind: an enum over clusters and patches implementing [`NodeKind`].
//!
//! A patch also carries its corners in the integer parameter space of its input face (a 2^30 lattice), so
//! elements of one face can be located by a point and share vertices exactly for Gouraud output.

use glam::DVec3;
use radlab_scene::{FaceId, Polygon, Rgb, Scene, sampling};

/// A bounding sphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bound {
    /// Centre.
    pub centre: DVec3,
    /// Radius.
    pub radius: f64,
}

/// What the hierarchical solver needs to know about a node, whatever kind it is.
pub trait NodeKind: Send + Sync + Sized {
    /// Surface area it represents (for a cluster, the sum over its surfaces).
    fn area(&self) -> f64;
    /// A sphere containing it.
    fn bound(&self) -> Bound;
    /// Unit normal of a planar node; `None` for a node without one orientation (a volume cluster).
    fn normal(&self) -> Option<DVec3>;
    /// Area seen from unit direction `dir` (a patch: A |n·d|; an isotropic cluster: A/4).
    fn projected_area(&self, dir: DVec3) -> f64;
    /// Area-mean diffuse reflectance.
    fn reflectance(&self) -> Rgb;
    /// Area-mean emitted exitance (W/m²).
    fn emission(&self) -> Rgb;
    /// Whether it may be split, given the minimum element edge (scene units).
    fn can_split(&self, min_size: f64) -> bool;
    /// Its children. Called at most once per node, the first time the solver subdivides it, and only when
    /// [`NodeKind::can_split`] said yes; their areas sum to this node's.
    fn split(&self) -> Vec<Self>;
    /// The input face it lies on, for a node within one face.
    fn face(&self) -> Option<FaceId>;
    /// An identity that depends only on what the node is, not on when it was created (random streams are
    /// derived from it, so any schedule and thread count draws the same rays for the same pair of nodes).
    fn key(&self) -> u64;
    /// The quadtree element this node is, if it is one (the output layer locates points and interpolates
    /// vertices through it).
    fn patch(&self) -> Option<&Patch> {
        None
    }

    /// Whether, as a link's source, the node already sends what its emitting contents would send one by one
    /// (a face cluster's power vector includes its faces' emission, Σ E_i A_i n_i). When false — by default,
    /// for every node that is not within one input face — the refinement splits an emitting source before
    /// anything else, so emitters are reached as surfaces.
    fn sends_own_emission(&self) -> bool {
        self.face().is_some()
    }
}

/// Side of the integer parameter lattice every input face is addressed in.
pub const LATTICE: u32 = 1 << 30;

/// Deepest quadtree level (the lattice's resolution).
pub const MAX_LEVEL: u8 = 30;

/// Relative slack of the minimum-size test: an element splits if its children's longest edge reaches the
/// minimum size up to this fraction. Edges are computed from rounded vertex coordinates, so an edge of
/// exactly twice the minimum size at one scale (h and h/16, say: powers of two are exact) lies a rounding error
/// above or below it at another; without the slack the same scene split differently at 1e-4 of its size.
pub const SIZE_TOL_REL: f64 = 1e-9;

/// A quadtree element: an input face or a piece of one.
#[derive(Clone, Copy, Debug)]
pub struct Patch {
    /// The input face.
    pub face: FaceId,
    /// Its geometry.
    pub polygon: Polygon,
    /// Quadtree level (0 for the input face).
    pub level: u8,
    /// Corners in the face's parameter lattice (quads: (s, t) of the bilinear map; triangles: (u, v) with
    /// p = a + u (b − a) + v (c − a)), in units of 1/[`LATTICE`]. The fourth is unused for a triangle.
    pub uv: [[u32; 2]; 4],
    /// Unit normal.
    pub normal: DVec3,
    /// Area.
    pub area: f64,
    /// Area centroid.
    pub centroid: DVec3,
    /// Longest edge.
    pub max_edge: f64,
    /// Reflectance of its face.
    pub reflectance: Rgb,
    /// Emission of its face.
    pub emission: Rgb,
}

impl Patch {
    /// The root element of input face `f`.
    pub fn root(scene: &Scene, f: FaceId) -> Self {
        let polygon = scene.polygon(f);
        let n = LATTICE;
        let uv = if polygon.is_triangle() {
            [[0, 0], [n, 0], [0, n], [0, n]]
        } else {
            [[0, 0], [n, 0], [n, n], [0, n]]
        };
        Self::new(
            f,
            polygon,
            0,
            uv,
            scene.reflectance(f),
            scene.emission(f),
            scene.faces[f].normal,
        )
    }

    fn new(
        face: FaceId,
        polygon: Polygon,
        level: u8,
        uv: [[u32; 2]; 4],
        reflectance: Rgb,
        emission: Rgb,
        normal: DVec3,
    ) -> Self {
        Self {
            face,
            level,
            uv,
            normal,
            area: polygon.area(),
            centroid: polygon.centroid(),
            max_edge: polygon.max_edge(),
            reflectance,
            emission,
            polygon,
        }
    }

    /// Number of corners (3 or 4).
    pub fn corners(&self) -> usize {
        self.polygon.len()
    }
}

fn mid(a: [u32; 2], b: [u32; 2]) -> [u32; 2] {
    [(a[0] + b[0]) / 2, (a[1] + b[1]) / 2]
}

impl NodeKind for Patch {
    fn area(&self) -> f64 {
        self.area
    }

    fn bound(&self) -> Bound {
        let radius = self
            .polygon
            .vertices()
            .iter()
            .map(|v| (*v - self.centroid).length())
            .fold(0.0, f64::max);
        Bound {
            centre: self.centroid,
            radius,
        }
    }

    fn normal(&self) -> Option<DVec3> {
        Some(self.normal)
    }

    fn projected_area(&self, dir: DVec3) -> f64 {
        self.area * self.normal.dot(dir).abs()
    }

    fn reflectance(&self) -> Rgb {
        self.reflectance
    }

    fn emission(&self) -> Rgb {
        self.emission
    }

    fn can_split(&self, min_size: f64) -> bool {
        self.level < MAX_LEVEL && self.max_edge >= 2.0 * min_size * (1.0 - SIZE_TOL_REL)
    }

    fn split(&self) -> Vec<Self> {
        let kids = self.polygon.split4();
        let u = &self.uv;
        // Parameter corners in the same order as Polygon::split4's children.
        let uvs: [[[u32; 2]; 4]; 4] = if self.polygon.is_triangle() {
            let (ab, bc, ca) = (mid(u[0], u[1]), mid(u[1], u[2]), mid(u[2], u[0]));
            [
                [u[0], ab, ca, ca],
                [ab, u[1], bc, bc],
                [ca, bc, u[2], u[2]],
                [ab, bc, ca, ca],
            ]
        } else {
            let (m01, m12, m23, m30) = (
                mid(u[0], u[1]),
                mid(u[1], u[2]),
                mid(u[2], u[3]),
                mid(u[3], u[0]),
            );
            let c = mid(u[0], u[2]);
            [
                [u[0], m01, c, m30],
                [m01, u[1], m12, c],
                [c, m12, u[2], m23],
                [m30, c, m23, u[3]],
            ]
        };
        kids.iter()
            .zip(uvs)
            .map(|(p, uv)| {
                Self::new(
                    self.face,
                    *p,
                    self.level + 1,
                    uv,
                    self.reflectance,
                    self.emission,
                    self.normal,
                )
            })
            .collect()
    }

    fn face(&self) -> Option<FaceId> {
        Some(self.face)
    }

    fn patch(&self) -> Option<&Patch> {
        Some(self)
    }

    fn key(&self) -> u64 {
        let mut h = sampling::mix64(self.face as u64);
        for c in &self.uv[..self.corners()] {
            h = sampling::mix64(h ^ ((c[0] as u64) << 32 | c[1] as u64));
        }
        h
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splits_conserve_area_and_nest_in_the_lattice() {
        let s = radlab_scene::builtin("furnace-cube?tessellation=1").expect("scene");
        let mut b = radlab_scene::SceneBuilder::new("tri");
        let m = b
            .add_material(
                radlab_scene::Material::new("m", Rgb::splat(0.5), Rgb::ZERO).expect("material"),
            )
            .expect("material");
        b.add_polygon_points(
            &[
                DVec3::ZERO,
                DVec3::new(2.0, 0.0, 0.0),
                DVec3::new(0.5, 1.5, 0.0),
            ],
            m,
            "t",
        )
        .expect("triangle");
        let t = b.build().expect("scene");
        for (scene, f) in [(&s, 0), (&t, 0)] {
            let root = Patch::root(scene, f);
            let kids = root.split();
            assert_eq!(kids.len(), 4);
            let area: f64 = kids.iter().map(|k| k.area).sum();
            assert!((area - root.area).abs() < 1e-12 * root.area);
            for k in &kids {
                // Each child's lattice corners map onto its polygon's vertices.
                for (c, v) in k.uv.iter().zip(k.polygon.vertices()) {
                    let (x, y) = (c[0] as f64 / LATTICE as f64, c[1] as f64 / LATTICE as f64);
                    let p = if root.polygon.is_triangle() {
                        let r = root.polygon.vertices();
                        r[0] + (r[1] - r[0]) * x + (r[2] - r[0]) * y
                    } else {
                        root.polygon.point_at(x, y)
                    };
                    assert!((p - *v).length() < 1e-12, "{p} vs {v}");
                }
                assert_eq!(k.level, 1);
            }
        }
    }
}

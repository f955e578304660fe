//! Gouraud interpolation of irradiance fields that depend on the receiving normal, for solutions that keep
//! an irradiance vector per face (face clusters: Willmott, Heckbert & Garland 1999) rather than one value.
//!
//! Each face g holds a field linear in the receiving normal n, I_g(n) = n·e_g + c_g per channel. At a corner
//! v of face f, every face g around v offers its own irradiance carried to f's normal n by the trapezoid rule
//! between the two faces' fields,
//!
//!   I_g→f = I_g(n_g) + (n − n_g)·(e_g + e_f)/2,
//!
//! and the corner takes their mean weighted by A_g max(0, n·n_g) (a face across a crease counts less, one at
//! a right angle or beyond not at all). The corner values are interpolated over f (bilinear in a quad's
//! parameters, linear in a triangle's barycentric coordinates: [`crate::gouraud::interpolate_corners`], as
//! Gouraud 1971 shades). So a face keeps its own orientation, where interpolating vertex radiosities taken
//! with vertex normals would blur a rough surface's tilts into each other. Two cases are exact: where the
//! irradiance is one linear field of the normal everywhere (a distant light in front of every face) the
//! corner value is that field at n; where it does not depend on the normal at all (the inside of a furnace,
//! whose faces' fields point along their own normals, e_g = a n_g) the two fields' slopes cancel, where
//! carrying g's field alone to n would lose a(1 − n·n_g).
//!
//! The result is the interpolated irradiance, not clamped: the caller reflects it, B = E + ρ max(0, I).

use glam::DVec3;

use crate::gouraud::interpolate_corners;
use radlab_scene::{FaceId, Rgb, Scene, VertexAdjacency};

/// A face's irradiance as a function of the receiving normal, linear in it: I(n) = n·e + c per channel.
pub trait LinearIrradiance {
    /// The unclamped irradiance I(n) of channel `k` for a receiver of unit normal `n`.
    fn linear(&self, n: DVec3, k: usize) -> f64;
    /// The irradiance vector e of channel `k` (the gradient of I with respect to n).
    fn vector(&self, k: usize) -> DVec3;
}

/// The irradiance at `point` of `face`, interpolated from its corners (see the module documentation);
/// `fields[g]` is face g's field, `around` the scene's faces around each vertex.
pub fn irradiance_at<F: LinearIrradiance>(
    scene: &Scene,
    around: &VertexAdjacency,
    fields: &[F],
    face: FaceId,
    point: DVec3,
) -> Rgb {
    let n = scene.faces[face].normal;
    let own = &fields[face];
    let mut corners = [Rgb::ZERO; 4];
    for (corner, &v) in corners.iter_mut().zip(scene.faces[face].vertex_indices()) {
        let mut total = 0.0;
        for g in around.faces_around(v) {
            let other = &scene.faces[g];
            let w = other.area * n.dot(other.normal).max(0.0);
            if w > 0.0 {
                let (eg, m) = (&fields[g], n - other.normal);
                let carried = |c: usize| {
                    eg.linear(other.normal, c) + 0.5 * m.dot(eg.vector(c) + own.vector(c))
                };
                let carried = Rgb::new(carried(0), carried(1), carried(2));
                *corner += w * carried;
                total += w;
            }
        }
        if total > 0.0 {
            *corner /= total;
        }
    }
    interpolate_corners(&scene.polygon(face), &corners, point)
}

#[cfg(test)]
mod tests {
    use super::*;
    use radlab_scene::builtin::builtin;

    /// I(n) = n·e + c with the same e and c on every channel.
    struct Field {
        e: DVec3,
        c: f64,
    }

    impl LinearIrradiance for Field {
        fn linear(&self, n: DVec3, _k: usize) -> f64 {
            n.dot(self.e) + self.c
        }
        fn vector(&self, _k: usize) -> DVec3 {
            self.e
        }
    }

    fn sample_points(scene: &Scene) -> impl Iterator<Item = (FaceId, DVec3)> + '_ {
        (0..scene.face_count()).step_by(7).map(|f| {
            let v = scene.polygon(f).vertices().to_vec();
            // A point inside the face, off its centroid: a weighted mean of its corners.
            let w = [0.5, 0.3, 0.2, 0.0];
            let p = v.iter().zip(w).map(|(x, w)| *x * w).sum::<DVec3>();
            (f, p)
        })
    }

    #[test]
    fn one_field_of_the_normal_is_reproduced_at_every_point() {
        let scene = builtin("furnace-sphere?tessellation=8").expect("sphere");
        let around = VertexAdjacency::new(&scene);
        let (e, c) = (DVec3::new(0.3, -0.7, 0.2), 2.0);
        let fields: Vec<Field> = (0..scene.face_count()).map(|_| Field { e, c }).collect();
        let mut checked = 0;
        for (f, p) in sample_points(&scene) {
            let want = scene.faces[f].normal.dot(e) + c;
            let got = irradiance_at(&scene, &around, &fields, f, p);
            for k in 0..3 {
                assert!(
                    (got[k] - want).abs() < 1e-12,
                    "face {f}: {} vs {want}",
                    got[k]
                );
            }
            checked += 1;
        }
        assert!(checked > 10);
    }

    #[test]
    fn fields_along_their_own_normals_interpolate_to_their_common_value() {
        // The inside of a furnace: every face receives a + c whatever its tilt, from a field e = a n_g.
        let scene = builtin("furnace-sphere?tessellation=8").expect("sphere");
        let around = VertexAdjacency::new(&scene);
        // Corners are shared, so each corner value mixes several faces' tilted fields.
        assert!(
            around
                .faces_around(scene.faces[0].vertex_indices()[0])
                .count()
                >= 3
        );
        let (a, c) = (1.5, 0.25);
        let fields: Vec<Field> = (0..scene.face_count())
            .map(|g| Field {
                e: a * scene.faces[g].normal,
                c,
            })
            .collect();
        for (f, p) in sample_points(&scene) {
            let got = irradiance_at(&scene, &around, &fields, f, p);
            assert!((got[0] - (a + c)).abs() < 1e-12, "face {f}: {}", got[0]);
        }
    }
}

//! The open fraction of an element: the share of its area that can receive light at all.
//!
//! A constant element holds one radiosity, its area mean B̄, and sends it from all of its area. Where part
//! of an element lies under a panel that touches or nearly touches it (a floor covering, a lamp mounted under
//! a ceiling) and sees only that panel's back, that part receives nothing, so B̄ = o B_open with o the open
//! share and B_open the radiosity of the rest. Sending B̄ from the whole element sends from the sealed part
//! light that the panel's back absorbs, and the open part sends only o of what it should: every element that
//! straddles such a contact loses (1 − o) of the light it reflects. These are the light and shadow leaks of
//! Baum, Mann, Smith & Winget 1991 ("Making radiosity usable: automatic preprocessing and meshing techniques
//! for the generation of accurate radiosity solutions"), who split the surfaces along the contact instead.
//! Here the solvers keep their meshes and solve for B_open on the effective area o A:
//!
//! o A_i B_i = o A_i E_i + ρ_i Σ_j A_i F_ij B_j,
//!
//! with F_ij sampled from all of element i (its sealed points see nothing, so A_i F_ij already carries the
//! factor o). Energy is then conserved across a contact, and where nothing is sealed o = 1 and nothing
//! changes.
//!
//! The estimate: `side` × `side` stratified points on the element, each casting `rays` cosine-distributed
//! rays ignoring its own face. A point is sealed when every ray hits the back of a face (one-sided faces
//! absorb at their backs, so such a point receives nothing); a ray that escapes the scene or reaches a
//! front face leaves the point open. o is the open share of the points ([`open_share`]); as an open fraction
//! ([`open_fraction`], what matrix and progressive radiosity solve with) an element with no open point is
//! left at o = 1 (it receives next to nothing, so there is nothing to correct). The random stream is a
//! function of (seed, key) only.

use radlab_scene::polygon::Polygon;
use radlab_scene::sampling::{self, mix64};
use radlab_scene::{FaceId, Scene};
use radlab_visibility::Accel;
use rayon::prelude::*;

/// Points per side of the stratified grid (default 4: 16 points).
pub const DEFAULT_OPEN_SIDE: u32 = 4;
/// Probe rays per point (default 8).
pub const DEFAULT_OPEN_RAYS: u32 = 8;

/// The open fraction o ∈ (0, 1] of an element from its measured open share ([`open_share`]): an element
/// with no open point is left at 1 (see the module documentation).
pub fn open_fraction(share: f64) -> f64 {
    if share == 0.0 { 1.0 } else { share }
}

/// The open share of `polygon` on `face` as measured, o ∈ [0, 1] (0: no probe point open), and the rays it
/// cast. Solvers that hold an element's radiosity over its open part on effective areas o A (matrix,
/// progressive) use [`open_fraction`] of it; hierarchical radiosity, which credits what a leaf receives to
/// its open part link by link, lets a wholly sealed leaf take no part (o = 0).
pub fn open_share(
    scene: &Scene,
    accel: &Accel,
    polygon: &Polygon,
    face: FaceId,
    seed: u64,
    key: u64,
) -> (f64, u64) {
    let (side, rays) = (DEFAULT_OPEN_SIDE, DEFAULT_OPEN_RAYS);
    let n = polygon.normal();
    let mut r = sampling::rng(seed, mix64(key ^ 0x6f70_656e_6672_6163));
    let (mut open, mut cast) = (0u32, 0u64);
    for k in 0..side * side {
        let u = ((k % side) as f64 + sampling::uniform(&mut r)) / side as f64;
        let w = ((k / side) as f64 + sampling::uniform(&mut r)) / side as f64;
        let y = polygon.point_at(u, w);
        let mut sealed = true;
        for _ in 0..rays {
            let (u1, u2) = (sampling::uniform(&mut r), sampling::uniform(&mut r));
            if !sealed {
                continue; // keep the stream's length fixed: the next point's samples do not depend on this one
            }
            let d = sampling::cosine_hemisphere(n, u1, u2);
            cast += 1;
            match accel.intersect_from(face, y, d) {
                None => sealed = false,
                // A hit at t = 0 is a surface the point lies on, entered through its back-facing side
                // (`Accel`'s contact rule): the bottom of a box resting on the floor, seen from the floor
                // under it. The two touch, so no light passes between them whichever way that surface
                // faces: the ray stays sealed.
                Some(hit) if hit.t <= 0.0 => {}
                Some(hit) => {
                    if scene.faces[hit.face].normal.dot(d) < 0.0 {
                        sealed = false;
                    }
                }
            }
        }
        if !sealed {
            open += 1;
        }
    }
    (open as f64 / (side * side) as f64, cast)
}

/// The open fractions of `elements` (each given as its polygon and face by `part`), on rayon threads, element k
/// keyed `first_key + k`, and the rays cast: the same values on any number of threads.
pub fn open_fractions<T: Sync>(
    scene: &Scene,
    accel: &Accel,
    elements: &[T],
    part: impl Fn(&T) -> (&Polygon, FaceId) + Sync,
    seed: u64,
    first_key: u64,
) -> (Vec<f64>, u64) {
    let found: Vec<(f64, u64)> = elements
        .par_iter()
        .enumerate()
        .map(|(k, e)| {
            let (polygon, face) = part(e);
            let (o, rays) = open_share(scene, accel, polygon, face, seed, first_key + k as u64);
            (open_fraction(o), rays)
        })
        .collect();
    let rays = found.iter().map(|f| f.1).sum();
    (found.into_iter().map(|f| f.0).collect(), rays)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use radlab_scene::{Material, SceneBuilder};

    /// A 2 × 2 floor facing up with a one-sided panel `gap` above it covering x < `cover`, facing up too.
    fn covered_floor(cover: f64, gap: f64) -> Scene {
        let mut b = SceneBuilder::new("covered");
        let m = b
            .add_material(Material::new("grey", DVec3::splat(0.5), DVec3::ZERO).expect("material"))
            .expect("add");
        let q = |x0: f64, x1: f64, y: f64| {
            vec![
                DVec3::new(x0, y, 0.0),
                DVec3::new(x0, y, 2.0),
                DVec3::new(x1, y, 2.0),
                DVec3::new(x1, y, 0.0),
            ]
        };
        b.add_polygon_points(&q(0.0, 2.0, 0.0), m, "floor")
            .expect("floor");
        b.add_polygon_points(&q(-1.0, cover, gap), m, "panel")
            .expect("panel");
        b.build().expect("scene")
    }

    #[test]
    fn the_covered_share_of_a_floor_is_sealed() {
        // The panel covers x < 0.5 of the floor [0, 2] a millimetre above it: the floor as one element is a
        // quarter sealed; 16 points on a 4 × 4 grid resolve x < 0.5 exactly (one column of points).
        let scene = covered_floor(0.5, 1e-3);
        let accel = Accel::new(&scene);
        let poly = scene.polygon(0);
        let (o, rays) = open_share(&scene, &accel, &poly, 0, 7, 0);
        assert_eq!(o, 0.75);
        assert!(rays >= 16 && rays <= 16 * DEFAULT_OPEN_RAYS as u64);
        // The panel itself is open, and so is a floor nothing covers.
        let (o, _) = open_share(&scene, &accel, &scene.polygon(1), 1, 7, 1);
        assert_eq!(o, 1.0);
        let bare = covered_floor(-0.5, 1e-3);
        let accel = Accel::new(&bare);
        assert_eq!(open_share(&bare, &accel, &bare.polygon(0), 0, 7, 0).0, 1.0);
    }

    /// A 2 × 2 floor facing up with a unit box (outward faces, bottom included) resting on it, with no gap,
    /// over x, z < 1: a quarter of the floor and all of the box's bottom touch.
    fn box_on_floor() -> Scene {
        let mut b = SceneBuilder::new("box on floor");
        let m = b
            .add_material(Material::new("grey", DVec3::splat(0.5), DVec3::ZERO).expect("material"))
            .expect("add");
        let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
        let mut quad = |o: DVec3, u: DVec3, v: DVec3| {
            b.add_polygon_points(&[o, o + u, o + u + v, o + v], m, "quad")
                .expect("quad");
        };
        quad(DVec3::ZERO, 2.0 * z, 2.0 * x); // floor, +y
        quad(DVec3::ZERO, x, z); // box bottom, -y (face 1)
        quad(y, z, x); // top, +y
        quad(DVec3::ZERO, y, x); // z = 0, -z
        quad(z, x, y); // z = 1, +z
        quad(DVec3::ZERO, z, y); // x = 0, -x
        quad(x, y, z); // x = 1, +x
        b.build().expect("scene")
    }

    #[test]
    fn a_box_resting_on_a_floor_seals_the_floor_under_it_and_its_own_bottom() {
        // Rays leaving the floor under the box meet the box's bottom at t = 0 (the accelerator's contact
        // rule), from its front: the two surfaces touch, so no light reaches either. The floor is a quarter
        // sealed (4 of its 16 stratified points lie under the box), the bottom wholly; the box's sides, which
        // see the floor beside them, are open.
        let scene = box_on_floor();
        let accel = Accel::new(&scene);
        let share = |f: usize| open_share(&scene, &accel, &scene.polygon(f), f, 7, f as u64).0;
        assert_eq!(share(0), 0.75);
        assert_eq!(share(1), 0.0);
        for f in 2..7 {
            assert_eq!(share(f), 1.0, "face {f}");
        }
    }

    #[test]
    fn a_fully_covered_element_is_left_alone_and_elements_resolve_the_edge() {
        let scene = covered_floor(1.0, 1e-3);
        let accel = Accel::new(&scene);
        for (i, element) in scene.polygon(0).subdivide(0.5).iter().enumerate() {
            let (o, _) = open_share(&scene, &accel, element, 0, 3, i as u64);
            // Elements [0, 0.5] and [0.5, 1] lie wholly under the panel (share 0; fraction 1: nothing to
            // correct), the rest wholly outside it.
            let under = element.centroid().x < 1.0;
            assert_eq!(
                o,
                if under { 0.0 } else { 1.0 },
                "element at {:?}",
                element.centroid()
            );
            assert_eq!(open_fraction(o), 1.0);
        }
    }
}

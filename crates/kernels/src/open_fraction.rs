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
//! rays ignoring its own face. A point is sealed when every ray is closed ([`hit_closes`]): it hits the back of
//! a face (one-sided faces absorb at their backs, so such a point receives nothing), or the front of a face
//! that faces the point's own and whose plane passes within [`SEAL_GAP_REL`] of the scene's diagonal of the
//! point (a cube's bottom face lying on the floor); a ray that escapes the scene or reaches any other front
//! leaves the point open. A point answer's test ([`point_sealed`]) applies the same rule with more rays. o is
//! the open share of the points ([`open_share`]); as
//! an open fraction ([`open_fraction`], what matrix and progressive radiosity solve with) an element with no
//! open point is left at o = 1 (it receives next to nothing, so there is nothing to correct). The random
//! stream is a function of (seed, key) only.

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
    let gap = SEAL_GAP_REL * scene.diagonal();
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
            if ray_opens(scene, accel, face, y, d, gap) {
                sealed = false;
            }
        }
        if !sealed {
            open += 1;
        }
    }
    (open as f64 / (side * side) as f64, cast)
}

/// Whether the probe ray from `y` on `face` along `d` leaves the point open: it escapes the scene, or meets a
/// face that [`hit_closes`] does not close. A face's back absorbs (one-sided faces); a front facing the point's
/// face whose plane passes within `gap` of the point closes the ray (the point lies in a gap under that face: a
/// cube's bottom face on the floor). The plane's distance, t |n·d|, is the gap's height whichever way the ray
/// runs, where the distance t to the hit grows as 1/cos θ and a grazing ray would pass a rule on t. Both seal
/// tests take `gap` = [`SEAL_GAP_REL`] of the scene's diagonal. (Element shares used the back rule alone until
/// 2026-12-06: a t = 0 rule tried before had let light into closed boxes flush against walls, through the
/// final gather's rays behind a query's plane, which its visible share no longer counts.)
fn ray_opens(
    scene: &Scene,
    accel: &Accel,
    face: FaceId,
    y: glam::DVec3,
    d: glam::DVec3,
    gap: f64,
) -> bool {
    match accel.intersect_from(face, y, d) {
        None => true,
        Some(hit) => !hit_closes(scene, face, d, hit.face, hit.t, gap),
    }
}

/// Whether a ray leaving `face` along unit `d` and meeting `hit_face` at distance `t` is closed: it meets
/// that face's back, or its front where the face faces `face` (−n_hit·n > [`GAP_FACING`]) and its plane passes
/// within `gap` of the ray's origin (t |n_hit·d| ≤ `gap`). The rule of the seal tests ([`point_sealed`],
/// [`open_share`] with `gap` = [`SEAL_GAP_REL`] of the scene's diagonal); a particle transport that solves on
/// open shares ends a flight it closes, as light that leaves a sealed point never reaches the open scene.
pub fn hit_closes(
    scene: &Scene,
    face: FaceId,
    d: glam::DVec3,
    hit_face: FaceId,
    t: f64,
    gap: f64,
) -> bool {
    let n_hit = scene.faces[hit_face].normal;
    let facing = -n_hit.dot(d);
    let over = -n_hit.dot(scene.faces[face].normal) > GAP_FACING;
    facing <= 0.0 || (over && t * facing <= gap)
}

/// A front face closes a ray at the gap rule only if it faces the point's face, −n_hit·n > this (within 60°
/// of face to face): a gap lies between faces that face each other (a cube's bottom on the floor), while the
/// side of a cube standing on the floor, or the adjacent wall at a room's edge, only borders a point near it,
/// which the rest of its hemisphere lights. Without it, probe points within the gap of a room's edges and
/// corners were called sealed whenever all 8 rays met the faces beside them.
pub const GAP_FACING: f64 = 0.5;

/// Probe rays of a point answer's seal test ([`point_sealed`], default 128): more than an element's probe
/// points cast ([`DEFAULT_OPEN_RAYS`]), since a point wrongly called sealed answers 0, where a gather would
/// answer it. A point with 3% of its cosine-weighted hemisphere open passes for sealed with probability
/// 0.97¹²⁸ ≈ 2%. On a floor 4 gap heights inside a covering's straight edge 1.5% is open (by the slit's
/// geometry), sealed with probability 14% (61% at 32 rays, the former default). An open point usually pays
/// one ray; a sealed one all of them.
pub const POINT_SEAL_RAYS: u32 = 128;

/// A front face whose plane passes closer than this share of the scene's diagonal to a point (1e-3: 0.9 mm
/// in the Cornell box, 7.7 mm in a 5 × 3 × 5 m room), and facing the point's face ([`GAP_FACING`]), closes the
/// point's ray as a back does ([`hit_closes`]): the point lies in a gap between two faces facing each other (a
/// cube's bottom face lying on or just above the floor), and light reaches it only sideways through the gap's
/// mouth. Every ray that meets the face over the gap closes, so a point deep in a gap is sealed; a point
/// within a few gap heights of the mouth stays open with the chance that one of its rays leaves the gap
/// sideways.
pub const SEAL_GAP_REL: f64 = 1e-3;

/// Whether the point `y` on `face` is sealed: every one of `rays` cosine-distributed rays (a point answer:
/// [`POINT_SEAL_RAYS`]; a probe point of an element: [`DEFAULT_OPEN_RAYS`]) meets the back of a face or the
/// front of one facing it whose plane passes within [`SEAL_GAP_REL`] of the scene's diagonal (ignoring its own
/// face; [`open_share`] applies the same rule at each of its probe points); and the rays cast (one for an open point whose
/// first ray escapes or meets a front face farther away: the probe stops at the first open ray). A sealed point receives nothing (one-sided faces absorb at their
/// backs), so its exact radiosity is its emission; point answers read this test to answer so. The random
/// stream is a function of (seed, key) only.
pub fn point_sealed(
    scene: &Scene,
    accel: &Accel,
    face: FaceId,
    y: glam::DVec3,
    rays: u32,
    seed: u64,
    key: u64,
) -> (bool, u64) {
    let n = scene.faces[face].normal;
    let gap = SEAL_GAP_REL * scene.diagonal();
    let mut r = sampling::rng(seed, mix64(key ^ 0x7365_616c_6564_7074));
    for k in 0..rays {
        let (u1, u2) = (sampling::uniform(&mut r), sampling::uniform(&mut r));
        let d = sampling::cosine_hemisphere(n, u1, u2);
        if ray_opens(scene, accel, face, y, d, gap) {
            return (false, u64::from(k) + 1);
        }
    }
    (true, u64::from(rays))
}

/// The key of a point's random streams (its seal test, [`point_sealed`]; a final gather's rays): a hash of its
/// face and of its coordinates along two of the face's edges in units of those edges, quantised to 2^-30, so the
/// streams (and the answers) do not change when the scene is scaled.
pub fn point_key(scene: &Scene, face: FaceId, y: glam::DVec3) -> u64 {
    let poly = scene.polygon(face);
    let v = poly.vertices();
    let d = y - v[0];
    let q = |e: glam::DVec3| {
        let l2 = e.length_squared();
        let t = if l2 > 0.0 { d.dot(e) / l2 } else { 0.0 };
        (t * (1u64 << 30) as f64).round() as i64 as u64
    };
    let (a, b) = (q(v[1] - v[0]), q(v[v.len() - 1] - v[0]));
    mix64(a ^ mix64(b ^ mix64(face as u64)))
}

/// The measured open shares of `elements` (each given as its polygon and face by `part`; 0: no probe point
/// open), on rayon threads, element k keyed `first_key + k`, and the rays cast: the same values on any number
/// of threads.
pub fn open_shares<T: Sync>(
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
            open_share(scene, accel, polygon, face, seed, first_key + k as u64)
        })
        .collect();
    let rays = found.iter().map(|f| f.1).sum();
    (found.into_iter().map(|f| f.0).collect(), rays)
}

/// The open fractions of `elements` ([`open_shares`] through [`open_fraction`]) and the rays cast.
pub fn open_fractions<T: Sync>(
    scene: &Scene,
    accel: &Accel,
    elements: &[T],
    part: impl Fn(&T) -> (&Polygon, FaceId) + Sync,
    seed: u64,
    first_key: u64,
) -> (Vec<f64>, u64) {
    let (shares, rays) = open_shares(scene, accel, elements, part, seed, first_key);
    (shares.into_iter().map(open_fraction).collect(), rays)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use radlab_scene::{Material, SceneBuilder};

    /// A 2 × 2 floor facing up with a one-sided panel `gap` above it covering x < `cover`, facing up (or
    /// down, toward the floor, as a cube's bottom face lying on a floor).
    fn covered_floor(cover: f64, gap: f64, facing_down: bool) -> Scene {
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
        let mut panel = q(-1.0, cover, gap);
        if facing_down {
            panel.reverse();
        }
        b.add_polygon_points(&panel, m, "panel").expect("panel");
        b.build().expect("scene")
    }

    #[test]
    fn point_keys_follow_the_point_on_its_face_not_the_scene_scale() {
        // The same floor at two scales and offsets: a point at the same place on it keys the same stream
        // (so seal tests and gathers answer the same), and other points other streams.
        let floor = |s: f64, o: f64| {
            let mut b = SceneBuilder::new("floor");
            let m = b
                .add_material(
                    Material::new("grey", DVec3::splat(0.5), DVec3::ZERO).expect("material"),
                )
                .expect("add");
            let p = |x: f64, z: f64| DVec3::new(o + s * x, o, o + s * z);
            b.add_polygon_points(
                &[p(0.0, 0.0), p(0.0, 2.0), p(2.0, 2.0), p(2.0, 0.0)],
                m,
                "floor",
            )
            .expect("floor");
            b.build().expect("scene")
        };
        let (a, b) = (floor(1.0, 0.0), floor(1e4, -3.0));
        let at = |s: f64, o: f64, x: f64, z: f64| DVec3::new(o + s * x, o, o + s * z);
        for (x, z) in [(0.3, 1.7), (1.0, 1.0), (1.999, 0.001)] {
            assert_eq!(
                point_key(&a, 0, at(1.0, 0.0, x, z)),
                point_key(&b, 0, at(1e4, -3.0, x, z)),
                "({x}, {z})"
            );
        }
        assert_ne!(
            point_key(&a, 0, at(1.0, 0.0, 0.3, 1.7)),
            point_key(&a, 0, at(1.0, 0.0, 1.7, 0.3))
        );
        assert_ne!(
            point_key(&a, 0, at(1.0, 0.0, 0.3, 1.7)),
            point_key(&a, 0, at(1.0, 0.0, 0.3, 1.7 + 1e-6))
        );
    }

    #[test]
    fn the_covered_share_of_a_floor_is_sealed() {
        // The panel covers x < 0.5 of the floor [0, 2] a millimetre above it: the floor as one element is a
        // quarter sealed; 16 points on a 4 × 4 grid resolve x < 0.5 exactly (one column of points).
        let scene = covered_floor(0.5, 1e-3, false);
        let accel = Accel::new(&scene);
        let poly = scene.polygon(0);
        let (o, rays) = open_share(&scene, &accel, &poly, 0, 7, 0);
        assert_eq!(o, 0.75);
        assert!(rays >= 16 && rays <= 16 * DEFAULT_OPEN_RAYS as u64);
        // The panel itself is open, and so is a floor nothing covers.
        let (o, _) = open_share(&scene, &accel, &scene.polygon(1), 1, 7, 1);
        assert_eq!(o, 1.0);
        let bare = covered_floor(-0.5, 1e-3, false);
        let accel = Accel::new(&bare);
        assert_eq!(open_share(&bare, &accel, &bare.polygon(0), 0, 7, 0).0, 1.0);
    }

    #[test]
    fn points_under_a_covering_are_sealed_and_points_beside_it_are_not() {
        // The panel covers x < 0.5 of the floor a millimetre above it: every point under it sees only the
        // panel's back (32 rays); a point a centimetre beside it, or on the panel, is open at its first ray
        // or after a few.
        let scene = covered_floor(0.5, 1e-3, false);
        let accel = Accel::new(&scene);
        for x in [0.05, 0.25, 0.45] {
            let y = DVec3::new(x, 0.0, 1.0);
            let (sealed, rays) = point_sealed(
                &scene,
                &accel,
                0,
                y,
                POINT_SEAL_RAYS,
                7,
                point_key(&scene, 0, y),
            );
            assert!(sealed, "x = {x}");
            assert_eq!(rays, u64::from(POINT_SEAL_RAYS));
        }
        for (face, y) in [
            (0, DVec3::new(0.51, 0.0, 1.0)),
            (0, DVec3::new(1.5, 0.0, 1.0)),
            (1, DVec3::new(0.0, 1e-3, 1.0)),
        ] {
            let (sealed, rays) = point_sealed(
                &scene,
                &accel,
                face,
                y,
                POINT_SEAL_RAYS,
                7,
                point_key(&scene, face, y),
            );
            assert!(!sealed, "{y}");
            assert!(rays <= 4, "{rays} rays at {y}");
        }
    }

    #[test]
    fn points_in_a_gap_under_a_face_facing_them_are_sealed() {
        // The panel 1e-4 above the floor faces down (its front toward the floor, as a cube's bottom face
        // lying on a floor): the floor under it sees only a front 1e-4 away, below the gap of
        // SEAL_GAP_REL × the diagonal (3.6e-3); beside it, the floor is open.
        let scene = covered_floor(0.5, 1e-4, true);
        let accel = Accel::new(&scene);
        assert!(scene.faces[1].normal.y < 0.0);
        let at = |x: f64| {
            let y = DVec3::new(x, 0.0, 1.0);
            point_sealed(
                &scene,
                &accel,
                0,
                y,
                POINT_SEAL_RAYS,
                7,
                point_key(&scene, 0, y),
            )
            .0
        };
        assert!(at(0.25) && at(0.45));
        assert!(!at(0.55) && !at(1.5));
    }

    #[test]
    fn points_deep_in_a_gap_a_third_of_the_seal_gap_high_are_sealed() {
        // The panel faces down 1e-3 above the floor, a third of SEAL_GAP_REL × the diagonal (3.6e-3; a
        // block 1 mm above a room's floor covering is at a seventh). A ray from a point under it meets the
        // panel t = 1e-3 / cos θ away, beyond 3.6e-3 for a cosine-distributed ray with probability
        // (1e-3 / 3.6e-3)² ≈ 8%: a rule on t calls such a point sealed only with probability 0.92³² ≈ 7%.
        // The panel's plane lies 1e-3 from the point whichever way the ray runs, so every point more than
        // a few centimetres inside the panel's edge (x = 0.5) is sealed; beside the edge it is open.
        let scene = covered_floor(0.5, 1e-3, true);
        let accel = Accel::new(&scene);
        let at = |x: f64, z: f64| {
            let y = DVec3::new(x, 0.0, z);
            point_sealed(
                &scene,
                &accel,
                0,
                y,
                POINT_SEAL_RAYS,
                7,
                point_key(&scene, 0, y),
            )
            .0
        };
        for x in [0.05, 0.15, 0.25, 0.35, 0.45] {
            for z in [0.3, 0.7, 1.1, 1.5] {
                assert!(at(x, z), "x = {x}, z = {z}");
            }
        }
        assert!(!at(0.51, 1.0) && !at(1.5, 1.0));
    }

    #[test]
    fn an_element_under_a_face_lying_on_it_is_sealed_there() {
        // A cube's bottom face lying on the floor (a panel facing down, 1e-4 above it, over x < 0.5): the
        // floor's probe points under it see only that face's front. Without the gap rule they counted as
        // open (share 1), and the element sent the light of its whole area from under the cube, where the
        // cube's bottom caught it: a white room with a cube on its floor lost 1.7-4.2% in every method that
        // solves on open shares. With it the element's share is that of its points beside the face, 0.75.
        let scene = covered_floor(0.5, 1e-4, true);
        let accel = Accel::new(&scene);
        assert_eq!(
            open_share(&scene, &accel, &scene.polygon(0), 0, 7, 0).0,
            0.75
        );
    }

    #[test]
    fn a_face_standing_beside_a_point_does_not_close_its_rays() {
        use radlab_testkit::{grid, material};
        // A wall standing on the floor at x = 0.5 (facing -x, toward the floor's points at x < 0.5): points
        // of the floor 1e-4 from its foot meet its front within the seal gap with about half their rays, and
        // the rest of their hemisphere is open. The gap rule closes only faces that face the point's face
        // (GAP_FACING); the wall is at right angles to the floor, so no probe point of the floor is sealed,
        // whatever its rays. Closed by the wall, probe points near a room's edges and corners were called
        // sealed whenever all 8 of their rays met the faces beside them, and closed furnace rooms at
        // ρ = 0.999 lost their balance.
        let mut b = SceneBuilder::new("wall on a floor");
        let m = material(&mut b, "grey", 0.5, 0.0);
        let (z, x) = (2.0 * DVec3::Z, 0.5 * DVec3::X);
        grid(&mut b, DVec3::ZERO, z, x, 1, m);
        grid(&mut b, x, z, 2.0 * DVec3::Y, 1, m);
        let scene = b.build().expect("scene");
        assert!(scene.faces[0].normal.y > 0.0 && scene.faces[1].normal.x < 0.0);
        let accel = Accel::new(&scene);
        let gap = SEAL_GAP_REL * scene.diagonal();
        let y = DVec3::new(0.5 - 1e-4, 0.0, 1.0);
        let mut r = sampling::rng(7, 0);
        let mut beside = 0;
        for _ in 0..256 {
            let (u1, u2) = (sampling::uniform(&mut r), sampling::uniform(&mut r));
            let d = sampling::cosine_hemisphere(scene.faces[0].normal, u1, u2);
            if let Some(h) = accel.intersect_from(0, y, d).filter(|h| h.face == 1) {
                beside += 1;
                assert!(h.t * d.x.abs() <= gap, "within the gap");
                assert!(ray_opens(&scene, &accel, 0, y, d, gap), "{d}");
            }
        }
        assert!(beside > 64, "{beside} of 256 rays meet the wall");
    }

    #[test]
    fn a_fully_covered_element_is_left_alone_and_elements_resolve_the_edge() {
        let scene = covered_floor(1.0, 1e-3, false);
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

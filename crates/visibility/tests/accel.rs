//! The visibility engine against answers computed independently of it: closest hits against a brute-force
//! f64 loop over every face, visibility in a convex enclosure (every pair of points on its surface sees each
//! other, points on edges and corners included), touching surfaces and surfaces 1e-6 apart, each at scene
//! scales 1e-4, 1 and 1e4 (every answer must be the same, lengths scaled), ray counting, and casting from
//! rayon threads.

use glam::{DVec3, dvec3};
use radlab_scene::sampling::{self, Rng};
use radlab_scene::{FaceId, Material, Polygon, Ray, Scene, SceneBuilder, builtin};
use radlab_visibility::{Accel, AccelPreset, NodeTestKind, PACKET_SEGMENTS, Segment};
use rayon::prelude::*;

const PRESETS: [AccelPreset; 4] = [
    AccelPreset::VeryFast,
    AccelPreset::Fast,
    AccelPreset::Medium,
    AccelPreset::Quality,
];

fn u(r: &mut Rng) -> f64 {
    sampling::uniform(r)
}

fn random_dir(r: &mut Rng) -> DVec3 {
    loop {
        let v = dvec3(2.0 * u(r) - 1.0, 2.0 * u(r) - 1.0, 2.0 * u(r) - 1.0);
        let l = v.length();
        if l > 1e-3 && l <= 1.0 {
            return v / l;
        }
    }
}

/// Distance from `p` (in the polygon's plane) to the polygon's boundary: points closer than this to an edge
/// may legitimately be assigned to either neighbouring face.
fn distance_to_boundary(poly: &Polygon, p: DVec3) -> f64 {
    let v = poly.vertices();
    (0..v.len())
        .map(|k| {
            let (a, b) = (v[k], v[(k + 1) % v.len()]);
            let e = b - a;
            let t = ((p - a).dot(e) / e.length_squared()).clamp(0.0, 1.0);
            (p - (a + t * e)).length()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Brute-force closest hit in f64: the nearest face whose plane the ray crosses at t > tmin inside the face,
/// skipping face `skip`.
fn brute_force(
    scene: &Scene,
    o: DVec3,
    d: DVec3,
    tmin: f64,
    skip: FaceId,
) -> Option<(FaceId, f64)> {
    let mut best: Option<(FaceId, f64)> = None;
    for f in 0..scene.faces.len() {
        if f == skip {
            continue;
        }
        let poly = scene.polygon(f);
        // The normal from edge vectors (Newell's sum over absolute coordinates loses digits far from the
        // origin).
        let v = poly.vertices();
        let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
        let dn = n.dot(d);
        if dn == 0.0 {
            continue;
        }
        let t = (v[0] - o).dot(n) / dn;
        if t.is_nan() || t <= tmin || best.is_some_and(|(_, bt)| t >= bt) {
            continue;
        }
        if poly.contains(o + t * d, 0.0) {
            best = Some((f, t));
        }
    }
    best
}

/// Checks one closest-hit answer against brute force. Returns whether the brute-force hit lay within
/// `edge_tol` of a face boundary (an ambiguous case, where any face at the same distance is right).
fn check_hit(
    scene: &Scene,
    got: Option<radlab_visibility::Hit>,
    want: Option<(FaceId, f64)>,
    o: DVec3,
    d: DVec3,
    what: &str,
) -> bool {
    let diag = scene.diagonal();
    let edge_tol = 1e-6 * diag;
    match (got, want) {
        (Some(h), Some((f, t))) => {
            assert!(
                (h.t - t).abs() <= 1e-9 * diag,
                "{what}: t {} vs brute force {t} (faces {} / {f}), o {o:?} d {d:?}",
                h.t,
                h.face
            );
            if h.face != f {
                let ambiguous = distance_to_boundary(&scene.polygon(f), o + t * d) < edge_tol;
                assert!(
                    ambiguous,
                    "{what}: face {} vs brute force {f} at t {t}, o {o:?} d {d:?}",
                    h.face
                );
                return true;
            }
            false
        }
        (None, None) => false,
        (got, want) => {
            // Only a ray through an edge (within f32 resolution) may disagree about hitting at all.
            let near_edge = want.is_some_and(|(f, t)| {
                distance_to_boundary(&scene.polygon(f), o + t * d) < edge_tol
            });
            assert!(
                near_edge,
                "{what}: got {got:?}, brute force {want:?}, o {o:?} d {d:?}"
            );
            true
        }
    }
}

/// The furnace cube with blockers inside: two tilted quads, a triangle and a small box.
fn cube_with_blockers(scale: f64, offset: DVec3) -> Scene {
    let mut b = SceneBuilder::new("blockers");
    let m = b
        .add_material(Material::new("grey", DVec3::splat(0.5), DVec3::ZERO).expect("valid"))
        .expect("material");
    let p = |x: f64, y: f64, z: f64| offset + scale * dvec3(x, y, z);
    let mut add = |pts: &[DVec3]| {
        b.add_polygon_points(pts, m, "test").expect("polygon");
    };
    // Cube walls, inward normals, 3 × 3 quads each.
    let walls = [
        (p(0., 0., 0.), dvec3(1., 0., 0.), dvec3(0., 1., 0.)),
        (p(0., 0., 1.), dvec3(0., 1., 0.), dvec3(1., 0., 0.)),
        (p(0., 0., 0.), dvec3(0., 1., 0.), dvec3(0., 0., 1.)),
        (p(1., 0., 0.), dvec3(0., 0., 1.), dvec3(0., 1., 0.)),
        (p(0., 0., 0.), dvec3(0., 0., 1.), dvec3(1., 0., 0.)),
        (p(0., 1., 0.), dvec3(1., 0., 0.), dvec3(0., 0., 1.)),
    ];
    let n = 3;
    for (o, eu, ev) in walls {
        let (eu, ev) = (eu * scale, ev * scale);
        for j in 0..n {
            for i in 0..n {
                let q = |a: usize, c: usize| {
                    o + eu * (a as f64 / n as f64) + ev * (c as f64 / n as f64)
                };
                add(&[q(i, j), q(i + 1, j), q(i + 1, j + 1), q(i, j + 1)]);
            }
        }
    }
    // Two tilted parallelograms (planar by construction) and a triangle.
    let para = |o: DVec3, eu: DVec3, ev: DVec3| [o, o + eu, o + eu + ev, o + ev];
    add(&para(
        p(0.2, 0.2, 0.3),
        scale * dvec3(0.4, 0.05, 0.05),
        scale * dvec3(-0.05, 0.4, 0.1),
    ));
    add(&para(
        p(0.7, 0.1, 0.6),
        scale * dvec3(0.2, 0.0, 0.0),
        scale * dvec3(0.0, 0.1, 0.3),
    ));
    add(&[p(0.3, 0.8, 0.7), p(0.8, 0.6, 0.8), p(0.5, 0.9, 0.2)]);
    // A small closed box, outward normals.
    let (lo, hi) = (dvec3(0.6, 0.6, 0.1), dvec3(0.8, 0.85, 0.3));
    let c = |x: usize, y: usize, z: usize| {
        p(
            if x == 0 { lo.x } else { hi.x },
            if y == 0 { lo.y } else { hi.y },
            if z == 0 { lo.z } else { hi.z },
        )
    };
    add(&[c(0, 0, 0), c(0, 1, 0), c(1, 1, 0), c(1, 0, 0)]);
    add(&[c(0, 0, 1), c(1, 0, 1), c(1, 1, 1), c(0, 1, 1)]);
    add(&[c(0, 0, 0), c(1, 0, 0), c(1, 0, 1), c(0, 0, 1)]);
    add(&[c(0, 1, 0), c(0, 1, 1), c(1, 1, 1), c(1, 1, 0)]);
    add(&[c(0, 0, 0), c(0, 0, 1), c(0, 1, 1), c(0, 1, 0)]);
    add(&[c(1, 0, 0), c(1, 1, 0), c(1, 1, 1), c(1, 0, 1)]);
    b.build().expect("scene")
}

#[test]
fn closest_hit_matches_brute_force() {
    let scenes = [
        builtin("furnace-cube?tessellation=5").expect("cube"),
        cube_with_blockers(1.0, DVec3::ZERO),
        cube_with_blockers(1e-4, dvec3(3.0, -2.0, 5.0)),
        cube_with_blockers(1e4, dvec3(-3e4, 2e4, 1e4)),
    ];
    for (si, scene) in scenes.iter().enumerate() {
        let (lo, hi) = scene.bounds();
        for preset in PRESETS {
            let accel = Accel::with_preset(scene, preset);
            let mut r = sampling::rng(11, si as u64);
            let mut ambiguous = 0;
            let rays = 2000;
            for k in 0..rays {
                // Free rays from interior points ...
                let o = lo
                    + (hi - lo)
                        * dvec3(
                            0.02 + 0.96 * u(&mut r),
                            0.02 + 0.96 * u(&mut r),
                            0.02 + 0.96 * u(&mut r),
                        );
                let d = random_dir(&mut r);
                let got = accel.intersect(&Ray::new(o, d));
                let want = brute_force(scene, o, d, 0.0, usize::MAX);
                assert!(want.is_some(), "the cube is closed");
                ambiguous += check_hit(
                    scene,
                    got,
                    want,
                    o,
                    d,
                    &format!("scene {si} {preset:?} ray {k}"),
                ) as usize;
                // ... and rays leaving a face into its front hemisphere.
                let f = (u(&mut r) * scene.faces.len() as f64) as usize;
                let x = scene.polygon(f).sample_uniform(u(&mut r), u(&mut r));
                let n = scene.faces[f].normal;
                let d = sampling::cosine_hemisphere(n, u(&mut r), u(&mut r));
                let got = accel.intersect_from(f, x, d);
                assert!(got.is_none_or(|h| h.face != f && h.t > 0.0));
                let want = brute_force(scene, x, d, 0.0, f);
                ambiguous += check_hit(
                    scene,
                    got,
                    want,
                    x,
                    d,
                    &format!("scene {si} {preset:?} from face {f}"),
                ) as usize;
            }
            // Rays through an edge within 1e-6 of the scene size are rare.
            assert!(ambiguous < rays / 50, "{ambiguous} ambiguous of {rays}");
        }
    }
}

#[test]
fn rays_from_a_closed_cube_never_escape() {
    // Rays leaving every face, from points anywhere including within 1e-9 of edges and corners, always hit
    // another face: no self-hits, no leaks through shared edges.
    for scale in [1e-4f64, 1.0, 1e4] {
        let scene = builtin(&format!("furnace-cube?tessellation=4&size={scale}")).expect("cube");
        let accel = Accel::new(&scene);
        let mut r = sampling::rng(5, scale.to_bits());
        for k in 0..20_000 {
            let f = k % scene.faces.len();
            let poly = scene.polygon(f);
            // Push a third of the points onto the element's edges and corners.
            let (mut s, mut t) = (u(&mut r), u(&mut r));
            match k % 6 {
                0 => s = 0.0,
                1 => t = 1.0,
                2 => (s, t) = (0.0, 1.0),
                3 => s = 1e-9,
                _ => {}
            }
            let x = poly.point_at(s, t);
            let n = scene.faces[f].normal;
            let d = sampling::cosine_hemisphere(n, u(&mut r), u(&mut r));
            let h = accel.intersect_from(f, x, d);
            let Some(h) = h else {
                panic!("scale {scale}: ray {k} from face {f} at {x:?} dir {d:?} escaped");
            };
            assert!(h.face != f && h.t >= 0.0 && h.t <= 1.8 * scale, "{h:?}");
            // The hit point lies on the face that was hit.
            let hp = scene.polygon(h.face);
            assert!((h.point - hp.vertices()[0]).dot(hp.normal()).abs() < 1e-9 * scale);
        }
    }
}

/// Points on a cube's surface: uniform, on edges and at corners.
fn surface_points(scene: &Scene, count: usize, r: &mut Rng) -> Vec<(DVec3, FaceId)> {
    (0..count)
        .map(|k| {
            let f = (u(r) * scene.faces.len() as f64) as usize;
            let poly = scene.polygon(f);
            let (s, t) = match k % 4 {
                0 => (0.0, u(r)),
                1 => ((u(r) * 2.0).floor(), (u(r) * 2.0).floor()),
                _ => (u(r), u(r)),
            };
            (poly.point_at(s, t), f)
        })
        .collect()
}

#[test]
fn points_on_a_convex_enclosure_all_see_each_other() {
    // Every segment between two points of a convex surface lies inside it: nothing occludes, whether the
    // points lie inside faces, on shared edges or at corners, on the same face or on neighbours.
    for scale in [1e-4f64, 1.0, 1e4] {
        let scene = builtin(&format!("furnace-cube?tessellation=3&size={scale}")).expect("cube");
        for preset in PRESETS {
            let accel = Accel::with_preset(&scene, preset);
            let mut r = sampling::rng(3, scale.to_bits());
            let pts = surface_points(&scene, 300, &mut r);
            for (i, &(p, fp)) in pts.iter().enumerate() {
                for &(q, fq) in &pts[i + 1..] {
                    assert!(
                        accel.visible(p, q),
                        "scale {scale} {preset:?}: {p:?} -> {q:?}"
                    );
                    assert!(
                        accel.visible_between(p, fp, q, fq),
                        "scale {scale} {preset:?}: {p:?} ({fp}) -> {q:?} ({fq})"
                    );
                }
                // The same segments as packets.
                let segments: Vec<Segment> = pts[i + 1..]
                    .iter()
                    .map(|&(q, fq)| Segment { p, fp, q, fq })
                    .collect();
                let mut seen = vec![false; segments.len()];
                accel.visible_many(&segments, &mut seen);
                assert!(
                    seen.iter().all(|&v| v),
                    "scale {scale} {preset:?}: a packet from {p:?} is blocked"
                );
            }
        }
    }
}

/// A unit room (floor, ceiling, four walls, one quad each, inward) with, scaled by `s` and moved by `o`:
/// a closed box standing on the floor against the x = 0 wall (its bottom coplanar with the floor and its
/// back coplanar with the wall, both touching), and a thin plate `gap` above the floor, facing up.
fn touching_scene(s: f64, o: DVec3, gap: f64) -> Scene {
    let mut b = SceneBuilder::new("touching");
    let m = b
        .add_material(Material::new("grey", DVec3::splat(0.5), DVec3::ZERO).expect("valid"))
        .expect("material");
    let p = |x: f64, y: f64, z: f64| o + s * dvec3(x, y, z);
    let quads = [
        // Room.
        [p(0., 0., 0.), p(1., 0., 0.), p(1., 1., 0.), p(0., 1., 0.)],
        [p(0., 0., 1.), p(0., 1., 1.), p(1., 1., 1.), p(1., 0., 1.)],
        [p(0., 0., 0.), p(0., 1., 0.), p(0., 1., 1.), p(0., 0., 1.)],
        [p(1., 0., 0.), p(1., 0., 1.), p(1., 1., 1.), p(1., 1., 0.)],
        [p(0., 0., 0.), p(0., 0., 1.), p(1., 0., 1.), p(1., 0., 0.)],
        [p(0., 1., 0.), p(1., 1., 0.), p(1., 1., 1.), p(0., 1., 1.)],
        // Box [0, 0.3] × [0.1, 0.4] × [0, 0.3], outward normals.
        [
            p(0., 0.1, 0.),
            p(0., 0.4, 0.),
            p(0.3, 0.4, 0.),
            p(0.3, 0.1, 0.),
        ],
        [
            p(0., 0.1, 0.3),
            p(0.3, 0.1, 0.3),
            p(0.3, 0.4, 0.3),
            p(0., 0.4, 0.3),
        ],
        [
            p(0., 0.1, 0.),
            p(0.3, 0.1, 0.),
            p(0.3, 0.1, 0.3),
            p(0., 0.1, 0.3),
        ],
        [
            p(0., 0.4, 0.),
            p(0., 0.4, 0.3),
            p(0.3, 0.4, 0.3),
            p(0.3, 0.4, 0.),
        ],
        [
            p(0., 0.1, 0.),
            p(0., 0.1, 0.3),
            p(0., 0.4, 0.3),
            p(0., 0.4, 0.),
        ],
        [
            p(0.3, 0.1, 0.),
            p(0.3, 0.4, 0.),
            p(0.3, 0.4, 0.3),
            p(0.3, 0.1, 0.3),
        ],
        // Thin plate, `gap` above the floor.
        [
            p(0.5, 0.5, gap),
            p(0.8, 0.5, gap),
            p(0.8, 0.8, gap),
            p(0.5, 0.8, gap),
        ],
    ];
    for q in quads {
        b.add_polygon_points(&q, m, "test").expect("quad");
    }
    b.build().expect("scene")
}

/// One query's answer: visible, or the face hit and its distance over the scale.
type Answer = (bool, Option<(FaceId, f64)>);

const FLOOR: FaceId = 0;
const WALL_X0: FaceId = 2;
const BOX_BOTTOM: FaceId = 6;
const BOX_TOP: FaceId = 7;
const BOX_SIDE_X: FaceId = 11;
const PLATE: FaceId = 12;

#[test]
fn touching_and_nearly_touching_surfaces_at_every_scale() {
    for gap in [1e-6, 1e-5] {
        let mut answers: Vec<Vec<Answer>> = Vec::new();
        for (s, o) in [
            (1e-4, dvec3(1e-3, -2e-3, 5e-4)),
            (1.0, DVec3::ZERO),
            (1e4, dvec3(-3e4, 1e4, 7e3)),
        ] {
            let scene = touching_scene(s, o, gap);
            let accel = Accel::new(&scene);
            let p = |x: f64, y: f64, z: f64| o + s * dvec3(x, y, z);
            let mut got = Vec::new();
            let mut vis = |a: DVec3, fa: FaceId, b: DVec3, fb: FaceId, want: bool, what: &str| {
                let v = accel.visible_between(a, fa, b, fb);
                assert_eq!(v, want, "gap {gap} scale {s}: {what} (visible_between)");
                let v2 = accel.visible(a, b);
                assert_eq!(v2, want, "gap {gap} scale {s}: {what} (visible)");
                got.push((v, None));
            };
            // Floor next to the box sees the box's side (the box bottom touches the floor along the way).
            vis(
                p(0.5, 0.25, 0.0),
                FLOOR,
                p(0.3, 0.25, 0.15),
                BOX_SIDE_X,
                true,
                "floor to box side",
            );
            vis(
                p(0.301, 0.25, 0.0),
                FLOOR,
                p(0.3, 0.25, 0.29),
                BOX_SIDE_X,
                true,
                "floor at the box's foot",
            );
            // Floor under the box sees nothing above the box.
            vis(
                p(0.15, 0.25, 0.0),
                FLOOR,
                p(0.15, 0.25, 1.0),
                1,
                false,
                "floor under the box to ceiling",
            );
            // The wall behind the box is covered; beside it, it is not.
            vis(
                p(0.0, 0.25, 0.15),
                WALL_X0,
                p(1.0, 0.25, 0.15),
                3,
                false,
                "wall behind the box",
            );
            vis(
                p(0.0, 0.6, 0.15),
                WALL_X0,
                p(1.0, 0.6, 0.15),
                3,
                true,
                "wall beside the box",
            );
            // The box top sees the ceiling.
            vis(
                p(0.1, 0.25, 0.3),
                BOX_TOP,
                p(0.5, 0.5, 1.0),
                1,
                true,
                "box top to ceiling",
            );
            // Floor under the thin plate sees its back only; beside it, the ceiling.
            vis(
                p(0.6, 0.6, 0.0),
                FLOOR,
                p(0.6, 0.6, 1.0),
                1,
                false,
                "floor under the plate",
            );
            vis(
                p(0.6, 0.6, 0.0),
                FLOOR,
                p(0.9, 0.6, 1.0),
                1,
                false,
                "floor under the plate, slanted",
            );
            vis(
                p(0.9, 0.6, 0.0),
                FLOOR,
                p(0.9, 0.6, 1.0),
                1,
                true,
                "floor beside the plate",
            );
            vis(
                p(0.6, 0.6, 0.0),
                FLOOR,
                p(0.6, 0.6, gap),
                PLATE,
                true,
                "floor to the plate's back",
            );
            vis(
                p(0.6, 0.6, gap),
                PLATE,
                p(0.6, 0.6, 1.0),
                1,
                true,
                "plate to ceiling",
            );
            // Closest hits: from the floor under the plate, the plate's back at distance gap·s.
            let mut hit = |x: DVec3, f: FaceId, d: DVec3, want: FaceId, t: f64, what: &str| {
                let h = accel.intersect_from(f, x, d.normalize()).expect("hit");
                assert_eq!(h.face, want, "gap {gap} scale {s}: {what}");
                assert!(
                    (h.t / s - t).abs() < 1e-9,
                    "gap {gap} scale {s}: {what}: t {} vs {t}",
                    h.t / s
                );
                got.push((true, Some((h.face, h.t / s))));
            };
            hit(
                p(0.6, 0.6, 0.0),
                FLOOR,
                DVec3::Z,
                PLATE,
                gap,
                "floor under the plate, up",
            );
            hit(
                p(0.6, 0.6, 0.0),
                FLOOR,
                dvec3(1.0, 0.0, 1.0),
                PLATE,
                gap * 2f64.sqrt(),
                "floor under the plate, slanted",
            );
            hit(
                p(0.6, 0.6, gap),
                PLATE,
                DVec3::Z,
                1,
                1.0 - gap,
                "plate to ceiling",
            );
            hit(
                p(0.5, 0.25, 0.0),
                FLOOR,
                dvec3(-1.0, 0.0, 1.0),
                BOX_SIDE_X,
                0.2 * 2f64.sqrt(),
                "floor to box side",
            );
            // Floor under the box: the box bottom touches the floor point, so the ray hits it at once.
            hit(
                p(0.15, 0.25, 0.0),
                FLOOR,
                DVec3::Z,
                BOX_BOTTOM,
                0.0,
                "floor under the box",
            );
            // A ray from the wall behind the box meets the box's back face (touching) at once.
            hit(
                p(0.0, 0.25, 0.15),
                WALL_X0,
                DVec3::X,
                10,
                0.0,
                "wall behind the box",
            );
            // A ray grazing along the floor from just beside the box reaches the far wall.
            let x0 = 0.3 + 1e-6;
            hit(
                p(x0, 0.25, 0.0),
                FLOOR,
                dvec3(1.0, 0.0, 1e-3),
                3,
                (1.0 - x0) * (1.0 + 1e-6f64).sqrt(),
                "grazing",
            );
            answers.push(got);
        }
        // Identical answers at every scale.
        for a in &answers[1..] {
            assert_eq!(a.len(), answers[0].len());
            for (x, y) in a.iter().zip(&answers[0]) {
                assert_eq!(x.0, y.0);
                match (x.1, y.1) {
                    (Some((fa, ta)), Some((fb, tb))) => assert!(fa == fb && (ta - tb).abs() < 1e-9),
                    (None, None) => {}
                    _ => panic!("answers differ across scales"),
                }
            }
        }
    }
}

#[test]
fn rays_through_shared_edges_and_quad_diagonals_do_not_slip_through() {
    // Quads are split into two triangles along a diagonal, and walls are tessellated: a ray aimed exactly at
    // a diagonal, a shared edge or a shared vertex must still hit (an f32 ray-triangle test alone lets such
    // rays through both neighbours). Sources inside the cube, targets on those lines of every face.
    for scale in [1e-4f64, 1.0, 1e4] {
        let scene = builtin(&format!("furnace-cube?tessellation=3&size={scale}")).expect("cube");
        for preset in PRESETS {
            let accel = Accel::with_preset(&scene, preset);
            let mut r = sampling::rng(8, scale.to_bits());
            for f in 0..scene.faces.len() {
                let v = scene.polygon(f).vertices().to_vec();
                for k in 0..40 {
                    let a = u(&mut r);
                    let target = match k % 4 {
                        0 => v[0].lerp(v[2], a), // the split diagonal
                        1 => v[0].lerp(v[1], a), // an edge, shared unless on the cube's edge
                        2 => v[1].lerp(v[2], a),
                        _ => v[(k / 4) % 4], // a vertex
                    };
                    let o = scale
                        * dvec3(
                            0.1 + 0.8 * u(&mut r),
                            0.1 + 0.8 * u(&mut r),
                            0.1 + 0.8 * u(&mut r),
                        );
                    let d = (target - o).normalize();
                    let Some(h) = accel.intersect(&Ray::new(o, d)) else {
                        panic!(
                            "scale {scale} {preset:?}: face {f} k {k} target {target:?} from {o:?}: no hit"
                        );
                    };
                    assert!(
                        (h.t - (target - o).length()).abs() < 1e-9 * scale,
                        "scale {scale} {preset:?}: face {f} target {target:?}: hit {h:?}"
                    );
                    // And the target is visible from the source (it lies on the surface).
                    assert!(accel.visible(o, target));
                }
            }
        }
    }
}

#[test]
fn rays_are_counted() {
    let scene = cube_with_blockers(1.0, DVec3::ZERO);
    let accel = Accel::new(&scene);
    assert_eq!(accel.rays_cast(), 0);
    let mut r = sampling::rng(2, 0);
    for _ in 0..100 {
        let o = dvec3(0.5, 0.5, 0.5) + 0.1 * random_dir(&mut r);
        accel.intersect(&Ray::new(o, random_dir(&mut r)));
    }
    for _ in 0..50 {
        accel.intersect_from(0, dvec3(0.1, 0.1, 0.0), random_dir(&mut r).abs());
    }
    for _ in 0..70 {
        accel.visible(
            dvec3(0.1, 0.5, 0.5),
            dvec3(0.9, 0.4, 0.2) + 0.05 * random_dir(&mut r),
        );
    }
    assert_eq!(accel.rays_cast(), 220);
    // The counting variants give the same answers, count as rays, and report a traversal that did work.
    for _ in 0..30 {
        let ray = Ray::new(dvec3(0.5, 0.5, 0.5), random_dir(&mut r));
        let (h, cost) = accel.intersect_counting(&ray);
        let h2 = accel.intersect(&ray);
        assert_eq!(h.map(|h| (h.face, h.t)), h2.map(|h| (h.face, h.t)));
        assert!(cost.nodes >= 1 && cost.triangles >= 1);
        let q = dvec3(0.9, 0.1, 0.8) + 0.05 * random_dir(&mut r);
        let (v, cost) = accel.visible_counting(ray.origin, q);
        assert_eq!(v, accel.visible(ray.origin, q));
        assert!(cost.nodes >= 1);
    }
    assert_eq!(accel.rays_cast(), 220 + 4 * 30);
}

#[test]
fn answers_are_the_same_from_rayon_threads() {
    let scene = cube_with_blockers(1.0, DVec3::ZERO);
    let accel = Accel::new(&scene);
    let jobs: Vec<(DVec3, DVec3, DVec3)> = (0..20_000u64)
        .map(|k| {
            let mut r = sampling::rng(9, k);
            let o = dvec3(0.05, 0.05, 0.05) + 0.9 * dvec3(u(&mut r), u(&mut r), u(&mut r));
            let q = dvec3(0.05, 0.05, 0.05) + 0.9 * dvec3(u(&mut r), u(&mut r), u(&mut r));
            (o, random_dir(&mut r), q)
        })
        .collect();
    let cast = |&(o, d, q): &(DVec3, DVec3, DVec3)| {
        let h = accel.intersect(&Ray::new(o, d)).map(|h| (h.face, h.t));
        (h, accel.visible(o, q))
    };
    let serial: Vec<_> = jobs.iter().map(cast).collect();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(4)
        .build()
        .expect("pool");
    let parallel: Vec<_> = pool.install(|| jobs.par_iter().map(cast).collect());
    assert_eq!(serial, parallel);
    assert_eq!(accel.rays_cast(), 4 * jobs.len() as u64);
    // The enclosure is closed and the blockers occlude something.
    assert!(serial.iter().all(|(h, _)| h.is_some()));
    let blocked = serial.iter().filter(|(_, v)| !v).count();
    assert!(
        blocked > jobs.len() / 50 && blocked < jobs.len() / 2,
        "{blocked}"
    );
}

/// The ray count stays exact when more threads cast at once than the counter has slots of their own (63):
/// 100 threads, released together, each cast 2,000 rays and segments, and the later threads share one slot.
#[test]
fn rays_are_counted_exactly_from_more_threads_than_counter_slots() {
    let scene = cube_with_blockers(1.0, DVec3::ZERO);
    let accel = Accel::new(&scene);
    let (threads, per_thread) = (100u64, 1000u64);
    let start = std::sync::Barrier::new(threads as usize);
    std::thread::scope(|s| {
        for t in 0..threads {
            let (accel, start) = (&accel, &start);
            s.spawn(move || {
                start.wait();
                for k in 0..per_thread {
                    let mut r = sampling::rng(31, t * per_thread + k);
                    let o = dvec3(0.05, 0.05, 0.05) + 0.9 * dvec3(u(&mut r), u(&mut r), u(&mut r));
                    let q = dvec3(0.05, 0.05, 0.05) + 0.9 * dvec3(u(&mut r), u(&mut r), u(&mut r));
                    accel.intersect(&Ray::new(o, random_dir(&mut r)));
                    accel.visible(o, q);
                }
            });
        }
    });
    assert_eq!(accel.rays_cast(), 2 * threads * per_thread);
}

/// An `Accel` built on a pool of 1 thread and one built on 2 (where the build's passes and the wide BVH
/// conversion split over rayon tasks) give the same answer, bit for bit, to every ray: closest hits from
/// surface points (the face chosen on edge ties depends on the BVH's order) and visibility between them,
/// and count the same rays.
#[test]
fn accels_built_on_1_and_2_threads_answer_alike() {
    let scene = builtin("bumpy-sphere?faces=20000").expect("scene");
    let build = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool")
            .install(|| Accel::new(&scene))
    };
    let (one, two) = (build(1), build(2));
    let mut r = sampling::rng(13, 0);
    let points = surface_points(&scene, 6000, &mut r);
    let answers = |a: &Accel| -> Vec<(Option<(FaceId, u64)>, bool)> {
        points
            .windows(2)
            .enumerate()
            .map(|(k, w)| {
                let ((p, f), (q, g)) = (w[0], w[1]);
                let mut r = sampling::rng(14, k as u64);
                let d =
                    sampling::cosine_hemisphere(scene.polygon(f).normal(), u(&mut r), u(&mut r));
                let h = a.intersect_from(f, p, d).map(|h| (h.face, h.t.to_bits()));
                (h, a.visible_between(p, f, q, g))
            })
            .collect()
    };
    let (a1, a2) = (answers(&one), answers(&two));
    assert!(
        a1 == a2,
        "answers differ between the 1- and 2-thread builds"
    );
    assert_eq!(one.rays_cast(), two.rays_cast());
    // A closed scene: every ray hits; some segments are blocked by the bumps.
    assert!(a1.iter().all(|(h, _)| h.is_some()));
    assert!(a1.iter().any(|(_, v)| !v));
}

/// Packets of segments (`visible_many`) answer exactly as the segments one by one (`visible_between`) and
/// count the same rays, with either node test: bundles between two faces (the coherent case packets are
/// for) and segments between unrelated points, packets from 1 to over two [`PACKET_SEGMENTS`] long, with
/// zero-length segments and ends on no face mixed in, on enclosures with blockers and touching surfaces at
/// scales 1e-4 to 1e4 and on a bumpy sphere of 2·10⁴ faces.
#[test]
fn packets_answer_as_segments_one_by_one() {
    let scenes = [
        ("blockers", cube_with_blockers(1.0, DVec3::ZERO)),
        (
            "blockers 1e-4",
            cube_with_blockers(1e-4, dvec3(1e-3, -2e-3, 5e-4)),
        ),
        (
            "touching 1e4",
            touching_scene(1e4, dvec3(-3e4, 1e4, 7e3), 1e-6),
        ),
        ("touching 1", touching_scene(1.0, DVec3::ZERO, 1e-6)),
        (
            "bumpy sphere",
            builtin("bumpy-sphere?faces=20000").expect("scene"),
        ),
    ];
    for (name, scene) in &scenes {
        for kind in [NodeTestKind::Portable, NodeTestKind::Avx2] {
            let mut accel = Accel::new(scene);
            if !accel.set_node_test(kind) {
                continue; // no AVX2 on this processor
            }
            let mut r = sampling::rng(21, name.len() as u64);
            let (mut blocked, mut open) = (0usize, 0usize);
            for k in 0..400 {
                let len = 1 + k % (2 * PACKET_SEGMENTS + 7);
                let (fa, fb) = (
                    (u(&mut r) * scene.faces.len() as f64) as FaceId,
                    (u(&mut r) * scene.faces.len() as f64) as FaceId,
                );
                let segments: Vec<Segment> = (0..len)
                    .map(|j| {
                        let (p, fp, q, fq) = if k % 2 == 0 {
                            // A bundle between two faces.
                            let (pa, pb) = (scene.polygon(fa), scene.polygon(fb));
                            (
                                pa.point_at(u(&mut r), u(&mut r)),
                                fa,
                                pb.point_at(u(&mut r), u(&mut r)),
                                fb,
                            )
                        } else {
                            let pts = surface_points(scene, 2, &mut r);
                            (pts[0].0, pts[0].1, pts[1].0, pts[1].1)
                        };
                        match j % 11 {
                            3 => Segment { p, fp, q: p, fq },
                            5 => Segment {
                                p,
                                fp: usize::MAX,
                                q,
                                fq: usize::MAX,
                            },
                            _ => Segment { p, fp, q, fq },
                        }
                    })
                    .collect();
                let before = accel.rays_cast();
                let one_by_one: Vec<bool> = segments
                    .iter()
                    .map(|s| accel.visible_between(s.p, s.fp, s.q, s.fq))
                    .collect();
                let single_rays = accel.rays_cast() - before;
                let mut packed = vec![false; len];
                accel.visible_many(&segments, &mut packed);
                assert_eq!(
                    packed, one_by_one,
                    "{name} {kind:?}: packet {k} of {len} answers differently"
                );
                assert_eq!(
                    accel.rays_cast() - before,
                    2 * single_rays,
                    "{name} {kind:?}: packet {k} counts other rays"
                );
                blocked += one_by_one.iter().filter(|&&v| !v).count();
                open += one_by_one.iter().filter(|&&v| v).count();
            }
            // Not vacuous: both answers occur often.
            assert!(
                blocked > 100 && open > 500,
                "{name} {kind:?}: {blocked} blocked, {open} open"
            );
        }
    }
}

/// Random triangles of every shape (slivers, triangles 1e-5 of the scene) hit by rays aimed at their
/// vertices and at points on and beside their edges, from every angle down to grazing. In debug builds
/// `Accel` checks each decision its f32 test takes alone (inside, or outside by more than the tolerance)
/// against the f64 test it skips; here the answers must also match brute force away from edges.
#[test]
fn f32_decisions_agree_with_f64_near_edges_and_at_grazing_angles() {
    let mut r = sampling::rng(11, 0);
    let mut b = SceneBuilder::new("slivers");
    let m = b
        .add_material(Material::new("grey", DVec3::splat(0.5), DVec3::ZERO).expect("valid"))
        .expect("material");
    let mut tris = Vec::new();
    while tris.len() < 300 {
        let c = dvec3(u(&mut r), u(&mut r), u(&mut r));
        let size = [0.2, 1e-2, 1e-5][tris.len() % 3];
        let e1 = size * random_dir(&mut r);
        // Every fourth a sliver: the third vertex 1e-3 of the size off the first edge.
        let thin = if tris.len() % 4 == 0 { 1e-3 } else { 1.0 };
        let e2 = 0.5 * e1 + thin * size * random_dir(&mut r);
        let t = [c, c + e1, c + e2];
        if b.add_polygon_points(&t, m, "test").is_ok() {
            tris.push(t);
        }
    }
    let scene = b.build().expect("scene");
    let accel = Accel::new(&scene);
    let mut cast = 0u64;
    for (k, t) in tris.iter().enumerate() {
        let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
        for j in 0..40 {
            // A vertex, a point on an edge, or a point beside an edge by a few tolerances or ulps.
            let (a, c) = (t[j % 3], t[(j + 1) % 3]);
            let s = u(&mut r);
            let beside = [0.0, 1e-16, 1e-12, 3e-9, 1e-7][j % 5];
            let edge_out = (c - a).cross(n).normalize();
            let target = if j % 7 == 0 {
                a
            } else {
                a + s * (c - a) + beside * edge_out
            };
            // From any direction, every eighth grazing the plane.
            let mut d = random_dir(&mut r);
            if j % 8 == 0 {
                d = (d - d.dot(n) * n).normalize() + 1e-6 * u(&mut r) * n;
                d = d.normalize();
            }
            let o = target - 0.5 * d;
            let h = accel.intersect(&Ray::new(o, d));
            cast += 1;
            if let (Some(h), Some((f, t_bf))) = (h, brute_force(&scene, o, d, 0.0, usize::MAX)) {
                // Away from both faces' edges the nearest face is unambiguous.
                let clear =
                    |face: FaceId, x: DVec3| distance_to_boundary(&scene.polygon(face), x) > 1e-6;
                if clear(f, o + t_bf * d) && clear(h.face, h.point) {
                    assert_eq!(
                        h.face, f,
                        "triangle {k} ray {j}: {h:?} brute force t {t_bf}"
                    );
                    assert!((h.t - t_bf).abs() < 1e-9, "triangle {k} ray {j}");
                }
            }
            accel.visible(o, target + 0.5 * d);
            accel.visible(o, target);
            cast += 2;
        }
    }
    assert_eq!(accel.rays_cast(), cast);
}

#[test]
fn nearest_faces_agree_with_comparing_every_face() {
    // Points on and near the faces of a bumpy sphere in a room (and at its corners, where several faces tie):
    // the BVH query finds the nearest distance and every face within the slack, as a scan of all faces does.
    let scene = radlab_scene::builtin("bumpy-sphere?faces=600").expect("scene");
    let accel = Accel::new(&scene);
    let slack = 1e-9 * scene.diagonal();
    let mut r = sampling::rng(11, 0);
    for k in 0..400 {
        let f = k % scene.face_count();
        let poly = scene.polygon(f);
        let mut p = poly.sample_uniform(sampling::uniform(&mut r), sampling::uniform(&mut r));
        if k % 3 == 1 {
            p +=
                (sampling::uniform(&mut r) - 0.5) * 0.05 * scene.diagonal() * scene.faces[f].normal;
        }
        if k % 7 == 0 {
            p = poly.vertices()[0];
        }
        let d: Vec<f64> = (0..scene.face_count())
            .map(|g| scene.polygon(g).distance_to(p))
            .collect();
        let best = d.iter().copied().fold(f64::INFINITY, f64::min);
        let (near, faces) = accel.nearest_faces(p, slack).expect("faces");
        assert!(
            (near - best).abs() <= 1e-12 * scene.diagonal(),
            "{near} vs {best}"
        );
        let want: Vec<usize> = (0..scene.face_count())
            .filter(|&g| d[g] <= best + slack)
            .collect();
        assert_eq!(faces, want, "point {k}");
    }
}

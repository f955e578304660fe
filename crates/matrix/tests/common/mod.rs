//! Scenes the matrix tests and benches share, built with `SceneBuilder` (so they do not depend on file
//! formats or builtins other than the analytic ones).

#![allow(dead_code)]

use radlab_scene::glam::{DVec3, dvec3};
use radlab_scene::{Material, Rgb, Scene, SceneBuilder};

/// Adds the planar quad `p` with its normal turned toward `toward`.
fn quad(b: &mut SceneBuilder, mut p: [DVec3; 4], toward: DVec3, mat: u32) {
    let n = (p[1] - p[0]).cross(p[2] - p[0]);
    let c = (p[0] + p[1] + p[2] + p[3]) / 4.0;
    if n.dot(toward - c) < 0.0 {
        p.reverse();
    }
    let added = b
        .add_polygon_points(&p, mat, "test quad")
        .expect("valid quad");
    assert_eq!(added, 1, "quad {p:?} was not kept as one face");
}

/// A block of square footprint (side 2h, rotated by `deg` about y, centred at (cx, cz)) and height `height`,
/// standing on y = 0: four sides and a top, normals outward.
fn block(b: &mut SceneBuilder, cx: f64, cz: f64, h: f64, height: f64, deg: f64, mat: u32) {
    let (s, c) = deg.to_radians().sin_cos();
    let corner = |u: f64, v: f64| dvec3(cx + c * u - s * v, 0.0, cz + s * u + c * v);
    let base = [corner(-h, -h), corner(h, -h), corner(h, h), corner(-h, h)];
    let up = dvec3(0.0, height, 0.0);
    let centre = dvec3(cx, 0.5 * height, cz);
    for k in 0..4 {
        let (a, bb) = (base[k], base[(k + 1) % 4]);
        let mid = 0.5 * (a + bb) + 0.5 * up;
        quad(b, [a, bb, bb + up, a + up], mid + (mid - centre), mat);
    }
    let top = [base[0] + up, base[1] + up, base[2] + up, base[3] + up];
    quad(b, top, centre + 2.0 * up, mat);
}

/// A Cornell-like box (555 units a side, y up, open at z = 0 unless `closed`): white floor, ceiling and back
/// wall, red and green side walls, two rotated white blocks and a 130 × 105 ceiling light facing down.
/// `white` sets the white walls' and blocks' reflectance.
pub fn cornell_like(closed: bool, white: Rgb) -> Scene {
    cornell_box(
        closed,
        white,
        dvec3(0.63, 0.065, 0.05),
        dvec3(0.14, 0.45, 0.091),
    )
}

/// The same box with every surface but the light of reflectance `rho` (grey).
pub fn cornell_grey(closed: bool, rho: f64) -> Scene {
    let g = Rgb::splat(rho);
    cornell_box(closed, g, g, g)
}

fn cornell_box(closed: bool, white: Rgb, red_rho: Rgb, green_rho: Rgb) -> Scene {
    let s = 555.0;
    let mut b = SceneBuilder::new("cornell-like");
    let w = b
        .add_material(Material::new("white", white, Rgb::ZERO).expect("white"))
        .expect("white");
    let red = b
        .add_material(Material::new("red", red_rho, Rgb::ZERO).expect("red"))
        .expect("red");
    let green = b
        .add_material(Material::new("green", green_rho, Rgb::ZERO).expect("green"))
        .expect("green");
    let light = b
        .add_material(
            Material::new(
                "light",
                Rgb::ZERO,
                std::f64::consts::PI * dvec3(17.0, 12.0, 4.0),
            )
            .expect("light"),
        )
        .expect("light");
    let centre = DVec3::splat(0.5 * s);
    let p = |x: f64, y: f64, z: f64| dvec3(x, y, z);
    quad(
        &mut b,
        [p(0., 0., 0.), p(s, 0., 0.), p(s, 0., s), p(0., 0., s)],
        centre,
        w,
    ); // floor
    quad(
        &mut b,
        [p(0., s, 0.), p(s, s, 0.), p(s, s, s), p(0., s, s)],
        centre,
        w,
    ); // ceiling
    quad(
        &mut b,
        [p(0., 0., s), p(s, 0., s), p(s, s, s), p(0., s, s)],
        centre,
        w,
    ); // back
    quad(
        &mut b,
        [p(s, 0., 0.), p(s, 0., s), p(s, s, s), p(s, s, 0.)],
        centre,
        red,
    ); // left
    quad(
        &mut b,
        [p(0., 0., 0.), p(0., 0., s), p(0., s, s), p(0., s, 0.)],
        centre,
        green,
    ); // right
    if closed {
        quad(
            &mut b,
            [p(0., 0., 0.), p(s, 0., 0.), p(s, s, 0.), p(0., s, 0.)],
            centre,
            w,
        ); // front
    }
    block(&mut b, 185.5, 169.0, 82.5, 165.0, -17.0, w);
    block(&mut b, 368.5, 351.5, 82.5, 330.0, 17.0, w);
    let y = s - 1.0;
    quad(
        &mut b,
        [
            p(213., y, 227.),
            p(343., y, 227.),
            p(343., y, 332.),
            p(213., y, 332.),
        ],
        p(278., 0., 278.),
        light,
    );
    b.build().expect("cornell-like box")
}

/// A convex unit box (x, y, z in [0, 1]) with a lid when `closed`: an emitting floor (E = `emission`,
/// ρ = 0.5) and walls of three different colours. Convex, so every pair is fully visible and the exact point
/// kernel makes each element's row sum 1 minus its view of the opening.
pub fn mixed_box(closed: bool, emission: Rgb) -> Scene {
    let mut b = SceneBuilder::new("mixed-box");
    let floor = b
        .add_material(Material::new("floor", Rgb::splat(0.5), emission).expect("floor"))
        .expect("floor");
    let m1 = b
        .add_material(Material::new("a", dvec3(0.8, 0.3, 0.1), Rgb::ZERO).expect("a"))
        .expect("a");
    let m2 = b
        .add_material(Material::new("b", dvec3(0.2, 0.7, 0.4), Rgb::ZERO).expect("b"))
        .expect("b");
    let m3 = b
        .add_material(Material::new("c", dvec3(0.0, 0.6, 0.9), Rgb::ZERO).expect("c"))
        .expect("c");
    let centre = DVec3::splat(0.5);
    let p = |x: f64, y: f64, z: f64| dvec3(x, y, z);
    quad(
        &mut b,
        [p(0., 0., 0.), p(1., 0., 0.), p(1., 1., 0.), p(0., 1., 0.)],
        centre,
        floor,
    ); // z = 0
    quad(
        &mut b,
        [p(0., 0., 0.), p(0., 1., 0.), p(0., 1., 1.), p(0., 0., 1.)],
        centre,
        m1,
    ); // x = 0
    quad(
        &mut b,
        [p(1., 0., 0.), p(1., 1., 0.), p(1., 1., 1.), p(1., 0., 1.)],
        centre,
        m2,
    ); // x = 1
    quad(
        &mut b,
        [p(0., 0., 0.), p(1., 0., 0.), p(1., 0., 1.), p(0., 0., 1.)],
        centre,
        m3,
    ); // y = 0
    quad(
        &mut b,
        [p(0., 1., 0.), p(1., 1., 0.), p(1., 1., 1.), p(0., 1., 1.)],
        centre,
        m1,
    ); // y = 1
    if closed {
        quad(
            &mut b,
            [p(0., 0., 1.), p(1., 0., 1.), p(1., 1., 1.), p(0., 1., 1.)],
            centre,
            m2,
        ); // lid
    }
    b.build().expect("mixed box")
}

/// The closed [`mixed_box`] with a panel (ρ = 0.5, facing up) a millimetre above its y = 0 face over
/// x, z ∈ [0.13, 0.71]: its edges cross elements of size 0.2, which then lie partly under the panel, where
/// they see only its back.
pub fn covered_box(emission: Rgb) -> Scene {
    let base = mixed_box(true, emission);
    let mut b = SceneBuilder::new("covered-box");
    let mut ids = Vec::new();
    for m in &base.materials {
        ids.push(b.add_material(m.clone()).expect("material"));
    }
    for f in 0..base.face_count() {
        let poly = base.polygon(f);
        b.add_polygon_points(poly.vertices(), ids[base.faces[f].material as usize], "box")
            .expect("face");
    }
    let panel = b
        .add_material(Material::new("panel", Rgb::splat(0.5), Rgb::ZERO).expect("panel"))
        .expect("panel");
    let (lo, hi, y) = (0.13, 0.71, 1e-3);
    quad(
        &mut b,
        [
            dvec3(lo, y, lo),
            dvec3(hi, y, lo),
            dvec3(hi, y, hi),
            dvec3(lo, y, hi),
        ],
        dvec3(0.5, 1.0, 0.5),
        panel,
    );
    b.build().expect("covered box")
}

/// The opening of the open [`mixed_box`] as a polygon facing into the box (its front sees the interior).
pub fn mixed_box_opening() -> radlab_scene::Polygon {
    radlab_scene::Polygon::quad(
        dvec3(0., 0., 1.),
        dvec3(0., 1., 1.),
        dvec3(1., 1., 1.),
        dvec3(1., 0., 1.),
    )
}

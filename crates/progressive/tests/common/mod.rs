//! Test scenes shared by the integration tests.
#![allow(dead_code)]

use radlab_scene::glam::{DVec3, dvec3};
use radlab_scene::{Material, Rgb, Scene, SceneBuilder};

/// Adds the axis-aligned box [lo, hi] with outward normals (no bottom face when `open_bottom`).
pub fn add_block(b: &mut SceneBuilder, lo: DVec3, hi: DVec3, m: u32, open_bottom: bool) {
    let c = |x: bool, y: bool, z: bool| {
        dvec3(
            if x { hi.x } else { lo.x },
            if y { hi.y } else { lo.y },
            if z { hi.z } else { lo.z },
        )
    };
    let (f, t) = (false, true);
    let mut faces = vec![
        [c(f, f, t), c(t, f, t), c(t, t, t), c(f, t, t)], // top, +z
        [c(f, f, f), c(f, f, t), c(f, t, t), c(f, t, f)], // -x
        [c(t, f, f), c(t, t, f), c(t, t, t), c(t, f, t)], // +x
        [c(f, f, f), c(t, f, f), c(t, f, t), c(f, f, t)], // -y
        [c(f, t, f), c(f, t, t), c(t, t, t), c(t, t, f)], // +y
    ];
    if !open_bottom {
        faces.push([c(f, f, f), c(f, t, f), c(t, t, f), c(t, f, f)]); // -z
    }
    for q in faces {
        b.add_polygon_points(&q, m, "block").expect("block face");
    }
}

/// A closed unit room, scaled by `scale`, (inward normals) with a square light in the middle of the ceiling and a block on the
/// floor: occlusion, colour and a light that is one face among others. Every reflectance is positive, so every
/// element's irradiance is known from its radiosity (for the energy balance).
pub fn closed_room(scale: f64) -> Scene {
    room(scale, true)
}

/// The same room without the block: a convex enclosure, where every pair of elements sees each other fully.
pub fn convex_room() -> Scene {
    room(1.0, false)
}

/// The floor (+z) and four inward walls of the box [0,1]³ mapped through `p`; the x = 0 wall is `red`.
fn add_floor_and_walls(
    b: &mut SceneBuilder,
    p: &dyn Fn(f64, f64, f64) -> DVec3,
    white: u32,
    red: u32,
) {
    let quads = [
        (
            [p(0., 0., 0.), p(1., 0., 0.), p(1., 1., 0.), p(0., 1., 0.)],
            white,
            "floor",
        ),
        (
            [p(0., 0., 0.), p(0., 1., 0.), p(0., 1., 1.), p(0., 0., 1.)],
            red,
            "x0",
        ),
        (
            [p(1., 0., 0.), p(1., 0., 1.), p(1., 1., 1.), p(1., 1., 0.)],
            white,
            "x1",
        ),
        (
            [p(0., 0., 0.), p(0., 0., 1.), p(1., 0., 1.), p(1., 0., 0.)],
            white,
            "y0",
        ),
        (
            [p(0., 1., 0.), p(1., 1., 0.), p(1., 1., 1.), p(0., 1., 1.)],
            white,
            "y1",
        ),
    ];
    for (pts, m, what) in quads {
        b.add_polygon_points(&pts, m, what).expect("f");
    }
}

fn room(scale: f64, with_block: bool) -> Scene {
    let mut b = SceneBuilder::new("room");
    let white = b
        .add_material(Material::new("white", Rgb::splat(0.7), Rgb::ZERO).expect("m"))
        .expect("m");
    let red = b
        .add_material(Material::new("red", Rgb::new(0.6, 0.1, 0.1), Rgb::ZERO).expect("m"))
        .expect("m");
    let light = b
        .add_material(Material::new("light", Rgb::splat(0.5), Rgb::new(10.0, 9.0, 8.0)).expect("m"))
        .expect("m");
    let s = scale;
    let p = |x: f64, y: f64, z: f64| dvec3(x, y, z) * s;
    // Floor (+z), walls, ceiling split 3 × 3 with the centre emitting (-z).
    add_floor_and_walls(&mut b, &p, white, red);
    let cuts = [0.0, 0.4, 0.6, 1.0];
    for j in 0..3 {
        for i in 0..3 {
            let (x0, x1, y0, y1) = (cuts[i], cuts[i + 1], cuts[j], cuts[j + 1]);
            let m = if i == 1 && j == 1 { light } else { white };
            b.add_polygon_points(
                &[p(x0, y0, 1.), p(x0, y1, 1.), p(x1, y1, 1.), p(x1, y0, 1.)],
                m,
                "ceiling",
            )
            .expect("f");
        }
    }
    if with_block {
        add_block(&mut b, p(0.55, 0.2, 0.0), p(0.85, 0.5, 0.45), white, true);
    }
    b.build().expect("room")
}

/// A closed unit cube meshed on a 0.25 grid everywhere: the ceiling is 4 × 4 faces whose centre 2 × 2 emit,
/// walls and floor are single faces, and the optional block [0.5, 0.75] × [0.25, 0.5] × [0, 0.4] stands on
/// the floor. With element size 0.25 every pair of elements that touch shares a whole edge.
pub fn aligned_room(with_block: bool) -> Scene {
    let mut b = SceneBuilder::new("aligned-room");
    let white = b
        .add_material(Material::new("white", Rgb::splat(0.75), Rgb::ZERO).expect("m"))
        .expect("m");
    let red = b
        .add_material(Material::new("red", Rgb::new(0.7, 0.1, 0.1), Rgb::ZERO).expect("m"))
        .expect("m");
    let light = b
        .add_material(Material::new("light", Rgb::splat(0.5), Rgb::new(10.0, 9.0, 8.0)).expect("m"))
        .expect("m");
    let p = |x: f64, y: f64, z: f64| dvec3(x, y, z);
    add_floor_and_walls(&mut b, &p, white, red);
    for j in 0..4 {
        for i in 0..4 {
            let (x0, y0) = (0.25 * i as f64, 0.25 * j as f64);
            let (x1, y1) = (x0 + 0.25, y0 + 0.25);
            let m = if (1..3).contains(&i) && (1..3).contains(&j) {
                light
            } else {
                white
            };
            b.add_polygon_points(
                &[p(x0, y0, 1.), p(x0, y1, 1.), p(x1, y1, 1.), p(x1, y0, 1.)],
                m,
                "ceiling",
            )
            .expect("f");
        }
    }
    if with_block {
        add_block(&mut b, p(0.5, 0.25, 0.0), p(0.75, 0.5, 0.4), white, true);
    }
    b.build().expect("room")
}

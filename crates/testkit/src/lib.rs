//! # radlab-testkit
//!
//! Small scenes that several crates' tests share (the conformance suite, the cluster methods' own tests):
//! builders for quads, grids and boxes, the closed unit room lit by one ceiling quad (every reflectance
//! positive, so emitted power must equal absorbed power), hollow boxes with sealed interiors, two rooms split by a thin wall, the Cornell box closed into a furnace ([`cornell_furnace`]) or lit by its lamp alone ([`cornell_lamp_lit`]), a block standing on the floor ([`sealed`]), and a scene
//! scaled by a factor (results must not depend on it); and the comparison of several seeds' mean answer with a
//! reference's ([`ChannelMeans`]). Test support, kept in one place so no crate carries its own copy; nothing in
//! the solvers uses it.

pub mod sealed;

use glam::{DVec3, dvec3};

use radlab_scene::{Material, Rgb, Scene, SceneBuilder};

/// A grey material of reflectance `rho` and emission `e` in every channel; returns its id.
pub fn material(b: &mut SceneBuilder, name: &str, rho: f64, e: f64) -> u32 {
    b.add_material(Material::new(name, Rgb::splat(rho), Rgb::splat(e)).expect("material"))
        .expect("material")
}

/// An n × n grid of quads over o + s u + t v (s, t ∈ [0, 1]), normal along u × v.
pub fn grid(b: &mut SceneBuilder, o: DVec3, u: DVec3, v: DVec3, n: usize, m: u32) {
    for j in 0..n {
        for i in 0..n {
            let p = |di: usize, dj: usize| {
                o + u * ((i + di) as f64 / n as f64) + v * ((j + dj) as f64 / n as f64)
            };
            b.add_polygon_points(&[p(0, 0), p(1, 0), p(1, 1), p(0, 1)], m, "grid")
                .expect("quad");
        }
    }
}

/// The six faces of the box [lo, hi] as (origin, u, v) with u × v pointing outward (or inward).
pub fn box_sides(lo: DVec3, hi: DVec3, outward: bool) -> Vec<(DVec3, DVec3, DVec3)> {
    let d = hi - lo;
    let (x, y, z) = (dvec3(d.x, 0., 0.), dvec3(0., d.y, 0.), dvec3(0., 0., d.z));
    let sides = [
        (lo, y, x),     // z = lo, normal −z
        (lo + z, x, y), // z = hi, +z
        (lo, z, y),     // x = lo, −x
        (lo + x, y, z), // x = hi, +x
        (lo, x, z),     // y = lo, −y
        (lo + y, z, x), // y = hi, +y
    ];
    sides
        .into_iter()
        .map(|(o, u, v)| if outward { (o, u, v) } else { (o, v, u) })
        .collect()
}

/// The box [lo, hi] as six n × n grids of quads of material `m`, facing outward (or inward).
pub fn add_box(b: &mut SceneBuilder, lo: DVec3, hi: DVec3, n: usize, m: u32, outward: bool) {
    for (o, u, v) in box_sides(lo, hi, outward) {
        grid(b, o, u, v, n, m);
    }
}

/// The closed unit room (inward faces, 2 × 2 quads per side, h = 0.5) with coloured reflectances; one ceiling
/// quad is the light (so every face's back is inside a wall and nothing is absorbed by a back); `extra` adds
/// objects. Every reflectance is positive.
pub fn room(name: &str, extra: &dyn Fn(&mut SceneBuilder)) -> Scene {
    let mut b = SceneBuilder::new(name);
    let refl = [0.7, 0.4, 0.5, 0.6, 0.5, 0.3];
    let light = material(&mut b, "light", 0.3, 10.0);
    for (k, (o, u, v)) in box_sides(DVec3::ZERO, DVec3::ONE, false)
        .into_iter()
        .enumerate()
    {
        let m = material(&mut b, &format!("wall{k}"), refl[k], 0.0);
        for j in 0..2 {
            for i in 0..2 {
                let p = |di: usize, dj: usize| {
                    o + u * ((i + di) as f64 / 2.0) + v * ((j + dj) as f64 / 2.0)
                };
                // The ceiling (side 1, z = 1) has its quad nearest the origin as the light.
                let mat = if k == 1 && i == 0 && j == 0 { light } else { m };
                b.add_polygon_points(&[p(0, 0), p(1, 0), p(1, 1), p(0, 1)], mat, "room")
                    .expect("quad");
            }
        }
    }
    extra(&mut b);
    b.build().expect("scene")
}

/// A closed furnace room on [0, 2.5] × [0, 2] × [0, 2.5] (inward faces, one quad each, y up) with a unit
/// cube over x, z ∈ [1, 2] and y ∈ [lift, 1 + lift] (outward faces; with `lift` = 0 it rests on the floor
/// with no gap, its bottom touching it), every face of reflectance `rho` and emission `e`. Every point light
/// can reach has B = E/(1 − ρ); a resting cube's bottom and the floor under it receive nothing. The floor's
/// 2 × 2 Gauss points (x, z ≈ 0.53, 1.97) and centroid all lie behind the planes of the cube's x = 2 and
/// z = 2 sides, which the floor beyond them sees. Faces in [`box_sides`] order: the room's z = 0, z = 2.5,
/// x = 0, x = 2.5, y = 0 (the floor, 4), y = 2 (0–5), then the cube's z = 1, z = 2, x = 1, x = 2 (9),
/// bottom, top (6–11).
pub fn furnace_with_cube(rho: f64, e: f64, lift: f64) -> Scene {
    let mut b = SceneBuilder::new("furnace with a cube");
    let m = material(&mut b, "furnace", rho, e);
    add_box(&mut b, DVec3::ZERO, dvec3(2.5, 2.0, 2.5), 1, m, false);
    add_box(
        &mut b,
        dvec3(1., lift, 1.),
        dvec3(2., 1. + lift, 2.),
        1,
        m,
        true,
    );
    b.build().expect("scene")
}

/// The published Cornell box (radlab-scene's `builtin:cornell`, millimetres) closed by a front wall over its
/// open side, every face of reflectance `rho` and emission `e`: the two blocks stand on the floor, occluding
/// and sealing it, and every point light can reach has B = E/(1 − ρ) (the floor under the blocks, which sees
/// only their insides, receives nothing). The front wall's corners are where the published floor and ceiling
/// end at z = 0. Faces: the builtin's, in its order, then the front wall.
pub fn cornell_furnace(rho: f64, e: f64) -> Scene {
    let mut b = SceneBuilder::new("closed Cornell furnace");
    let m = material(&mut b, "furnace", rho, e);
    closed_cornell(b, true, |_| m)
}

/// The same closed Cornell box lit by its own lamp: every face of reflectance `rho`, the builtin's light of
/// emission `lamp` and nothing else emitting, the two blocks kept or left out. Closed and of one reflectance,
/// it absorbs what the lamp emits: the faces' power Σ A B is A_lamp E / (1 − ρ), however unevenly the lamp
/// lights them. The blocks' faces are those with a vertex strictly between the floor (y = 0) and the
/// ceiling (y = 548.8). Faces: the builtin's in its order (less the blocks'), then the front wall.
pub fn cornell_lamp_lit(rho: f64, lamp: f64, blocks: bool) -> Scene {
    let mut b = SceneBuilder::new("closed lamp-lit Cornell box");
    let grey = material(&mut b, "grey", rho, 0.0);
    let light = material(&mut b, "lamp", rho, lamp);
    closed_cornell(b, blocks, |emits| if emits { light } else { grey })
}

/// The builtin Cornell box's faces in its order (the blocks' left out unless `blocks`: the faces with a vertex
/// strictly between the floor, y = 0, and the ceiling, y = 548.8), then [`CORNELL_FRONT`], each of the material
/// `pick(emits)` gives by whether the builtin's face emits (the front wall: `pick(false)`).
fn closed_cornell(mut b: SceneBuilder, blocks: bool, pick: impl Fn(bool) -> u32) -> Scene {
    let cornell = radlab_scene::builtin("cornell").expect("builtin Cornell box");
    for f in 0..cornell.face_count() {
        let polygon = cornell.polygon(f);
        let vertices = polygon.vertices();
        if !blocks && vertices.iter().any(|v| v.y > 0.0 && v.y < 548.8) {
            continue;
        }
        let m = pick(cornell.emission(f).max_element() > 0.0);
        b.add_polygon_points(vertices, m, "cornell").expect("face");
    }
    b.add_polygon_points(&CORNELL_FRONT, pick(false), "front wall")
        .expect("front wall");
    b.build().expect("scene")
}

/// The wall that closes the published Cornell box's open side, where its floor and ceiling end at z = 0.
const CORNELL_FRONT: [DVec3; 4] = [
    dvec3(0.0, 0.0, 0.0),
    dvec3(552.8, 0.0, 0.0),
    dvec3(556.0, 548.8, 0.0),
    dvec3(0.0, 548.8, 0.0),
];

/// A closed box (outward faces) on [lo, hi] with a closed unlit interior: inward faces inset by 1e-3 of its size.
pub fn hollow_box(b: &mut SceneBuilder, lo: DVec3, hi: DVec3) {
    let m = material(b, "box", 0.6, 0.0);
    add_box(b, lo, hi, 1, m, true);
    let inside = material(b, "interior", 0.9, 0.0);
    let inset = 1e-3 * (hi - lo).max_element();
    add_box(b, lo + inset, hi - inset, 1, inside, false);
}

/// The scene with every vertex multiplied by `s`: same vertices (so the same mesh connectivity), faces,
/// indices and materials.
pub fn scaled(scene: &Scene, s: f64) -> Scene {
    let mut b = SceneBuilder::new(&format!("{} x {s}", scene.name));
    for m in &scene.materials {
        b.add_material(m.clone()).expect("valid material");
    }
    for &v in &scene.vertices {
        b.add_vertex(v * s, "scaled").expect("finite vertex");
    }
    for f in &scene.faces {
        let added = b
            .add_polygon(f.vertex_indices(), f.material, "scaled")
            .expect("valid face");
        assert_eq!(added, 1, "a face changed under scaling");
    }
    b.build().expect("scene")
}

/// Two rooms side by side (for light-leak tests) on one floor quad and under one ceiling quad, split by a wall of thickness `t`
/// (two faces back to back); the light hangs in room A (x < 1). Room B's faces are named "dark".
pub fn two_rooms(t: f64) -> Scene {
    let mut b = SceneBuilder::new("two rooms behind a thin wall");
    let white = material(&mut b, "white", 0.7, 0.0);
    let dark = material(&mut b, "dark", 0.7, 0.0);
    let light = material(&mut b, "light", 0.5, 20.0);
    let q = |b: &mut SceneBuilder, p: [DVec3; 4], m: u32| {
        b.add_polygon_points(&p, m, "two rooms").expect("quad");
    };
    let (w, h) = (1.0 - t / 2.0, 1.0 + t / 2.0);
    // Floor (up) and ceiling (down), one quad each under both rooms.
    q(
        &mut b,
        [
            dvec3(0., 0., 0.),
            dvec3(2., 0., 0.),
            dvec3(2., 1., 0.),
            dvec3(0., 1., 0.),
        ],
        white,
    );
    q(
        &mut b,
        [
            dvec3(0., 0., 1.),
            dvec3(0., 1., 1.),
            dvec3(2., 1., 1.),
            dvec3(2., 0., 1.),
        ],
        white,
    );
    // Room A's walls (x = 0, y = 0, y = 1 for x < w) and the wall's A side (x = w, facing −x).
    q(
        &mut b,
        [
            dvec3(0., 0., 0.),
            dvec3(0., 1., 0.),
            dvec3(0., 1., 1.),
            dvec3(0., 0., 1.),
        ],
        white,
    );
    q(
        &mut b,
        [
            dvec3(0., 0., 0.),
            dvec3(0., 0., 1.),
            dvec3(w, 0., 1.),
            dvec3(w, 0., 0.),
        ],
        white,
    );
    q(
        &mut b,
        [
            dvec3(0., 1., 0.),
            dvec3(w, 1., 0.),
            dvec3(w, 1., 1.),
            dvec3(0., 1., 1.),
        ],
        white,
    );
    q(
        &mut b,
        [
            dvec3(w, 0., 0.),
            dvec3(w, 0., 1.),
            dvec3(w, 1., 1.),
            dvec3(w, 1., 0.),
        ],
        white,
    );
    // Room B's walls and the wall's B side (x = h, facing +x).
    q(
        &mut b,
        [
            dvec3(2., 0., 0.),
            dvec3(2., 0., 1.),
            dvec3(2., 1., 1.),
            dvec3(2., 1., 0.),
        ],
        dark,
    );
    q(
        &mut b,
        [
            dvec3(h, 0., 0.),
            dvec3(h, 0., 1.),
            dvec3(2., 0., 1.),
            dvec3(2., 0., 0.),
        ],
        dark,
    );
    q(
        &mut b,
        [
            dvec3(h, 1., 0.),
            dvec3(2., 1., 0.),
            dvec3(2., 1., 1.),
            dvec3(h, 1., 1.),
        ],
        dark,
    );
    q(
        &mut b,
        [
            dvec3(h, 0., 0.),
            dvec3(h, 1., 0.),
            dvec3(h, 1., 1.),
            dvec3(h, 0., 1.),
        ],
        dark,
    );
    // The wall's top and bottom are on the ceiling and floor quads; its ends on the side walls (y = 0, 1),
    // covered by small strips.
    q(
        &mut b,
        [
            dvec3(w, 0., 0.),
            dvec3(w, 0., 1.),
            dvec3(h, 0., 1.),
            dvec3(h, 0., 0.),
        ],
        white,
    );
    q(
        &mut b,
        [
            dvec3(w, 1., 0.),
            dvec3(h, 1., 0.),
            dvec3(h, 1., 1.),
            dvec3(w, 1., 1.),
        ],
        white,
    );
    // The light, facing down, in room A.
    q(
        &mut b,
        [
            dvec3(0.3, 0.3, 0.99),
            dvec3(0.3, 0.7, 0.99),
            dvec3(0.7, 0.7, 0.99),
            dvec3(0.7, 0.3, 0.99),
        ],
        light,
    );
    b.build().expect("scene")
}

/// One channel's mean answer over a set of points: several independent runs' (their mean, and its standard
/// error from the spread between runs) against a reference's (the mean of its per-point estimates, and the
/// standard error that follows from theirs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChannelMeans {
    /// The runs' mean over the points, averaged over the runs.
    pub mean: f64,
    /// Its standard error: the standard deviation of the runs' means over √runs.
    pub se: f64,
    /// The reference's mean over the points.
    pub reference: f64,
    /// Its standard error: √Σ se_i² / points.
    pub reference_se: f64,
}

impl ChannelMeans {
    /// Channel `c` of `runs` (each run's answers at the points, at least two runs) against `reference` (each
    /// point's estimate and standard error, in the same order).
    pub fn new(reference: &[(Rgb, Rgb)], runs: &[Vec<Rgb>], c: usize) -> Self {
        let n = reference.len() as f64;
        assert!(runs.len() >= 2, "a standard error needs at least two runs");
        let means: Vec<f64> = runs
            .iter()
            .map(|r| r.iter().map(|b| b[c]).sum::<f64>() / n)
            .collect();
        let (mean, se) = mean_se(&means);
        Self {
            mean,
            se,
            reference: reference.iter().map(|(m, _)| m[c]).sum::<f64>() / n,
            reference_se: reference
                .iter()
                .map(|(_, e)| e[c] * e[c])
                .sum::<f64>()
                .sqrt()
                / n,
        }
    }

    /// The tolerance `relative` × reference + `sigmas` × the combined standard error: a stated bias
    /// allowance (0 for an unbiased method) plus the noise of both.
    pub fn tolerance(&self, relative: f64, sigmas: f64) -> f64 {
        relative * self.reference.abs() + sigmas * self.se.hypot(self.reference_se)
    }

    /// Whether the two means differ by no more than [`ChannelMeans::tolerance`].
    pub fn agrees(&self, relative: f64, sigmas: f64) -> bool {
        (self.mean - self.reference).abs() <= self.tolerance(relative, sigmas)
    }
}

/// The mean of independent samples and its standard error (sample standard deviation over √count; at least
/// two samples).
pub fn mean_se(xs: &[f64]) -> (f64, f64) {
    let k = xs.len() as f64;
    let m = xs.iter().sum::<f64>() / k;
    let var = xs.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (k - 1.0);
    (m, (var / k).sqrt())
}

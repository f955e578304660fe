//! Sealed interiors stay dark: closed boxes flush against the walls and floor of a lit room, each holding an
//! inner box of inward faces that no ray from outside can reach. The exact answer is B = 0 on every inner face
//! at every order of reflection; a cluster link's mean visibility times its mean source flux is not zero there
//! (before faces were tested for reachability the α transfer left 3.0e-3 of the lit maximum inside), so this
//! checks the reachability test ([`radlab_volume_cluster::enclosure`]) and its use by every transfer.

use glam::{DVec3, dvec3};
use radlab_scene::{Accel, Material, Rgb, Scene, SceneBuilder, Solver, Step};
use radlab_volume_cluster::{Transfer, VolumeClusterParams, VolumeClusterSolver, enclosure};

/// A grey material.
fn material(b: &mut SceneBuilder, name: &str, rho: f64, e: f64) -> u32 {
    b.add_material(Material::new(name, Rgb::splat(rho), Rgb::splat(e)).expect("material"))
        .expect("material")
}

/// An n × n grid of quads over o + s u + t v.
fn grid(b: &mut SceneBuilder, o: DVec3, u: DVec3, v: DVec3, n: usize, m: u32) {
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

/// The six sides of the box [lo, hi] as (origin, u, v), u × v outward (or inward).
fn box_sides(lo: DVec3, hi: DVec3, outward: bool) -> Vec<(DVec3, DVec3, DVec3)> {
    let d = hi - lo;
    let (x, y, z) = (dvec3(d.x, 0., 0.), dvec3(0., d.y, 0.), dvec3(0., 0., d.z));
    let sides = [
        (lo, y, x),
        (lo + z, x, y),
        (lo, z, y),
        (lo + x, y, z),
        (lo, x, z),
        (lo + y, z, x),
    ];
    sides
        .into_iter()
        .map(|(o, u, v)| if outward { (o, u, v) } else { (o, v, u) })
        .collect()
}

/// The six sides of a box as n × n grids.
fn add_box(b: &mut SceneBuilder, lo: DVec3, hi: DVec3, n: usize, m: u32, outward: bool) {
    for (o, u, v) in box_sides(lo, hi, outward) {
        grid(b, o, u, v, n, m);
    }
}

/// The closed unit room (inward faces, 2 × 2 quads per side) lit by one ceiling quad, with `extra` added.
fn room(name: &str, extra: &dyn Fn(&mut SceneBuilder)) -> Scene {
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
                let mat = if k == 1 && i == 0 && j == 0 { light } else { m };
                b.add_polygon_points(&[p(0, 0), p(1, 0), p(1, 1), p(0, 1)], mat, "room")
                    .expect("quad");
            }
        }
    }
    extra(&mut b);
    b.build().expect("scene")
}

/// A closed box (outward faces) holding a sealed box of inward faces inset by 1e-3 of its size.
fn hollow_box(b: &mut SceneBuilder, lo: DVec3, hi: DVec3) {
    let m = material(b, "box", 0.6, 0.0);
    add_box(b, lo, hi, 1, m, true);
    let inside = material(b, "interior", 0.9, 0.0);
    let inset = 1e-3 * (hi - lo).max_element();
    add_box(b, lo + inset, hi - inset, 1, inside, false);
}

/// Boxes flush against the x = 0 wall and the floor, and in the corner x = y = 1 on the floor.
fn touching() -> Scene {
    room("boxes touching walls", &|b| {
        hollow_box(b, dvec3(0.0, 0.3, 0.0), dvec3(0.25, 0.6, 0.3));
        hollow_box(b, dvec3(0.7, 0.7, 0.0), dvec3(1.0, 1.0, 0.5));
    })
}

#[test]
fn sealed_interiors_are_unreachable_and_the_room_is_reachable() {
    let scene = touching();
    let accel = Accel::new(&scene);
    let reach = enclosure::reachable_faces(&scene, &accel, 1);
    assert_eq!(reach.len(), scene.face_count());
    for (f, &reached) in reach.iter().enumerate() {
        let name = &scene.material(f).name;
        if name == "interior" {
            assert!(!reached, "inner face {f} reachable");
        } else if name != "box" {
            assert!(reached, "room face {f} ({name}) unreachable");
        } else {
            // Every box face not pressed against a wall or the floor (those see nothing) faces the room.
            let c = scene.faces[f].centroid;
            let pressed = [c.x, c.z, 1.0 - c.x, 1.0 - c.y]
                .iter()
                .any(|t| t.abs() < 1e-9);
            assert!(reached || pressed, "box face {f} at {c:?} unreachable");
        }
    }
}

#[test]
fn no_light_enters_sealed_interiors_with_any_transfer() {
    let scene = touching();
    let accel = Accel::new(&scene);
    for transfer in [Transfer::Isotropic, Transfer::Alpha, Transfer::Directional] {
        let p = VolumeClusterParams {
            transfer,
            ..VolumeClusterParams::default()
        };
        let mut s = VolumeClusterSolver::new(&scene, &accel, p, 1).expect("solver");
        let mut converged = false;
        for _ in 0..10_000 {
            if s.step().expect("step") == Step::Converged {
                converged = true;
                break;
            }
        }
        assert!(converged, "{transfer:?} did not converge");
        let faces = s.face_radiosity();
        let lit = faces.iter().map(|f| f.2.max_element()).fold(0.0, f64::max);
        assert!(lit > 0.0, "{transfer:?}: nothing lit");
        for (f, _, b) in faces {
            if scene.material(f).name == "interior" {
                assert_eq!(b, Rgb::ZERO, "{transfer:?}: inner face {f} has B = {b:?}");
            }
        }
    }
}

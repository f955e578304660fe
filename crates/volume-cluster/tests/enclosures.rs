//! Sealed interiors stay dark: closed boxes flush against the walls and floor of a lit room, each holding an
//! inner box of inward faces that no ray from outside can reach. The exact answer is B = 0 on every inner face
//! at every order of reflection; a cluster link's mean visibility times its mean source flux is not zero there
//! (before faces were tested for reachability the α transfer left 3.0e-3 of the lit maximum inside), so this
//! checks the reachability test ([`radlab_volume_cluster::enclosure`]) and its use by every transfer.

use glam::dvec3;
use radlab_method::{Solver, Step};
use radlab_scene::{Rgb, Scene};
use radlab_testkit::{hollow_box, room};
use radlab_visibility::Accel;
use radlab_volume_cluster::{Transfer, VolumeClusterParams, VolumeClusterSolver, enclosure};

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

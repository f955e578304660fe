//! A sliver (aspect ratio 1e4) in a furnace: a unit cube of inward faces, uniform E = 1 and ρ = 0.9, whose floor
//! is a 1e-4 × 1 strip beside the rest. Every point has B = E/(1 − ρ) = 10 exactly, so the sliver's row of
//! the discrete operator must sum to one. The sliver is a direct child of the root cluster (its extent is the
//! whole box), and under the power norm a receiver of relative area 1.7e-5 keeps its first links: patch links
//! to the walls it touches (exact point-to-polygon factors at its Gauss points) and point approximations from
//! the octant clusters above. Evaluated at its centroid, those approximations and the patch links' Gauss means
//! summed to 1.058 (B = 10.52); evaluated at the same Gauss points they sum to 1.037 (B = 10.33): the rest is
//! the point approximation of the octant clusters at distances comparable to their size (their part of the
//! row is 0.373 against 0.336), which the power norm never refines for so small a receiver. (The box is
//! closed: with `row_normalisation = "closed-scenes"` that row is rescaled to one and B = 10 by construction,
//! which is why this test runs at the default, without it.)

use glam::{DVec3, dvec3};
use radlab_method::{Solver, Step};
use radlab_scene::{Material, Rgb, SceneBuilder};
use radlab_volume_cluster::{VolumeClusterParams, VolumeClusterSolver};

#[test]
#[ignore = "measured B = 10.33 against 10 (3.3%; 5.2% before Gauss-point evaluation): the octant clusters' point \
            approximation, unrefined under the power norm for a receiver of relative area 1.7e-5"]
fn a_sliver_in_a_furnace_gets_e_over_one_minus_rho() {
    let rho = 0.9;
    let mut b = SceneBuilder::new("sliver furnace");
    let m = b
        .add_material(Material::new("furnace", Rgb::splat(rho), Rgb::ONE).expect("material"))
        .expect("material");
    // Floor: the sliver, then the rest.
    b.add_polygon_points(
        &[
            dvec3(0., 0., 0.),
            dvec3(1e-4, 0., 0.),
            dvec3(1e-4, 1., 0.),
            dvec3(0., 1., 0.),
        ],
        m,
        "sliver",
    )
    .expect("sliver");
    b.add_polygon_points(
        &[
            dvec3(1e-4, 0., 0.),
            dvec3(1., 0., 0.),
            dvec3(1., 1., 0.),
            dvec3(1e-4, 1., 0.),
        ],
        m,
        "floor",
    )
    .expect("floor");
    // The other five sides, inward, 2 × 2 quads each: (origin, u, v) with u × v pointing in.
    let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
    for (o, u, v) in [
        (z, y, x),
        (DVec3::ZERO, y, z),
        (x, z, y),
        (DVec3::ZERO, z, x),
        (y, x, z),
    ] {
        for j in 0..2 {
            for i in 0..2 {
                let p = |di: usize, dj: usize| {
                    o + u * ((i + di) as f64 / 2.0) + v * ((j + dj) as f64 / 2.0)
                };
                b.add_polygon_points(&[p(0, 0), p(1, 0), p(1, 1), p(0, 1)], m, "wall")
                    .expect("quad");
            }
        }
    }
    let scene = b.build().expect("scene");
    assert_eq!(scene.face_count(), 22, "the sliver must be kept");
    for f in 0..scene.face_count() {
        let n = scene.faces[f].normal;
        let c = scene.faces[f].centroid;
        assert!(n.dot(DVec3::splat(0.5) - c) > 0.0, "face {f} faces out");
    }
    let accel = radlab_visibility::Accel::new(&scene);
    // The element's own value, not a final gather's (which re-gathers with exact point-to-polygon factors
    // from the walls' B ≈ 10 and would hide the sliver's row).
    let mut params = VolumeClusterParams::default();
    params.engine.answer.reconstruction = radlab_answer::Reconstruction::Constant;
    let mut s = VolumeClusterSolver::new(&scene, &accel, params, 1).expect("solver");
    let mut converged = false;
    for _ in 0..10_000 {
        if s.step().expect("step") == Step::Converged {
            converged = true;
            break;
        }
    }
    assert!(converged);
    let b = s
        .solution()
        .radiosity_at(0, dvec3(0.5e-4, 0.5, 0.0))
        .max_element();
    let exact = 1.0 / (1.0 - rho);
    assert!(
        (b - exact).abs() / exact < 0.01,
        "sliver B = {b}, exact {exact}"
    );
}

//! Progressive radiosity against matrix radiosity (radlab-matrix) on the same mesh: once both have converged
//! they solve the same linear system, so they must agree element by element.
//!
//! The two are not bit-for-bit the same system: the matrix method symmetrises each pair,
//! G_ij = ½(A_i F_ij + A_j F_ji), while shooting uses the receiver-side factor F_ij as it is. They coincide when
//! the receiver quadrature is reciprocal, which it becomes as the quadrature is refined, fastest where element
//! grids meet edge to edge. So the tight check (the issue asks for 1e-3; 1e-4 is asserted) is on rooms meshed
//! on one grid, at 4 × 4 receiver points, with the 2 × 2 difference printed beside it (it is larger: that
//! quadrature's reciprocity error); a room whose grids meet out of step shows the difference shrinking with
//! the quadrature. Visibility is the same deterministic kernel in both: unoccluded in a convex room, one
//! centre-to-centre ray in a room with a block.

use radlab_kernels::form_factor::VisibilitySampling;
use radlab_matrix::{Iteration, MatrixParams, MatrixSolver};
use radlab_method::{Solver, Step};
use radlab_progressive::{ProgressiveParams, ProgressiveSolver};
use radlab_scene::{Rgb, Scene};
use radlab_visibility::Accel;

mod common;

/// Worst relative difference per element and channel between the two converged solutions.
fn worst_difference(
    scene: &Scene,
    size: f64,
    q: u32,
    visibility: VisibilitySampling,
) -> (f64, u64) {
    let accel = Accel::new(scene);
    let mut m = MatrixSolver::new(
        scene,
        &accel,
        MatrixParams {
            element_size: Some(size),
            iteration: Iteration::GaussSeidel,
            tolerance: 1e-10,
            visibility,
            quadrature: q,
            ..Default::default()
        },
        1,
    )
    .expect("matrix");
    while m.step().expect("matrix step") == Step::Continue {}
    let mut p = ProgressiveSolver::new(
        scene,
        &accel,
        ProgressiveParams {
            quadrature: q,
            stop_unshot_fraction: 1e-9,
            ..ProgressiveParams::fixed_mesh(size, visibility)
        },
        1,
    )
    .expect("progressive");
    while p.step().expect("progressive step") == Step::Continue {}
    let pe = p.elements();
    let mb = m.element_radiosity();
    assert_eq!(pe.len(), mb.len(), "same mesh");
    let mut worst: f64 = 0.0;
    for (k, (a, b)) in pe.iter().zip(mb).enumerate() {
        assert_eq!(
            a.polygon,
            m.mesh().elements[k].polygon,
            "same element order"
        );
        let rel = (a.radiosity - *b).abs() / b.abs().max(Rgb::splat(1e-12));
        worst = worst.max(rel.max_element());
    }
    (worst, p.shots())
}

#[test]
fn agrees_with_matrix_radiosity_in_a_convex_room() {
    let scene = common::aligned_room(false);
    let (d2, _) = worst_difference(&scene, 0.25, 2, VisibilitySampling::Unoccluded);
    let (d4, shots) = worst_difference(&scene, 0.25, 4, VisibilitySampling::Unoccluded);
    println!(
        "aligned convex room, {shots} shots: worst relative difference {d2:.2e} (2x2), {d4:.2e} (4x4)"
    );
    assert!(d4 < 1e-4, "{d4}");
    assert!(d4 < d2, "{d2} {d4}");
}

#[test]
fn agrees_with_matrix_radiosity_with_occlusion() {
    let scene = common::aligned_room(true);
    let (d2, _) = worst_difference(&scene, 0.25, 2, VisibilitySampling::Centre);
    let (d4, shots) = worst_difference(&scene, 0.25, 4, VisibilitySampling::Centre);
    println!(
        "aligned room with block, centre visibility, {shots} shots: worst relative difference {d2:.2e} (2x2), \
         {d4:.2e} (4x4)"
    );
    assert!(d4 < 1e-4, "{d4}");
    assert!(d4 < d2, "{d2} {d4}");
}

#[test]
fn difference_from_matrix_radiosity_shrinks_with_quadrature_on_misaligned_meshes() {
    // Where element grids meet out of step (the ceiling's 0.2 pieces against 0.25 wall elements, the block's
    // sides standing inside floor elements), receiver quadrature is far from reciprocal and the symmetrised
    // matrix system differs from the shooting one by that quadrature error: it must shrink as the quadrature is
    // refined (slowly: the kernel is singular along the contact line inside the floor elements).
    let scene = common::closed_room(1.0);
    let (d2, _) = worst_difference(&scene, 0.2, 2, VisibilitySampling::Centre);
    let (d4, _) = worst_difference(&scene, 0.2, 4, VisibilitySampling::Centre);
    println!(
        "misaligned room with block: worst relative difference {d2:.2e} (2x2), {d4:.2e} (4x4)"
    );
    assert!(d4 < 0.5 * d2, "{d2} {d4}");
}

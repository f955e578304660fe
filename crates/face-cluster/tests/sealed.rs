//! Points no light reaches: a block standing on the floor of the closed unit room (radlab-testkit's
//! `sealed`), no bottom face, so the floor under it sees only the backs of the block's faces. No ray
//! leaving a point there reaches an emitter: its exact radiosity is 0 (the path tracer's too, with zero
//! variance). A face's irradiance field (Gouraud), its constant answer and a final gather all carry the lit
//! floor's light under the block unless the point itself is tested; floor points beside the block are
//! compared with the path tracer as well.

mod common;

use common::{params, solve};
use radlab_face_cluster::{FaceClusterSolver, FaceNode};
use radlab_hierarchical::NodeKind;
use radlab_method::Solution;
use radlab_pathtrace::{PointParams, SurfacePoint, estimate_points};
use radlab_testkit::sealed::SealedCase;
use radlab_visibility::Accel;

#[test]
fn points_under_a_block_answer_zero_and_points_beside_it_match_the_path_tracer() {
    let case = SealedCase::new(&|scene, pts| {
        let accel = Accel::new(scene);
        let pts: Vec<_> = pts
            .iter()
            .map(|&(f, p)| SurfacePoint::on_face(scene, f, p))
            .collect();
        let pt = PointParams {
            samples: 16384,
            ..PointParams::default()
        };
        let estimates = estimate_points(scene, &accel, &pts, &pt, 3);
        estimates.iter().map(|r| (r.mean, r.std_error)).collect()
    });
    let accel = Accel::new(&case.scene);
    let mut failures = Vec::new();
    // The final gather resolves the block's shadow beside it; Gouraud and constant answers smear it (issue
    // 45's shadows), so only their sealed points are judged.
    for reconstruction in ["gouraud", "constant", "final-gather"] {
        let mut s = FaceClusterSolver::new(
            &case.scene,
            &accel,
            params(&[("reconstruction", reconstruction)]),
            7,
        )
        .expect("solver");
        solve(&mut s);
        failures.extend(case.judge(
            reconstruction,
            &|f, p| s.radiosity_at(f, p),
            reconstruction == "final-gather",
        ));
    }
    assert!(failures.is_empty(), "{failures:?}");
}

/// An occluded furnace (radlab-testkit's `cornell_furnace`: the Cornell box closed by a front wall, every
/// surface at ρ = 0.5 and E = 1) has B = E/(1 − ρ) = 2 wherever light reaches, blocks or not, so the mean
/// radiosity of the walls', ceiling's and blocks' leaves (no contact seals any of them) must be 2. The floor's
/// leaves along the blocks' feet lie partly under them: held as area means and sent from their whole area,
/// they sent into the blocks' undersides the light their open parts reflect (Baum et al. 1991's leak), and
/// every other surface was darker for it, until the transport estimated their open shares. At the default
/// ε = 7e-5 the mean measured −0.50% without open shares, +0.04% with them (at 1e-4: −0.47%, −0.03%; the
/// method's signed error on the Cornell box was −1.03% without). The bound is the ±0.3% Cornell bias radlab's
/// defaults are held to (docs/defaults.md).
#[test]
fn an_occluded_furnace_keeps_its_light() {
    let scene = radlab_testkit::cornell_furnace(0.5, 1.0);
    let accel = Accel::new(&scene);
    let mut s = FaceClusterSolver::new(&scene, &accel, params(&[]), 1).expect("solver");
    solve(&mut s);
    // Off the floor: no contact seals any part of the walls, the ceiling or the blocks.
    let off_floor = |n: &FaceNode<'_>| n.face().is_some_and(|f| scene.faces[f].centroid.y > 0.0);
    let mean = s.engine().open_mean_radiosity(off_floor).x;
    let bias = mean / 2.0 - 1.0;
    assert!(
        bias.abs() <= 3e-3,
        "the mean radiosity off the floor {mean:.5} against 2: bias {:+.3}%",
        100.0 * bias
    );
}

//! Open shares at a contact: a block standing on the floor of the closed unit room (radlab-testkit's
//! `sealed`), no bottom face, so the floor under it sees only the backs of the block's faces. No ray
//! leaving a point there reaches an emitter: its exact radiosity is 0 (the path tracer's too, with zero
//! variance). Floor points beside the block are compared with the path tracer within its standard error and
//! the method's own discretisation error there.

use radlab_method::{Solution, Solver, Step};
use radlab_pathtrace::{PointParams, SurfacePoint, estimate_points};
use radlab_scene::{FaceId, Scene};
use radlab_testkit::sealed::{beside_points, block_on_floor, sealed_points};
use radlab_visibility::Accel;
use radlab_wavelet::{Basis, WaveletParams, WaveletReconstruction, WaveletSolver};

fn solve<'a>(scene: &'a Scene, accel: &'a Accel, params: WaveletParams) -> WaveletSolver<'a> {
    let mut s = WaveletSolver::new(scene, accel, params, 7).expect("solver");
    for _ in 0..10_000 {
        if s.step().expect("step") != Step::Continue {
            return s;
        }
    }
    panic!("no convergence");
}

fn surface(scene: &Scene, pts: &[(FaceId, glam::DVec3)]) -> Vec<SurfacePoint> {
    pts.iter()
        .map(|&(face, point)| SurfacePoint {
            face,
            point,
            normal: scene.faces[face].normal,
        })
        .collect()
}

#[test]
fn points_under_a_block_answer_zero_and_points_beside_it_match_the_path_tracer() {
    let scene = block_on_floor();
    let accel = Accel::new(&scene);
    let (sealed, beside) = (sealed_points(&scene), beside_points(&scene));
    let pt = PointParams {
        samples: 16384,
        ..PointParams::default()
    };
    let reference = estimate_points(&scene, &accel, &surface(&scene, &beside), &pt, 3);
    let dark = estimate_points(&scene, &accel, &surface(&scene, &sealed), &pt, 3);
    for d in &dark {
        assert_eq!(
            d.mean.max_element(),
            0.0,
            "the path tracer lights a sealed point"
        );
    }
    let lit: f64 = reference.iter().map(|r| r.mean.element_sum()).sum::<f64>() / 3.0;
    let lit = lit / reference.len() as f64;
    let mut failures = Vec::new();
    for (basis, reconstruction) in [
        (Basis::M2, WaveletReconstruction::Basis),
        (Basis::Haar, WaveletReconstruction::Basis),
        (Basis::M2, WaveletReconstruction::Smoothed),
        (Basis::M2, WaveletReconstruction::FinalGather),
    ] {
        let params = WaveletParams {
            basis,
            reconstruction,
            ..WaveletParams::default()
        };
        let s = solve(&scene, &accel, params);
        let worst_sealed = sealed
            .iter()
            .map(|&(f, p)| s.radiosity_at(f, p).max_element())
            .fold(0.0, f64::max);
        let (mut diff, mut sum, mut se) = (0.0, 0.0, 0.0);
        for (&(f, p), r) in beside.iter().zip(&reference) {
            diff += (s.radiosity_at(f, p) - r.mean).abs().element_sum();
            sum += r.mean.element_sum();
            se += r.std_error.element_sum();
        }
        eprintln!(
            "{basis:?} {reconstruction:?}: worst sealed point {worst_sealed:.4} (beside mean {lit:.4}); \
             beside: relative L1 {:.4}, reference standard error {:.5}",
            diff / sum,
            se / sum
        );
        // A final gather resolves the block's shadow beside it (the leaves' own answers smear it, at M2
        // by 12% L1 here): its difference must be the reference's noise, E|N(0, σ)| ≈ 0.8 σ a point, within
        // twice the summed standard errors.
        if reconstruction == WaveletReconstruction::FinalGather && diff > 2.0 * se {
            failures.push(format!(
                "final gather beside the block: L1 {diff} > 2 × {se}"
            ));
        }
        if worst_sealed > 1e-3 * lit {
            failures.push(format!(
                "{basis:?} {reconstruction:?}: a sealed point answers {worst_sealed}"
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}

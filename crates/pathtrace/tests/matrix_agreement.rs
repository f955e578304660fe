//! Cross-checks against radlab-matrix on a closed, coloured, non-uniformly lit box (common::lit_box): every
//! wall 2 × 2 input quads, one ceiling quad the light. The box is convex, so every pair of points sees each
//! other and the matrix can use exact (unoccluded) visibility: its only error is the receiver quadrature of
//! the form factors (and, for comparisons with the continuous solution, the mesh). Each method's error is
//! estimated, never chosen: the Monte Carlo standard errors by the methods themselves, the matrix's by
//! repeating it at a coarser setting (quadrature 4 vs 8; element size 1/8 vs 1/16) and taking the difference,
//! which bounds the finer solution's error when it converges (it shrinks at least linearly).
//! Tolerance: 4 combined standard errors, √(se_mc² + δ_matrix²) (plus the matrix's iteration tolerance), for
//! single comparisons; where hundreds of elements are compared at once, the family-wise threshold is stated
//! beside the test, and the mean of z² (1 under agreement) is checked as well, which is what a small bias
//! common to many elements would move.

mod common;

use common::*;
use radlab_matrix::{Iteration, MatrixParams, MatrixSolver, VisibilitySampling};
use radlab_method::{Solver, Step};
use radlab_pathtrace::*;
use radlab_scene::{Rgb, Scene};
use radlab_visibility::Accel;

const TOLERANCE: f64 = 1e-7;

fn matrix(scene: &Scene, accel: &Accel, element_size: f64, quadrature: u32) -> Vec<Rgb> {
    let params = MatrixParams {
        element_size: Some(element_size),
        iteration: Iteration::ConjugateGradient,
        tolerance: TOLERANCE,
        visibility: VisibilitySampling::Unoccluded,
        quadrature,
        ..MatrixParams::default()
    };
    let mut s = MatrixSolver::new(scene, accel, params, 1).expect("matrix solver");
    while s.step().expect("matrix step") == Step::Continue {}
    assert!(!s.hit_iteration_cap());
    s.element_radiosity().to_vec()
}

#[test]
fn mesh_monte_carlo_radiosity_agrees_with_matrix_radiosity_on_the_same_mesh() {
    let scene = lit_box();
    let accel = Accel::new(&scene);
    let h = 0.125; // 384 elements
    let fine = matrix(&scene, &accel, h, 8);
    let coarse = matrix(&scene, &accel, h, 4);
    for method in [McMethod::RandomWalk, McMethod::StochasticJacobi] {
        // 64 steps of 10,000 particles: each element's standard error comes from 64 independent step
        // estimates (a t-distribution with 63 degrees of freedom, or heavier-tailed where an element receives
        // few particles per step and its step estimates are skewed). 1,104 comparisons (368 non-emitting
        // elements × 3 channels): a family-wise false-alarm rate of 1 % needs |t| ≤ 4.9 per comparison
        // (Bonferroni), hence 5. The sharp test for a bias is the mean of z² over all comparisons: 63/61 under
        // agreement, with a spread of about 0.05–0.08 (the channels are correlated), so [0.75, 1.35] is a ±4σ
        // band; a bias of a third of a standard error on every element would leave it.
        let p = mc_params(h, 10_000, 64, method);
        let mut s = McRadiositySolver::new(&scene, &accel, p, 2024).expect("mc solver");
        while s.step().expect("mc step") == Step::Continue {}
        assert_eq!(s.mesh().len(), fine.len());
        let b = s.element_radiosity();
        let se = s.element_std_error().expect("se");
        let mut worst: f64 = 0.0;
        let mut sum_z2 = 0.0;
        let mut compared = 0;
        for j in 0..b.len() {
            if scene
                .material(s.mesh().elements[j].face as usize)
                .is_emitter()
            {
                assert_eq!(b[j], fine[j], "emitters (ρ = 0): B = E in both");
                continue;
            }
            for c in 0..3 {
                compared += 1;
                let delta = (fine[j][c] - coarse[j][c]).abs() + TOLERANCE * fine[j][c];
                let combined = (se[j][c].powi(2) + delta.powi(2)).sqrt();
                let z = (b[j][c] - fine[j][c]) / combined;
                worst = worst.max(z.abs());
                sum_z2 += z * z;
                assert!(
                    z.abs() <= 5.0,
                    "{method:?} element {j} channel {c}: MC {} ± {} vs matrix {} (δ {delta})",
                    b[j][c],
                    se[j][c],
                    fine[j][c]
                );
                // Power: the comparison resolves a few per cent on every element.
                assert!(
                    combined < 0.05 * fine[j][c],
                    "{method:?} element {j}: combined error {combined}"
                );
            }
        }
        let mean_z2 = sum_z2 / compared as f64;
        eprintln!("{method:?}: worst |z| = {worst:.2}, mean z² = {mean_z2:.3}");
        assert!(
            (0.75..=1.35).contains(&mean_z2),
            "{method:?}: mean z² = {mean_z2}"
        );
    }
}

#[test]
fn point_estimates_agree_with_matrix_radiosity_face_by_face() {
    // Face averages of B. The point estimator at 4,096 independent uniform points per face, 2 paths each: the
    // mean over the points is an unbiased estimate of the face's average of B, and the spread of the point
    // means (path noise and the variation of B over the face together) gives its standard error. Against the
    // matrix's area-weighted face average at h = 1/16, whose error is estimated by its change from h = 1/8.
    let scene = lit_box();
    let accel = Accel::new(&scene);
    let coarse = matrix(&scene, &accel, 0.125, 4);
    let fine = matrix(&scene, &accel, 0.0625, 4);
    let face_average = |b: &[Rgb], h: f64| -> Vec<Rgb> {
        let mesh = radlab_answer::ElementMesh::new(&scene, h);
        (0..scene.faces.len())
            .map(|f| {
                let r = mesh.elements_of(f);
                let a: f64 = r.clone().map(|e| mesh.elements[e].area).sum();
                r.map(|e| b[e] * mesh.elements[e].area).sum::<Rgb>() / a
            })
            .collect()
    };
    let (avg_c, avg_f) = (face_average(&coarse, 0.125), face_average(&fine, 0.0625));
    let per_face = 4096;
    let lit: Vec<usize> = (0..scene.faces.len())
        .filter(|&f| !scene.material(f).is_emitter())
        .collect();
    let mut rng = radlab_scene::sampling::rng(5, 0);
    let mut uniform = || radlab_scene::sampling::uniform(&mut rng);
    let pts: Vec<SurfacePoint> = lit
        .iter()
        .flat_map(|&f| std::iter::repeat_n(f, per_face))
        .map(|f| SurfacePoint {
            face: f,
            point: scene.polygon(f).sample_uniform(uniform(), uniform()),
            normal: scene.faces[f].normal,
        })
        .collect();
    let params = PointParams {
        samples: 2,
        ..Default::default()
    };
    let est = estimate_points(&scene, &accel, &pts, &params, 11);
    let mut sum_z2 = 0.0;
    for (k, &f) in lit.iter().enumerate() {
        let means: Vec<Rgb> = est[k * per_face..(k + 1) * per_face]
            .iter()
            .map(|e| e.mean)
            .collect();
        let n = means.len() as f64;
        let mean = means.iter().copied().sum::<Rgb>() / n;
        let var = means.iter().map(|m| (*m - mean) * (*m - mean)).sum::<Rgb>() / (n - 1.0);
        let se = (var / n).sqrt();
        for c in 0..3 {
            let delta = (avg_f[f][c] - avg_c[f][c]).abs() + TOLERANCE * avg_f[f][c];
            let combined = (se[c].powi(2) + delta.powi(2)).sqrt();
            let z = (mean[c] - avg_f[f][c]) / combined;
            sum_z2 += z * z;
            assert!(
                z.abs() <= 4.0,
                "face {f} channel {c}: points {} ± {} vs matrix {} (δ {delta})",
                mean[c],
                se[c],
                avg_f[f][c]
            );
            assert!(
                combined < 0.05 * avg_f[f][c],
                "face {f}: combined error {combined} too large to be a test"
            );
        }
    }
    eprintln!(
        "point vs matrix: mean z² = {:.3} over {} comparisons",
        sum_z2 / (3 * lit.len()) as f64,
        3 * lit.len()
    );
}

//! Bidirectional path tracing against answers nobody here chose: the furnace B = E/(1 − ρ) (closed cube,
//! uniform ρ and E), the path tracer's estimate on the Cornell box (an independent estimator: the two means must
//! agree within their standard errors), rays counted through the shared engine, determinism across thread
//! counts, and parameter errors that name the key. The weights' sum to 1 over strategies is a unit test of
//! mis_weight.rs.

use radlab_bdpt::{BdptParams, BdptSolver, Heuristic};
use radlab_method::{MethodParams, Solution, Solver, Step, evaluation_points};
use radlab_pathtrace::{PointEstimate, PointParams, SurfacePoint, estimate_points, surface_points};
use radlab_scene::glam::DVec3;
use radlab_scene::glam::dvec3;
use radlab_scene::{Scene, SceneBuilder, builtin};
use radlab_testkit::{add_box, hollow_box, material};
use radlab_visibility::Accel;

fn run(
    scene: &Scene,
    accel: &Accel,
    params: &BdptParams,
    seed: u64,
    pts: &[SurfacePoint],
) -> Vec<PointEstimate> {
    let mut s = BdptSolver::new(scene, accel, params.clone(), seed, pts.to_vec()).expect("valid");
    while s.step().expect("step") != Step::Converged {}
    s.estimates()
}

fn params(samples: u32, heuristic: Heuristic) -> BdptParams {
    BdptParams {
        samples,
        heuristic,
        ..BdptParams::default()
    }
}

/// z-scores of `a` against `b` per point and channel: (a − b)/√(se_a² + se_b²).
fn z_scores(a: &[PointEstimate], b: &[PointEstimate]) -> Vec<f64> {
    a.iter()
        .zip(b)
        .flat_map(|(a, b)| {
            (0..3).map(move |c| {
                (a.mean[c] - b.mean[c]) / (a.std_error[c].powi(2) + b.std_error[c].powi(2)).sqrt()
            })
        })
        .collect()
}

#[test]
fn furnace_gives_e_over_one_minus_rho() {
    for rho in [0.3, 0.8] {
        let scene = builtin(&format!(
            "furnace-cube?reflectance={rho}&emission=1&tessellation=2"
        ))
        .expect("scene");
        let accel = Accel::new(&scene);
        let pts = surface_points(&evaluation_points(&scene, 8, 3));
        let exact = 1.0 / (1.0 - rho);
        for h in [Heuristic::Balance, Heuristic::Power] {
            let est = run(&scene, &accel, &params(512, h), 1, &pts);
            for e in &est {
                let z = (e.mean.x - exact) / e.std_error.x;
                // 4.5 standard errors: two-sided p ≈ 7e-6 per value, 32 values.
                assert!(
                    z.abs() < 4.5,
                    "rho {rho} {h:?}: {} ± {}",
                    e.mean.x,
                    e.std_error.x
                );
            }
            // The mean over the (independent) points, its standard error below 1 % so the test can fail.
            let n = est.len() as f64;
            let m = est.iter().map(|e| e.mean.x).sum::<f64>() / n;
            let se = est
                .iter()
                .map(|e| e.std_error.x.powi(2))
                .sum::<f64>()
                .sqrt()
                / n;
            eprintln!("rho {rho} {h:?}: {m:.5} ± {se:.5} vs {exact:.5}");
            assert!((m - exact).abs() < 4.0 * se, "rho {rho} {h:?}: {m} ± {se}");
            assert!(se < 0.01 * exact, "rho {rho} {h:?}: se {se}");
        }
    }
}

#[test]
fn mean_equals_the_path_tracers_on_the_cornell_box() {
    let scene = builtin("cornell").expect("scene");
    let accel = Accel::new(&scene);
    let pts = surface_points(&evaluation_points(&scene, 6, 11));
    let reference = estimate_points(
        &scene,
        &accel,
        &pts,
        &PointParams {
            samples: 4096,
            ..PointParams::default()
        },
        99,
    );
    for h in [Heuristic::Balance, Heuristic::Power] {
        let est = run(&scene, &accel, &params(2048, h), 5, &pts);
        let z = z_scores(&est, &reference);
        let mean_z2 = z.iter().map(|z| z * z).sum::<f64>() / z.len() as f64;
        eprintln!("{h:?}: z = {z:.2?}, mean z² = {mean_z2:.3}");
        // Independent unbiased estimators: each z is about N(0, 1). Bound 4.5 on each of 18 (two-sided
        // p ≈ 1.2e-4 for any false failure) and 3 on the mean of z² (its expectation is 1).
        assert!(z.iter().all(|z| z.abs() < 4.5), "{h:?}: {z:?}");
        assert!(mean_z2 < 3.0, "{h:?}: mean z² {mean_z2}");
        // Not vacuous: the standard errors are small against the values.
        for (e, r) in est.iter().zip(&reference) {
            assert!(e.std_error.x < 0.05 * r.mean.x.max(1e-3), "{e:?} vs {r:?}");
        }
    }
}

/// A 2 × 1 × 1 room split at x = 0.9 … 1 by a partition 0.8 high (a sealed box); a lamp at x = 0.3 faces the
/// end wall x = 0, so no point beyond the partition sees it: that half is lit only over the partition, by
/// paths of two bounces or more.
fn partition_room() -> Scene {
    let mut b = SceneBuilder::new("partition room");
    let wall = material(&mut b, "wall", 0.6, 0.0);
    add_box(&mut b, DVec3::ZERO, dvec3(2.0, 1.0, 1.0), 2, wall, false);
    hollow_box(&mut b, dvec3(0.9, 0.0, 0.0), dvec3(1.0, 0.8, 1.0));
    let lamp = material(&mut b, "lamp", 0.0, 20.0);
    let p = [
        dvec3(0.3, 0.3, 0.3),
        dvec3(0.3, 0.3, 0.7),
        dvec3(0.3, 0.7, 0.7),
        dvec3(0.3, 0.7, 0.3),
    ];
    b.add_polygon_points(&p, lamp, "lamp").expect("quad");
    b.build().expect("scene")
}

#[test]
fn mean_equals_the_path_tracers_where_light_arrives_only_indirectly() {
    let scene = partition_room();
    let accel = Accel::new(&scene);
    let lamp = scene.faces.len() - 1;
    assert!(scene.faces[lamp].normal.x < -0.99, "the lamp faces -x");
    let pts: Vec<SurfacePoint> = surface_points(&evaluation_points(&scene, 64, 3))
        .into_iter()
        .filter(|p| p.point.x > 1.05)
        .take(6)
        .collect();
    assert_eq!(pts.len(), 6);
    let r0 = accel.rays_cast();
    let reference = estimate_points(
        &scene,
        &accel,
        &pts,
        &PointParams {
            samples: 16384,
            ..PointParams::default()
        },
        99,
    );
    let pt_rays = accel.rays_cast() - r0;
    let r0 = accel.rays_cast();
    let est = run(&scene, &accel, &params(8192, Heuristic::Power), 5, &pts);
    let bd_rays = accel.rays_cast() - r0;
    let z = z_scores(&est, &reference);
    let mean_z2 = z.iter().map(|z| z * z).sum::<f64>() / z.len() as f64;
    // Relative variance per ray of each (the machine-independent half of variance per unit time).
    let eff = |e: &[PointEstimate], rays: u64| {
        e.iter()
            .map(|e| (e.std_error.x / e.mean.x).powi(2))
            .sum::<f64>()
            / e.len() as f64
            * rays as f64
    };
    eprintln!(
        "indirect: z = {z:.2?}, mean z² = {mean_z2:.3}; relative variance × rays: path tracing {:.3e} \
         ({pt_rays} rays), bdpt {:.3e} ({bd_rays} rays)",
        eff(&reference, pt_rays),
        eff(&est, bd_rays)
    );
    // The same bounds as on the Cornell box: every z-score below 4.5, mean z² below 3 (the scene is grey, so
    // the three channels of a point agree and there are 6 independent z-scores).
    assert!(z.iter().all(|z| z.abs() < 4.5), "{z:?}");
    assert!(mean_z2 < 3.0, "mean z² {mean_z2}");
    // Not vacuous: every point lit (indirectly) and its standard error small against its value.
    for (e, r) in est.iter().zip(&reference) {
        assert!(
            e.mean.x > 0.0 && e.std_error.x < 0.1 * e.mean.x,
            "{e:?} vs {r:?}"
        );
    }
}

#[test]
fn rays_are_counted_and_points_off_the_set_are_reproducible() {
    let scene = builtin("cornell").expect("scene");
    let accel = Accel::new(&scene);
    let pts = surface_points(&evaluation_points(&scene, 4, 2));
    let r0 = accel.rays_cast();
    let mut s = BdptSolver::new(&scene, &accel, params(64, Heuristic::Power), 1, pts.clone())
        .expect("valid");
    while s.step().expect("step") != Step::Converged {}
    let stats = s.stats();
    assert_eq!(stats.rays, accel.rays_cast() - r0);
    // At least one ray per sample (the eye subpath's first bounce) and far more than that.
    assert!(stats.rays > 4 * 64, "{}", stats.rays);
    assert!(stats.bytes > 0);
    // A query point answers its running mean; another point a fresh, reproducible estimate.
    let p = pts[0];
    assert_eq!(
        s.radiosity_at(p.face, p.point),
        s.estimates()[0].mean,
        "query point"
    );
    let off = evaluation_points(&scene, 1, 77)[0];
    let a = s.radiosity_at(off.face, off.point);
    let b = s.radiosity_at(off.face, off.point);
    assert_eq!(a, b);
    assert!(a.is_finite());
    assert!(s.radiosity_at(scene.faces.len(), p.point).x.is_nan());
}

#[test]
fn deterministic_for_a_seed_and_any_thread_count() {
    let scene = builtin("cornell").expect("scene");
    let accel = Accel::new(&scene);
    let pts = surface_points(&evaluation_points(&scene, 8, 4));
    let bits = |v: &[PointEstimate]| -> Vec<[u64; 3]> {
        v.iter()
            .map(|e| e.mean.to_array().map(f64::to_bits))
            .collect()
    };
    let go = |threads: usize, seed: u64| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool")
            .install(|| run(&scene, &accel, &params(300, Heuristic::Power), seed, &pts))
    };
    let a = go(1, 3);
    assert_eq!(bits(&a), bits(&go(2, 3)), "1 vs 2 threads");
    assert_ne!(bits(&a), bits(&go(2, 4)), "another seed");
}

#[test]
fn parameters_name_their_key() {
    for (k, v) in [
        ("samples", "0"),
        ("initial_samples", "0"),
        ("max_depth", "0"),
        ("heuristic", "maximum"),
        ("max_light_vertices", "0"),
        ("initial_samples", "5000"),
    ] {
        let err = BdptParams::from_pairs(&[(k.into(), v.into())])
            .expect_err(k)
            .to_string();
        assert!(err.contains(k), "{k}={v}: {err}");
    }
    let err = BdptParams::from_pairs(&[("sample".into(), "3".into())])
        .expect_err("unknown key")
        .to_string();
    assert!(err.contains("sample"), "{err}");
    let p = BdptParams::from_pairs(&[("heuristic".into(), "balance".into())]).expect("valid");
    assert_eq!(p.heuristic, Heuristic::Balance);
    // A point off the scene's faces is refused, naming `points`.
    let scene = builtin("cornell").expect("scene");
    let accel = Accel::new(&scene);
    let bad = vec![SurfacePoint {
        face: scene.faces.len(),
        point: DVec3::ZERO,
        normal: DVec3::Z,
    }];
    let err = BdptSolver::new(&scene, &accel, BdptParams::default(), 1, bad)
        .expect_err("bad point")
        .to_string();
    assert!(err.contains("points"), "{err}");
}

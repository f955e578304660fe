//! The photon map against answers nobody here chose: the furnace B = E/(1 − ρ), the path-traced reference
//! on the Cornell box, no light through a thin wall between two rooms, determinism across thread counts, and
//! parameter errors that name the key.
//!
//! The density estimate is biased (a flat disk of photons assumed wholly on the surface; edges and corners see
//! part of it), and nothing here bounds that bias in closed form, so the tests check what theory does
//! guarantee: the progressive mode's bias shrinks as passes grow (consistency), and room B behind a wall gets
//! exactly nothing. Agreement with the path tracer and the furnace is checked against the project's error
//! targets (1 % in a furnace, as the conformance suite asks of every method; 3 % on the Cornell box, the
//! issue's coarse target), with the measured bias printed.

use radlab_method::{MethodParams, Solver, Step, evaluation_points};
use radlab_pathtrace::{PointParams, SurfacePoint, estimate_points, surface_points};
use radlab_photon_map::{PhotonMapParams, PhotonMapSolver, PhotonMode};
use radlab_scene::glam::dvec3;
use radlab_scene::{Rgb, Scene, builtin};
use radlab_testkit::{ChannelMeans, mean_se, two_rooms};
use radlab_visibility::Accel;

fn run(
    scene: &Scene,
    accel: &Accel,
    params: &PhotonMapParams,
    seed: u64,
    pts: &[SurfacePoint],
) -> Vec<Rgb> {
    let mut s =
        PhotonMapSolver::new(scene, accel, params.clone(), seed, pts.to_vec()).expect("valid");
    let mut steps = 0;
    while s.step().expect("step") != Step::Converged {
        steps += 1;
        assert!(steps < 1000, "no convergence");
    }
    pts.iter()
        .map(|p| s.solution().radiosity_at(p.face, p.point))
        .collect()
}

fn final_gather(photons: u64) -> PhotonMapParams {
    PhotonMapParams {
        photons,
        gather_samples: 32,
        direct_samples: 8,
        ..PhotonMapParams::default()
    }
}

fn progressive(photons: u64, passes: u32) -> PhotonMapParams {
    PhotonMapParams {
        mode: PhotonMode::Progressive,
        photons,
        passes,
        direct_samples: 8,
        ..PhotonMapParams::default()
    }
}

/// Mean over the points of each of `seeds` runs: (mean of runs, its standard error).
fn furnace_mean(scene: &Scene, params: &PhotonMapParams, seeds: u64) -> (f64, f64) {
    let accel = Accel::new(scene);
    let pts = surface_points(&evaluation_points(scene, 200, 7));
    let means: Vec<f64> = (1..=seeds)
        .map(|seed| {
            let b = run(scene, &accel, params, seed, &pts);
            b.iter().map(|b| b.x).sum::<f64>() / b.len() as f64
        })
        .collect();
    mean_se(&means)
}

#[test]
fn furnace_within_one_percent_and_progressive_is_consistent() {
    let rho = 0.5;
    let scene = builtin(&format!(
        "furnace-cube?reflectance={rho}&emission=1&tessellation=3"
    ))
    .expect("scene");
    let exact = 1.0 / (1.0 - rho);
    let (m, se) = furnace_mean(&scene, &final_gather(50_000), 4);
    eprintln!(
        "final gather: {m} ± {se} vs {exact}: {:+.4}",
        m / exact - 1.0
    );
    assert!(
        (m - exact).abs() <= 0.01 * exact + 4.0 * se,
        "final gather {m} ± {se}"
    );
    // Progressive: from a large initial radius (0.1 of the diagonal, so the edge bias is large at first),
    // the bias at 2 passes shrinks by 64 passes (radius reduction; Hachisuka et al. 2008).
    let wide = |passes| PhotonMapParams {
        initial_radius: 0.1,
        ..progressive(10_000, passes)
    };
    let (m2, se2) = furnace_mean(&scene, &wide(2), 4);
    let (m32, se32) = furnace_mean(&scene, &wide(64), 4);
    let (e2, e32) = ((m2 - exact).abs(), (m32 - exact).abs());
    eprintln!("progressive: 2 passes {m2} ± {se2}, 64 passes {m32} ± {se32}, exact {exact}");
    assert!(
        e2 - e32 > 3.0 * (se2 * se2 + se32 * se32).sqrt(),
        "no convergence: {e2} -> {e32}"
    );
}

#[test]
fn agrees_with_the_path_tracer_on_the_cornell_box() {
    let scene = builtin("cornell").expect("scene");
    let accel = Accel::new(&scene);
    let pts = surface_points(&evaluation_points(&scene, 128, 3));
    let reference = estimate_points(
        &scene,
        &accel,
        &pts,
        &PointParams {
            samples: 1024,
            ..PointParams::default()
        },
        99,
    );
    let reference: Vec<(Rgb, Rgb)> = reference.iter().map(|e| (e.mean, e.std_error)).collect();
    for (name, params) in [
        ("final gather", final_gather(50_000)),
        ("progressive", progressive(20_000, 8)),
    ] {
        let runs: Vec<Vec<Rgb>> = (1..=3)
            .map(|seed| run(&scene, &accel, &params, seed, &pts))
            .collect();
        for c in 0..3 {
            let m = ChannelMeans::new(&reference, &runs, c);
            eprintln!(
                "{name} channel {c}: {:.5} ± {:.5} vs path tracing {:.5} ± {:.5}: {:+.4}",
                m.mean,
                m.se,
                m.reference,
                m.reference_se,
                m.mean / m.reference - 1.0
            );
            assert!(m.agrees(0.03, 4.0), "{name} channel {c}: {m:?}");
        }
    }
}

#[test]
fn no_light_leaks_through_a_thin_wall() {
    let scene = two_rooms(1e-3);
    let accel = Accel::new(&scene);
    // Points on the shared floor and ceiling on both sides of the wall, close to it.
    let mut pts = Vec::new();
    for f in [0usize, 1] {
        for i in 0..20 {
            for j in 0..10 {
                let (y, dx) = ((i as f64 + 0.5) / 20.0, 0.001 + 0.003 * j as f64);
                for x in [1.0 - 5e-4 - dx, 1.0 + 5e-4 + dx] {
                    pts.push(SurfacePoint {
                        face: f,
                        point: dvec3(x, y, f as f64),
                        normal: scene.faces[f].normal,
                    });
                }
            }
        }
    }
    let in_b = |p: &SurfacePoint| p.point.x > 1.0;
    for mode in [PhotonMode::FinalGather, PhotonMode::Progressive] {
        let params = PhotonMapParams {
            mode,
            photons: 20_000,
            passes: 2,
            gather_samples: 16,
            direct_samples: 4,
            // A large radius so photons near the wall reach across it.
            initial_radius: 0.02,
            ..PhotonMapParams::default()
        };
        let dark = |b: &[Rgb]| {
            pts.iter()
                .zip(b)
                .filter(|(p, _)| in_b(p))
                .map(|(_, b)| b.max_element())
                .fold(0.0, f64::max)
        };
        let lit = |b: &[Rgb]| {
            pts.iter()
                .zip(b)
                .filter(|(p, _)| !in_b(p))
                .map(|(_, b)| b.x)
                .fold(0.0, f64::max)
        };
        let b = run(&scene, &accel, &params, 1, &pts);
        assert!(lit(&b) > 0.1, "{mode:?}: room A lit {}", lit(&b));
        assert_eq!(dark(&b), 0.0, "{mode:?}: light leaked into room B");
        let b = run(
            &scene,
            &accel,
            &PhotonMapParams {
                leak_test: false,
                ..params
            },
            1,
            &pts,
        );
        assert!(
            dark(&b) > 0.0,
            "{mode:?}: expected a leak without the leak test"
        );
    }
}

#[test]
fn deterministic_for_a_seed_and_any_thread_count() {
    let scene = builtin("cornell").expect("scene");
    let accel = Accel::new(&scene);
    let pts = surface_points(&evaluation_points(&scene, 64, 4));
    let bits =
        |v: &[Rgb]| -> Vec<[u64; 3]> { v.iter().map(|b| b.to_array().map(f64::to_bits)).collect() };
    for params in [final_gather(20_000), progressive(5_000, 3)] {
        let go = |threads: usize, seed: u64| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool")
                .install(|| run(&scene, &accel, &params, seed, &pts))
        };
        let a = go(1, 3);
        assert_eq!(bits(&a), bits(&go(2, 3)), "1 vs 2 threads");
        assert_ne!(bits(&a), bits(&go(2, 4)), "another seed");
    }
}

#[test]
fn parameters_name_their_key() {
    for (k, v) in [
        ("mode", "sideways"),
        ("photons", "0"),
        ("nearest", "0"),
        ("filter", "gaussian"),
        ("gather_samples", "0"),
        ("precompute_stride", "0"),
        ("direct_samples", "0"),
        ("passes", "0"),
        ("alpha", "1"),
        ("initial_radius", "-1"),
        ("max_depth", "0"),
    ] {
        let err = PhotonMapParams::from_pairs(&[(k.into(), v.into())])
            .expect_err(k)
            .to_string();
        assert!(err.contains(k), "{k}={v}: {err}");
    }
    let p = PhotonMapParams::from_pairs(&[("mode".into(), "progressive".into())]).expect("valid");
    assert_eq!(p.mode, PhotonMode::Progressive);
}

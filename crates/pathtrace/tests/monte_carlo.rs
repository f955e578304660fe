//! Cross-module tests of radlab-pathtrace against answers nobody here chose: the furnace B = E/(1 − ρ), the
//! point-to-polygon closed form for unoccluded direct light, the N^(−1/2) convergence law, and determinism
//! across thread counts. Tolerances are k standard errors as estimated by the methods themselves; each test
//! also bounds the standard error so that it has the power to see a real error.

mod common;

use common::*;
use glam::{DVec3, dvec3};
use radlab_kernels::form_factor::point_polygon;
use radlab_method::{MethodParams, Solver, Step, evaluation_points};
use radlab_pathtrace::*;
use radlab_scene::{Camera, Material, Rgb, SceneBuilder, builtin};
use radlab_visibility::Accel;

fn params(samples: u32, direct: DirectSampling) -> PointParams {
    PointParams {
        samples,
        direct,
        ..PointParams::default()
    }
}

#[test]
fn furnace_cube_point_estimates_match_e_over_one_minus_rho() {
    // (ρ, samples): higher ρ means longer paths (mean 1/(1 − ρ) vertices), so fewer samples.
    for (rho, samples) in [
        (0.0, 16),
        (0.3, 512),
        (0.7, 512),
        (0.9, 512),
        (0.99, 256),
        (0.999, 192),
    ] {
        let scene = builtin(&format!(
            "furnace-cube?reflectance={rho}&emission=1&tessellation=3"
        ))
        .expect("scene");
        let accel = Accel::new(&scene);
        let pts = spread_points(&scene, 5, 11);
        let est = estimate_points(
            &scene,
            &accel,
            &pts,
            &params(samples, DirectSampling::Mis),
            42,
        );
        let exact = Rgb::splat(1.0 / (1.0 - rho));
        for (p, e) in pts.iter().zip(&est) {
            assert_within(
                e,
                exact,
                4.0,
                &format!("furnace cube rho={rho} at {:?}", p.point),
            );
            if rho == 0.0 {
                assert_eq!(e.mean, Rgb::ONE, "rho = 0: B = E exactly");
                assert_eq!(e.std_error, Rgb::ZERO);
            } else {
                // The test has power, and the variance is what theory says: in a furnace a path's value is
                // about E × its number of vertices, geometric with relative spread √ρ ≤ 1, so the relative
                // standard error is about 1/√samples (6–7 % at 192–256 samples: a 30 % bias shows).
                assert!(
                    e.std_error.x < 1.5 / (samples as f64).sqrt() * exact.x,
                    "rho={rho}: se {:?}",
                    e.std_error
                );
            }
        }
        // Pooled over the points (same exact value everywhere): a sharper check.
        let n = est.len() as f64;
        let mean = est.iter().map(|e| e.mean.x).sum::<f64>() / n;
        let se = (est.iter().map(|e| e.std_error.x.powi(2)).sum::<f64>()).sqrt() / n;
        assert!(
            (mean - exact.x).abs() <= 4.0 * se + 1e-12,
            "pooled rho={rho}: {mean} ± {se} vs {}",
            exact.x
        );
    }
}

#[test]
fn coloured_furnace_keeps_channels_apart() {
    // Different ρ per channel: Russian roulette follows the largest, every channel must stay unbiased.
    let scene = builtin("furnace-cube?reflectance=0.2,0.6,0.95&emission=1,2,0.5&tessellation=2")
        .expect("scene");
    let accel = Accel::new(&scene);
    let pts = spread_points(&scene, 4, 5);
    let est = estimate_points(&scene, &accel, &pts, &params(768, DirectSampling::Mis), 3);
    let exact = Rgb::new(1.0 / 0.8, 2.0 / 0.4, 0.5 / 0.05);
    for e in &est {
        assert_within(e, exact, 4.0, "coloured furnace");
        assert!(
            (e.std_error / exact).max_element() < 0.05,
            "{:?}",
            e.std_error
        );
    }
}

#[test]
fn furnace_sphere_point_estimates_match_e_over_one_minus_rho() {
    for (rho, samples) in [(0.5, 512), (0.9, 512), (0.999, 192)] {
        let scene = furnace_icosphere(rho, 2.0, 2);
        let accel = Accel::new(&scene);
        let pts = spread_points(&scene, 5, 17);
        let est = estimate_points(
            &scene,
            &accel,
            &pts,
            &params(samples, DirectSampling::Mis),
            9,
        );
        let exact = Rgb::splat(2.0 / (1.0 - rho));
        for (p, e) in pts.iter().zip(&est) {
            assert_within(
                e,
                exact,
                4.0,
                &format!("furnace sphere rho={rho} at {:?}", p.point),
            );
            assert!(
                e.std_error.x < 1.5 / (samples as f64).sqrt() * exact.x,
                "rho={rho}: se {:?}",
                e.std_error
            );
        }
    }
}

/// An open scene of a receiver and one emitter (ρ = 0): B = ρ E F_{dx→emitter} exactly. Checks every strategy in `strategies` at 24 receiver points within 4 standard errors of the closed form,
/// and that the test has power: with 2048 samples, MIS and next-event estimation must reach 5 %; hemisphere
/// sampling alone is a hit-or-miss: Russian roulette lets the ray go with probability ρ (the receiver's
/// albedo), which then hits the emitter with probability F, so a sample is ρ E·(1/ρ) with probability ρF and 0
/// otherwise: relative spread √((1 − ρF)/(ρF)) per sample; it must come within 1.5 times that over √2048.
fn check_direct(
    scene: radlab_scene::Scene,
    emitter_face: usize,
    what: &str,
    strategies: &[DirectSampling],
) {
    let accel = Accel::new(&scene);
    let pts: Vec<SurfacePoint> = evaluation_points(&scene, 24, 5)
        .iter()
        .map(Into::into)
        .collect();
    assert_eq!(pts.len(), 24);
    let emitter = scene.polygon(emitter_face);
    let e_src = scene.emission(emitter_face);
    let samples = 2048;
    for &direct in strategies {
        let est = estimate_points(&scene, &accel, &pts, &params(samples, direct), 77);
        for (p, e) in pts.iter().zip(&est) {
            let f = point_polygon(p.point, p.normal, &emitter);
            let exact = scene.reflectance(p.face) * e_src * f;
            assert_within(
                e,
                exact,
                4.0,
                &format!("{what} {direct:?} at {:?}", p.point),
            );
            let power = match direct {
                DirectSampling::Hemisphere => {
                    let hit = scene.reflectance(p.face).max_element() * f;
                    1.5 * ((1.0 - hit) / (hit * samples as f64)).sqrt()
                }
                _ => 0.05,
            };
            assert!(
                (e.std_error / exact).max_element() < power,
                "{what} {direct:?}: se {:?} for exact {exact:?}",
                e.std_error
            );
        }
    }
}

#[test]
fn unoccluded_direct_light_matches_the_point_to_polygon_closed_form() {
    // Square emitter above a parallel square receiver (face 1 is the emitter).
    let scene = builtin("parallel-squares?reflectance=0.5&emission=3&distance=0.6").expect("scene");
    let all = [
        DirectSampling::Mis,
        DirectSampling::NextEvent,
        DirectSampling::Hemisphere,
    ];
    check_direct(scene, 1, "parallel squares", &all);
    // Perpendicular squares sharing an edge: points near the shared edge see the emitter at grazing angles.
    let scene = builtin("perpendicular-squares?reflectance=0.8&emission=1").expect("scene");
    // Next-event estimation alone is left out here: its 1/r² spike where the receiver touches the emitter makes
    // its distribution heavy-tailed, so its own standard error is no reliable yardstick (MIS is robust there).
    check_direct(
        scene,
        1,
        "perpendicular squares",
        &[DirectSampling::Mis, DirectSampling::Hemisphere],
    );
    // A tilted emitter that straddles the receiver's horizon (half of it lies below the receiver's plane,
    // beyond its edge): only the clipped part lights the receiver.
    let mut b = SceneBuilder::new("straddling");
    let recv = b
        .add_material(Material::new("recv", Rgb::new(0.3, 0.5, 0.7), Rgb::ZERO).expect("m"))
        .expect("add");
    let light = b
        .add_material(Material::new("light", Rgb::ZERO, Rgb::new(1.0, 2.0, 3.0)).expect("m"))
        .expect("add");
    b.add_polygon_points(
        &[
            dvec3(0., 0., 0.),
            dvec3(1., 0., 0.),
            dvec3(1., 1., 0.),
            dvec3(0., 1., 0.),
        ],
        recv,
        "receiver",
    )
    .expect("receiver");
    // Plane x = 1.3 − 0.3 z (leaning over the receiver), facing −x and down, toward the receiver; it spans
    // z from −0.5 to 0.8, so its lower part lies below the receiver's horizon.
    let (a, c) = (dvec3(1.45, -0.2, -0.5), dvec3(1.06, 1.2, 0.8));
    b.add_polygon_points(
        &[a, dvec3(c.x, a.y, c.z), c, dvec3(a.x, c.y, a.z)],
        light,
        "light",
    )
    .expect("light");
    let scene = b.build().expect("scene");
    assert!(
        scene.faces[1].normal.x < 0.0,
        "the light must face the receiver"
    );
    check_direct(scene, 1, "straddling emitter", &all);
}

#[test]
fn point_estimator_error_falls_as_one_over_sqrt_samples() {
    // RMS relative error over 64 points against the closed form, for N = 16 … 4096 samples, each N with its
    // own fixed seed (independent errors). E[error²] = σ²/N exactly, so the slope is −1/2; its sampling
    // spread with 64 points and 5 sizes is about ±0.03.
    let scene = builtin("parallel-squares?reflectance=0.5&emission=1&distance=0.5").expect("scene");
    let accel = Accel::new(&scene);
    let emitter = scene.polygon(1);
    let pts: Vec<SurfacePoint> = evaluation_points(&scene, 64, 1)
        .iter()
        .map(Into::into)
        .collect();
    let exact: Vec<f64> = pts
        .iter()
        .map(|p| 0.5 * point_polygon(p.point, p.normal, &emitter))
        .collect();
    let ns = [16u32, 64, 256, 1024, 4096];
    let errors: Vec<f64> = ns
        .iter()
        .map(|&n| {
            let est = estimate_points(
                &scene,
                &accel,
                &pts,
                &params(n, DirectSampling::Mis),
                1000 + n as u64,
            );
            let ms: f64 = est
                .iter()
                .zip(&exact)
                .map(|(e, x)| ((e.mean.x - x) / x).powi(2))
                .sum::<f64>()
                / pts.len() as f64;
            ms.sqrt()
        })
        .collect();
    let slope = log_log_slope(&ns.map(f64::from), &errors);
    eprintln!("point estimator: slope {slope:.4}, RMS relative errors {errors:?}");
    assert!(
        (slope + 0.5).abs() < 0.1,
        "slope {slope}, errors {errors:?}"
    );
}

#[test]
fn mc_radiosity_error_falls_as_one_over_sqrt_particles() {
    // One step of N particles per run (independent seeds), furnace cube ρ = 0.5: every element's exact
    // value is E/(1 − ρ) = 2 in the discrete system too (rows of F sum to 1).
    let scene = builtin("furnace-cube?reflectance=0.5&emission=1&tessellation=2").expect("scene");
    let accel = Accel::new(&scene);
    let ns = [2_000u64, 8_000, 32_000, 128_000];
    for method in [McMethod::RandomWalk, McMethod::StochasticJacobi] {
        let errors: Vec<f64> = ns
            .iter()
            .map(|&n| {
                let p = mc_params(0.25, n, 1, method);
                let mut s = McRadiositySolver::new(&scene, &accel, p, 500 + n).expect("solver");
                assert_eq!(s.step().expect("step"), Step::Converged);
                let b = s.element_radiosity();
                (b.iter().map(|x| (x.x / 2.0 - 1.0).powi(2)).sum::<f64>() / b.len() as f64).sqrt()
            })
            .collect();
        let slope = log_log_slope(&ns.map(|n| n as f64), &errors);
        eprintln!("{method:?}: slope {slope:.4}, RMS relative errors {errors:?}");
        assert!(
            (slope + 0.5).abs() < 0.1,
            "{method:?}: slope {slope}, errors {errors:?}"
        );
    }
}

#[test]
fn mc_radiosity_furnace_is_unbiased_from_rho_0_to_0_999() {
    for (rho, particles, steps) in [
        (0.0, 2_000, 4),
        (0.5, 20_000, 16),
        (0.9, 4_000, 16),
        (0.999, 120, 16),
    ] {
        let scene = builtin(&format!(
            "furnace-cube?reflectance={rho}&emission=1&tessellation=2"
        ))
        .expect("scene");
        let accel = Accel::new(&scene);
        let exact = 1.0 / (1.0 - rho);
        for method in [McMethod::RandomWalk, McMethod::StochasticJacobi] {
            let p = mc_params(0.34, particles, steps, method);
            let mut s = McRadiositySolver::new(&scene, &accel, p, 7).expect("solver");
            let mut area_means = Vec::new();
            let area: Vec<f64> = s.mesh().elements.iter().map(|e| e.area).collect();
            let total: f64 = area.iter().sum();
            while s.step().expect("step") == Step::Continue {
                area_means.push(
                    s.element_radiosity()
                        .iter()
                        .zip(&area)
                        .map(|(b, a)| b.x * a)
                        .sum::<f64>()
                        / total,
                );
            }
            area_means.push(
                s.element_radiosity()
                    .iter()
                    .zip(&area)
                    .map(|(b, a)| b.x * a)
                    .sum::<f64>()
                    / total,
            );
            assert_eq!(area_means.len() as u64, steps);
            let b = s.element_radiosity();
            let se = s.element_std_error().expect("two or more steps");
            if rho == 0.0 {
                assert!(b.iter().all(|x| *x == Rgb::ONE), "rho = 0: B = E exactly");
                continue;
            }
            // Per element: 5 standard errors (about 100 elements per run, so a family-wise false-alarm rate
            // below 1 % even with the t-distribution of 15 degrees of freedom).
            for (j, (x, e)) in b.iter().zip(&se).enumerate() {
                assert!(
                    (x.x - exact).abs() <= 5.0 * e.x,
                    "{method:?} rho={rho} element {j}: {} ± {} vs {exact}",
                    x.x,
                    e.x
                );
            }
            // The area-weighted mean, with its standard error from the spread of the step estimates
            // (recovered from the running means).
            let k = area_means.len();
            let (_, se_mean) = mean_se(&step_values(&area_means));
            assert!(
                (area_means[k - 1] - exact).abs() <= 4.0 * se_mean,
                "{method:?} rho={rho}: mean {} ± {se_mean} vs {exact}",
                area_means[k - 1]
            );
            assert!(se_mean < 0.03 * exact, "{method:?} rho={rho}: se {se_mean}");
            let rel = s
                .stats()
                .residual
                .expect("relative standard error after 2 steps");
            assert!(rel > 0.0 && rel < 0.5, "{rel}");
        }
    }
}

#[test]
fn mc_radiosity_direct_light_matches_element_form_factors() {
    // Parallel squares: the receiver's elements get B_j = ρ E F_{j→emitter}, F from a 24 × 24 midpoint
    // quadrature of the exact point-to-polygon factor (error far below the Monte Carlo noise). Non-uniform,
    // so particles deposited on the wrong element would show.
    let scene = builtin("parallel-squares?reflectance=0.5&emission=1&distance=0.5").expect("scene");
    let accel = Accel::new(&scene);
    let emitter = scene.polygon(1);
    for method in [McMethod::RandomWalk, McMethod::StochasticJacobi] {
        let p = mc_params(0.2, 10_000, 24, method);
        let mut s = McRadiositySolver::new(&scene, &accel, p, 99).expect("solver");
        while s.step().expect("step") == Step::Continue {}
        let se = s.element_std_error().expect("se");
        let mesh = s.mesh();
        for e in mesh.elements_of(0) {
            let poly = &mesh.elements[e].polygon;
            let q = 24;
            let f: f64 = (0..q * q)
                .map(|k| {
                    let (i, j) = (k % q, k / q);
                    let x = poly.point_at((i as f64 + 0.5) / q as f64, (j as f64 + 0.5) / q as f64);
                    point_polygon(x, DVec3::Z, &emitter)
                })
                .sum::<f64>()
                / (q * q) as f64;
            let exact = 0.5 * f;
            let b = s.element_radiosity()[e].x;
            assert!(
                (b - exact).abs() <= 5.0 * se[e].x,
                "{method:?} element {e}: {b} ± {} vs {exact}",
                se[e].x
            );
            assert!(
                se[e].x < 0.05 * exact,
                "{method:?}: se {} for {exact}",
                se[e].x
            );
        }
        // Rays: one per particle flight; the receiver (ρ = 0.5) re-emits upward into the open: all escape.
        assert!(s.stats().rays >= 24 * 10_000);
    }
}

#[test]
fn mc_radiosity_converges_after_max_steps_under_defaults() {
    let scene = builtin("parallel-squares?reflectance=0").expect("scene");
    let accel = Accel::new(&scene);
    let p = McRadiosityParams {
        particles_per_step: 500,
        ..Default::default()
    };
    let max = p.max_steps;
    let mut s = McRadiositySolver::new(&scene, &accel, p, 1).expect("solver");
    let mut steps = 0;
    while s.step().expect("step") == Step::Continue {
        steps += 1;
    }
    assert_eq!(steps + 1, max);
    assert_eq!(s.stats().steps, max);
    assert_eq!(s.step().expect("after"), Step::Converged);
    assert_eq!(s.stats().steps, max, "steps after convergence do nothing");
    // One flight per particle (ρ = 0 receiver), plus the open-fraction estimate's first step: 16 probe points
    // per element, each open at its first ray (nothing is sealed: every ray escapes or meets a front).
    assert_eq!(
        s.stats().rays,
        max * 500 + 16 * s.mesh().len() as u64,
        "ρ = 0 receiver: one flight per particle, one probe ray per open-fraction point"
    );
    assert!(s.stats().bytes > 0 && s.stats().elements == s.mesh().len() as u64);
    // radiosity_at answers with the element containing the point.
    let e = s.mesh().elements_of(0).start + 3;
    let c = s.mesh().elements[e].centroid;
    assert_eq!(s.solution().radiosity_at(0, c), s.element_radiosity()[e]);
}

#[test]
fn camera_render_of_a_furnace_is_flat_and_escaping_rays_are_black() {
    let scene = builtin("furnace-cube?reflectance=0.5&emission=1&tessellation=2").expect("scene");
    let accel = Accel::new(&scene);
    let camera = Camera {
        eye: dvec3(0.5, 0.2, 0.5),
        target: dvec3(0.5, 1.0, 0.6),
        up: DVec3::Z,
        fov_y_deg: 100.0,
        width: 8,
        height: 6,
    };
    let calls = std::sync::atomic::AtomicUsize::new(0);
    let last = std::sync::atomic::AtomicUsize::new(0);
    let rp = RenderParams {
        samples_per_pixel: 256,
        ..Default::default()
    };
    let (img, se) = render(&scene, &accel, &camera, &rp, 5, &|done, total| {
        assert_eq!(total, 48);
        calls.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        last.fetch_max(done, std::sync::atomic::Ordering::Relaxed);
    });
    assert_eq!((img.width, img.height, img.pixels.len()), (8, 6, 48));
    assert_eq!(calls.into_inner(), 6, "one call per row");
    assert_eq!(last.into_inner(), 48);
    let exact = 2.0 / std::f64::consts::PI;
    for (p, s) in img.pixels.iter().zip(&se.pixels) {
        let l = PointEstimate {
            mean: *p,
            std_error: *s,
        };
        assert_within(&l, Rgb::splat(exact), 4.0, "furnace pixel");
        assert!(s.x < 0.1 * exact);
    }
    // Looking away from the two plates of an open scene: every ray escapes.
    let scene = builtin("parallel-squares").expect("scene");
    let accel = Accel::new(&scene);
    let camera = Camera {
        eye: dvec3(0.5, 0.5, 3.0),
        target: dvec3(0.5, 0.5, 10.0),
        up: DVec3::Y,
        fov_y_deg: 40.0,
        width: 4,
        height: 4,
    };
    let (img, _) = render(
        &scene,
        &accel,
        &camera,
        &RenderParams::default(),
        1,
        &|_, _| {},
    );
    assert!(img.pixels.iter().all(|p| *p == Rgb::ZERO));
}

#[test]
fn results_are_identical_for_one_and_two_threads() {
    let scene = lit_box();
    let accel = Accel::new(&scene);
    let pts = spread_points(&scene, 6, 3);
    let camera = Camera {
        eye: dvec3(0.5, 0.05, 0.5),
        target: dvec3(0.5, 1.0, 0.5),
        up: DVec3::Z,
        fov_y_deg: 80.0,
        width: 10,
        height: 7,
    };
    let run = || {
        let pe = estimate_points(&scene, &accel, &pts, &params(600, DirectSampling::Mis), 8);
        let img = render(
            &scene,
            &accel,
            &camera,
            &RenderParams {
                samples_per_pixel: 8,
                ..Default::default()
            },
            8,
            &|_, _| {},
        );
        let mut mc = Vec::new();
        for method in [McMethod::RandomWalk, McMethod::StochasticJacobi] {
            let p = mc_params(0.25, 3_000, 2, method);
            let mut s = McRadiositySolver::new(&scene, &accel, p, 8).expect("solver");
            s.step().expect("step");
            s.step().expect("step");
            mc.push((
                s.element_radiosity().to_vec(),
                s.element_std_error(),
                s.stats().rays,
            ));
        }
        (pe, img, mc)
    };
    let one = on_threads(1, run);
    let two = on_threads(2, run);
    assert!(
        one.0 == two.0,
        "point estimates differ between 1 and 2 threads"
    );
    assert!(one.1 == two.1, "renders differ between 1 and 2 threads");
    assert!(
        one.2 == two.2,
        "mesh Monte Carlo radiosity differs between 1 and 2 threads"
    );
    // And the seed matters.
    let other = estimate_points(&scene, &accel, &pts, &params(600, DirectSampling::Mis), 9);
    assert!(other != one.0);
}

#[test]
fn progress_reports_every_point_once() {
    let scene = builtin("furnace-cube?reflectance=0.5").expect("scene");
    let accel = Accel::new(&scene);
    let pts = spread_points(&scene, 9, 1);
    let seen = std::sync::Mutex::new(Vec::new());
    let p = params(700, DirectSampling::Mis); // 3 chunks per point
    let est = estimate_points_with_progress(&scene, &accel, &pts, &p, 4, &|done, total| {
        seen.lock().expect("lock").push((done, total));
    });
    let mut seen = seen.into_inner().expect("lock");
    seen.sort_unstable();
    assert_eq!(seen, (1..=10).map(|d| (d, 10)).collect::<Vec<_>>());
    assert_eq!(
        est,
        estimate_points(&scene, &accel, &pts, &p, 4),
        "progress does not change results"
    );
}

#[test]
fn parameters_parse_validate_and_name_their_errors() {
    let pairs = |v: &[(&str, &str)]| -> Vec<(String, String)> {
        v.iter()
            .map(|(a, b)| (a.to_string(), b.to_string()))
            .collect()
    };
    let p = PointParams::from_pairs(&pairs(&[("samples", "64"), ("direct", "next-event")]))
        .expect("valid");
    assert_eq!(
        (p.samples, p.direct, p.max_depth),
        (64, DirectSampling::NextEvent, DEFAULT_MAX_DEPTH)
    );
    assert!(
        PointParams::from_pairs(&pairs(&[("samples", "0")]))
            .expect_err("0")
            .to_string()
            .contains("samples")
    );
    assert!(
        PointParams::from_pairs(&pairs(&[("sample", "3")]))
            .expect_err("typo")
            .to_string()
            .contains("sample")
    );
    let r = RenderParams::from_pairs(&pairs(&[
        ("samples_per_pixel", "4"),
        ("direct", "hemisphere"),
    ]))
    .expect("valid");
    assert_eq!(
        (r.samples_per_pixel, r.direct),
        (4, DirectSampling::Hemisphere)
    );
    let m = McRadiosityParams::from_pairs(&pairs(&[
        ("method", "stochastic-jacobi"),
        ("element_size", "0.1"),
    ]))
    .expect("valid");
    assert_eq!(
        (m.method, m.element_size),
        (McMethod::StochasticJacobi, Some(0.1))
    );
    assert!(
        McRadiosityParams::from_pairs(&pairs(&[("element_size", "-1")]))
            .expect_err("neg")
            .to_string()
            .contains("element_size")
    );
    assert!(McRadiosityParams::from_pairs(&pairs(&[("method", "gibbs")])).is_err());
    // Every parameter is declared with a help line, and only element_size (unset: scene-relative) has no
    // default value.
    let decls = [
        McRadiosityParams::declarations(),
        PointParams::declarations(),
        RenderParams::declarations(),
    ];
    for d in decls.iter().flatten() {
        assert!(!d.help.is_empty(), "{}", d.name);
        assert!(
            d.name == "element_size" || d.default != "unset",
            "{}",
            d.name
        );
    }
}

#[test]
fn an_emitter_facing_away_lights_nothing() {
    // Faces are one-sided: an emitter whose front faces away from the receiver gives it nothing, exactly.
    let mut b = SceneBuilder::new("facing-away");
    let recv = b
        .add_material(Material::new("recv", Rgb::splat(0.9), Rgb::ZERO).expect("m"))
        .expect("add");
    let light = b
        .add_material(Material::new("light", Rgb::splat(0.5), Rgb::ONE).expect("m"))
        .expect("add");
    let square = |z: f64, up: bool| {
        let mut v = vec![
            dvec3(0., 0., z),
            dvec3(1., 0., z),
            dvec3(1., 1., z),
            dvec3(0., 1., z),
        ];
        if !up {
            v.reverse();
        }
        v
    };
    b.add_polygon_points(&square(0.0, true), recv, "receiver")
        .expect("receiver");
    b.add_polygon_points(&square(1.0, true), light, "light facing up, away")
        .expect("light");
    let scene = b.build().expect("scene");
    let accel = Accel::new(&scene);
    let pts: Vec<SurfacePoint> = evaluation_points(&scene, 8, 2)
        .iter()
        .map(Into::into)
        .collect();
    for e in estimate_points(&scene, &accel, &pts, &params(256, DirectSampling::Mis), 1) {
        assert_eq!((e.mean, e.std_error), (Rgb::ZERO, Rgb::ZERO));
    }
    let p = mc_params(0.25, 2_000, 2, McMethod::default());
    let mut s = McRadiositySolver::new(&scene, &accel, p, 1).expect("solver");
    s.step().expect("step");
    for e in s.mesh().elements_of(0) {
        assert_eq!(s.element_radiosity()[e], Rgb::ZERO);
    }
}

#[test]
fn results_do_not_depend_on_the_scene_scale() {
    // Scenes scaled by 1e-4 and 1e4 (stability at the extremes): the furnace and the closed form still hold.
    for size in [1e-4, 1e4] {
        let scene = builtin(&format!(
            "furnace-cube?reflectance=0.7&tessellation=2&size={size}"
        ))
        .expect("scene");
        let accel = Accel::new(&scene);
        let pts = spread_points(&scene, 3, 4);
        for e in estimate_points(&scene, &accel, &pts, &params(512, DirectSampling::Mis), 6) {
            assert_within(
                &e,
                Rgb::splat(1.0 / 0.3),
                4.0,
                &format!("furnace size {size}"),
            );
            assert!(e.std_error.x < 0.1 / 0.3);
        }
        let scene = builtin(&format!(
            "parallel-squares?width={size}&depth={size}&distance={}",
            0.5 * size
        ))
        .expect("scene");
        let accel = Accel::new(&scene);
        let emitter = scene.polygon(1);
        for p in evaluation_points(&scene, 6, 8) {
            let sp = SurfacePoint {
                face: p.face,
                point: p.point,
                normal: p.normal,
            };
            let e =
                estimate_points(&scene, &accel, &[sp], &params(1024, DirectSampling::Mis), 2)[0];
            let exact = Rgb::splat(0.5 * point_polygon(p.point, p.normal, &emitter));
            assert_within(&e, exact, 4.0, &format!("parallel squares size {size}"));
            assert!(e.std_error.x < 0.05 * exact.x);
        }
    }
}

//! Measurements of progressive radiosity on the Cornell box, printed as tables (run in the bench profile):
//!
//! ```text
//! cargo bench -p radlab-progressive --bench measure -- [error] [memory] [scaling] [substructuring]
//! ```
//!
//! - `error`: error against time beside matrix radiosity, both at their defaults, against the path tracer's
//!   per-point reference at the shared evaluation points (area-weighted relative L1, printed with the
//!   reference's noise floor). Only `step()` is timed; evaluation happens between steps.
//! - `memory`: bytes each solver holds at equal element counts (no substructuring, no adaptive subdivision).
//! - `scaling`: time to converge against element count at four element sizes, with the least-squares slope
//!   of log(time) against log(elements).
//! - `substructuring`: defaults against variations (patch size, quadrature, adaptive off) in time and error.
//! - `high-albedo` (only when named): the furnace cube (`builtin:furnace-cube`, default mesh) at ρ = 0.5 …
//!   0.999, plain shooting against ambient overshooting, each run until the area-weighted relative L1 error
//!   against the exact B = E/(1 − ρ) is at most 1 % (or a time cap is reached): shots, step time, error.
//! - `cornell-overshoot` (only when named): the Cornell box at the defaults with `overshoot = none` and
//!   `ambient`: shots, step time, elements, and the relative L1 difference at the shared evaluation points from
//!   a plain-shooting solution converged to an unshot fraction of 1e-5.
//!
//! With no argument every table is printed. Each run asserts its solver converged before reporting.

use std::time::{Duration, Instant};

use radlab_answer::default_element_size;
use radlab_kernels::form_factor::VisibilitySampling;
use radlab_matrix::{MatrixParams, MatrixSolver};
use radlab_method::{EvalPoint, Solution, Solver, Step, error_metric, evaluation_points};
use radlab_pathtrace::{PointParams, SurfacePoint, estimate_points};
use radlab_progressive::{Overshoot, ProgressiveParams, ProgressiveSolver};
use radlab_scene::{Rgb, Scene, builtin};
use radlab_visibility::Accel;

struct Reference {
    points: Vec<EvalPoint>,
    mean: Vec<Rgb>,
    noise_floor: f64,
}

fn reference(scene: &Scene, accel: &Accel, count: usize, samples: u32) -> Reference {
    let points = evaluation_points(scene, count, 1);
    let sp: Vec<SurfacePoint> = points.iter().map(Into::into).collect();
    let t = Instant::now();
    let est = estimate_points(
        scene,
        accel,
        &sp,
        &PointParams {
            samples,
            ..Default::default()
        },
        12345,
    );
    let mean: Vec<Rgb> = est.iter().map(|e| e.mean).collect();
    let total: Rgb = mean.iter().copied().sum();
    let se: Rgb = est.iter().map(|e| e.std_error).sum();
    let noise_floor = (se / total).element_sum() / 3.0;
    eprintln!(
        "reference: {} points x {samples} paths in {:.1} s; noise floor (sum of standard errors / sum of B) {:.2e}",
        points.len(),
        t.elapsed().as_secs_f64(),
        noise_floor
    );
    Reference {
        points,
        mean,
        noise_floor,
    }
}

/// Relative L1 error of B against the reference (radlab_method::error_metric).
fn error(sol: &dyn Solution, r: &Reference) -> f64 {
    error_metric::solution_errors(sol, &r.points, &r.mean).l1
}

/// Runs to convergence; returns (step time, trace of (time, error, stats.bytes)).
fn trace(solver: &mut dyn Solver, r: Option<&Reference>) -> (Duration, Vec<(f64, f64, u64)>) {
    let mut spent = Duration::ZERO;
    let mut next = 0.02;
    let mut out = Vec::new();
    loop {
        let t = Instant::now();
        let s = solver.step().expect("step");
        spent += t.elapsed();
        let done = s != Step::Continue;
        if let Some(r) = r
            && (spent.as_secs_f64() >= next || done)
        {
            out.push((
                spent.as_secs_f64(),
                error(solver.solution(), r),
                solver.stats().bytes,
            ));
            next = spent.as_secs_f64() * 1.5;
        }
        if done {
            return (spent, out);
        }
    }
}

fn error_table(scene: &Scene, accel: &Accel) {
    let r = reference(scene, accel, 2000, 4096);
    eprintln!(
        "\n## Cornell box: error against step time (defaults), noise floor {:.2e}",
        r.noise_floor
    );
    let mut p =
        ProgressiveSolver::new(scene, accel, ProgressiveParams::default(), 1).expect("progressive");
    let (tp, trp) = trace(&mut p, Some(&r));
    eprintln!(
        "progressive: {} elements ({} patches, {} split), {} shots, unshot {:.2e}, {:.2} s, {} rays",
        p.element_count(),
        p.patch_count(),
        p.elements_split(),
        p.shots(),
        p.unshot_fraction(),
        tp.as_secs_f64(),
        p.stats().rays
    );
    let mut m = MatrixSolver::new(scene, accel, MatrixParams::default(), 1).expect("matrix");
    let (tm, trm) = trace(&mut m, Some(&r));
    eprintln!(
        "matrix: {} elements, {} iterations, {:.2} s, {} rays",
        m.mesh().len(),
        m.iterations(),
        tm.as_secs_f64(),
        m.stats().rays
    );
    eprintln!("method,step_time_s,rel_l1_error,bytes");
    for (t, e, b) in trp {
        eprintln!("progressive,{t:.3},{e:.4},{b}");
    }
    for (t, e, b) in trm {
        eprintln!("matrix,{t:.3},{e:.4},{b}");
    }
}

fn memory_table(scene: &Scene, accel: &Accel) {
    eprintln!(
        "\n## Memory held at equal element counts (patch = element, adaptive off; matrix default)"
    );
    eprintln!("elements,progressive_bytes,matrix_bytes,ratio");
    let d = default_element_size(scene);
    for k in [2.0, 1.0, 0.5] {
        let es = d * k;
        let mut p = ProgressiveSolver::new(
            scene,
            accel,
            ProgressiveParams {
                max_shots: Some(10),
                ..ProgressiveParams::fixed_mesh(es, VisibilitySampling::Jittered4x4)
            },
            1,
        )
        .expect("progressive");
        while p.step().expect("step") == Step::Continue {}
        let mut m = MatrixSolver::new(
            scene,
            accel,
            MatrixParams {
                element_size: Some(es),
                max_iterations: 1,
                ..Default::default()
            },
            1,
        )
        .expect("matrix");
        while m.step().expect("step") == Step::Continue {}
        assert_eq!(p.element_count(), m.mesh().len());
        let (bp, bm) = (p.stats().bytes, m.stats().bytes);
        eprintln!(
            "{},{bp},{bm},{:.1}",
            p.element_count(),
            bm as f64 / bp as f64
        );
    }
}

fn slope(xs: &[f64], ys: &[f64]) -> f64 {
    let n = xs.len() as f64;
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    let sxy: f64 = xs.iter().zip(ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = xs.iter().map(|x| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

fn scaling_table(scene: &Scene, accel: &Accel) {
    let d = default_element_size(scene);
    for (label, sub) in [
        ("no substructuring", false),
        ("defaults (patch = 2 x element, adaptive)", true),
    ] {
        eprintln!("\n## Time to converge against element count, Cornell box, {label}");
        eprintln!("element_size,elements,patches,shots,seconds");
        let (mut xs, mut ys) = (Vec::new(), Vec::new());
        for k in [
            2.0,
            std::f64::consts::SQRT_2,
            1.0,
            std::f64::consts::FRAC_1_SQRT_2,
        ] {
            let es = d * k;
            let params = if sub {
                ProgressiveParams {
                    element_size: Some(es),
                    ..Default::default()
                }
            } else {
                ProgressiveParams {
                    element_size: Some(es),
                    patch_size: Some(es),
                    adaptive: false,
                    ..Default::default()
                }
            };
            let mut p = ProgressiveSolver::new(scene, accel, params, 1).expect("progressive");
            let (t, _) = trace(&mut p, None);
            assert!(p.unshot_fraction() <= p.params().stop_unshot_fraction);
            eprintln!(
                "{es:.2},{},{},{},{:.3}",
                p.element_count(),
                p.patch_count(),
                p.shots(),
                t.as_secs_f64()
            );
            xs.push((p.element_count() as f64).ln());
            ys.push(t.as_secs_f64().ln());
        }
        eprintln!(
            "log-log slope of time against elements: {:.2}",
            slope(&xs, &ys)
        );
    }
}

fn substructuring_table(scene: &Scene, accel: &Accel) {
    let r = reference(scene, accel, 2000, 4096);
    eprintln!(
        "\n## Variations on the defaults, Cornell box (noise floor {:.2e})",
        r.noise_floor
    );
    eprintln!("variant,elements,patches,shots,seconds,rel_l1_error");
    let d = ProgressiveParams::default();
    let es = radlab_progressive::params::default_element_size(scene);
    let variants: Vec<(&str, ProgressiveParams)> = vec![
        ("defaults", d.clone()),
        (
            "adaptive off",
            ProgressiveParams {
                adaptive: false,
                ..d.clone()
            },
        ),
        (
            "patch = element",
            ProgressiveParams {
                patch_size: Some(es),
                ..d.clone()
            },
        ),
        (
            "patch = 4 x element",
            ProgressiveParams {
                patch_size: Some(4.0 * es),
                ..d.clone()
            },
        ),
        (
            "quadrature 2",
            ProgressiveParams {
                quadrature: 2,
                ..d.clone()
            },
        ),
        (
            "indirect 4x4",
            ProgressiveParams {
                indirect_visibility: VisibilitySampling::Jittered4x4,
                ..d.clone()
            },
        ),
        (
            "indirect centre",
            ProgressiveParams {
                indirect_visibility: VisibilitySampling::Centre,
                ..d.clone()
            },
        ),
        (
            "threshold 0.2",
            ProgressiveParams {
                adaptive_threshold: 0.2,
                ..d.clone()
            },
        ),
        (
            "threshold 0.15",
            ProgressiveParams {
                adaptive_threshold: 0.15,
                ..d.clone()
            },
        ),
        (
            "stop 1e-2",
            ProgressiveParams {
                stop_unshot_fraction: 1e-2,
                ..d.clone()
            },
        ),
        (
            "stop 5e-4",
            ProgressiveParams {
                stop_unshot_fraction: 5e-4,
                ..d.clone()
            },
        ),
        (
            "element / 2",
            ProgressiveParams {
                element_size: Some(es / 2.0),
                ..d.clone()
            },
        ),
    ];
    for (name, params) in variants {
        let mut p = ProgressiveSolver::new(scene, accel, params, 1).expect("progressive");
        let (t, _) = trace(&mut p, None);
        eprintln!(
            "{name},{},{},{},{:.3},{:.4}",
            p.element_count(),
            p.patch_count(),
            p.shots(),
            t.as_secs_f64(),
            error(p.solution(), &r)
        );
    }
}

/// Area-weighted relative L1 error of the elements against the furnace's exact B (worst channel), and the
/// largest relative element error.
fn furnace_error(p: &ProgressiveSolver, exact: f64) -> (f64, f64) {
    let (mut num, mut den, mut worst) = (0.0, 0.0, 0.0_f64);
    for e in p.elements() {
        let err = (e.radiosity - Rgb::splat(exact)).abs().max_element();
        num += e.area * err;
        den += e.area * exact;
        worst = worst.max(err / exact);
    }
    (num / den, worst)
}

fn high_albedo_table() {
    let cap = Duration::from_secs(
        std::env::var("HIGH_ALBEDO_CAP_S")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(120),
    );
    eprintln!(
        "\n## Furnace cube (default mesh, defaults but overshoot): time to a relative L1 error of 1 %, cap {} s",
        cap.as_secs()
    );
    eprintln!(
        "overshoot,rho,patches,elements,shots,step_time_s,rel_l1_error,max_element_error,reached"
    );
    for rho in [0.5, 0.9, 0.99, 0.999] {
        let scene = builtin(&format!("furnace-cube?reflectance={rho}")).expect("furnace");
        let accel = Accel::new(&scene);
        let exact = 1.0 / (1.0 - rho);
        for overshoot in [Overshoot::None, Overshoot::Ambient] {
            let params = ProgressiveParams {
                overshoot,
                // Never the reason to stop here: the loop stops on the measured error.
                stop_unshot_fraction: 1e-9,
                ..Default::default()
            };
            let mut p = ProgressiveSolver::new(&scene, &accel, params, 1).expect("progressive");
            let mut spent = Duration::ZERO;
            let mut err = furnace_error(&p, exact);
            while err.0 > 0.01 && spent < cap {
                let t = Instant::now();
                let s = p.step().expect("step");
                spent += t.elapsed();
                err = furnace_error(&p, exact);
                if s != Step::Continue {
                    break;
                }
            }
            eprintln!(
                "{overshoot:?},{rho},{},{},{},{:.3},{:.4},{:.4},{}",
                p.patch_count(),
                p.element_count(),
                p.shots(),
                spent.as_secs_f64(),
                err.0,
                err.1,
                err.0 <= 0.01
            );
        }
    }
}

fn cornell_overshoot_table(scene: &Scene, accel: &Accel) {
    let points = evaluation_points(scene, 2000, 1);
    let at = |sol: &dyn Solution| -> Vec<Rgb> {
        points
            .iter()
            .map(|p| sol.radiosity_at(p.face, p.point))
            .collect()
    };
    let tight = ProgressiveParams {
        overshoot: Overshoot::None,
        stop_unshot_fraction: 1e-5,
        ..Default::default()
    };
    let mut r = ProgressiveSolver::new(scene, accel, tight, 1).expect("progressive");
    let (tr, _) = trace(&mut r, None);
    let reference = at(r.solution());
    eprintln!(
        "\n## Cornell box, defaults: plain shooting against overshooting (reference: plain to 1e-5, {} shots, {:.1} s)",
        r.shots(),
        tr.as_secs_f64()
    );
    eprintln!("overshoot,shots,step_time_s,elements,unshot_fraction,rel_l1_from_reference");
    for overshoot in [Overshoot::None, Overshoot::Ambient] {
        let params = ProgressiveParams {
            overshoot,
            ..Default::default()
        };
        let mut p = ProgressiveSolver::new(scene, accel, params, 1).expect("progressive");
        let (t, _) = trace(&mut p, None);
        let b = at(p.solution());
        let num: Rgb = b.iter().zip(&reference).map(|(x, y)| (*x - *y).abs()).sum();
        let den: Rgb = reference.iter().map(|y| y.abs()).sum();
        eprintln!(
            "{overshoot:?},{},{:.3},{},{:.2e},{:.4}",
            p.shots(),
            t.as_secs_f64(),
            p.element_count(),
            p.unshot_fraction(),
            (num / den).element_sum() / 3.0
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    let want = |s: &str| args.is_empty() || args.iter().any(|a| a == s);
    let scene = builtin("cornell").expect("cornell");
    let accel = Accel::new(&scene);
    eprintln!(
        "Cornell box: {} faces, diagonal {:.1}, default element size {:.2} (matrix: {:.2}), {} rayon threads",
        scene.face_count(),
        scene.diagonal(),
        radlab_progressive::params::default_element_size(&scene),
        default_element_size(&scene),
        rayon::current_num_threads()
    );
    if args.iter().any(|a| a == "defaults") {
        let mut p = ProgressiveSolver::new(&scene, &accel, ProgressiveParams::default(), 1)
            .expect("progressive");
        let (t, _) = trace(&mut p, None);
        eprintln!(
            "defaults: {} elements, {} patches, {} shots, {:.2} s step time, {} rays, {} form factors",
            p.element_count(),
            p.patch_count(),
            p.shots(),
            t.as_secs_f64(),
            p.stats().rays,
            p.stats().form_factors
        );
        return;
    }
    if args.iter().any(|a| a == "high-albedo") {
        high_albedo_table();
        return;
    }
    if args.iter().any(|a| a == "cornell-overshoot") {
        cornell_overshoot_table(&scene, &accel);
        return;
    }
    if want("memory") {
        memory_table(&scene, &accel);
    }
    if want("scaling") {
        scaling_table(&scene, &accel);
    }
    if want("substructuring") {
        substructuring_table(&scene, &accel);
    }
    if want("error") {
        error_table(&scene, &accel);
    }
}

//! Throughput of radlab-pathtrace's Monte Carlo methods where the experiments spend it.
//!
//! - `paths`/`rays`: the per-point estimator (the reference) at 64 evaluation points × 256 paths on the Cornell
//!   box (`builtin:cornell`, 36 faces) and on the bumpy sphere in its closed room with 10⁶ faces
//!   (`builtin:bumpy-sphere?faces=1000000`): the same work timed twice, reported as paths per second and as
//!   rays per second (rays counted by the shared `Accel` over one run; the count is deterministic).
//! - `time-to-1%`: wall time for the estimator to reach a 1 % relative standard error (every channel, every
//!   point) at 32 of the Cornell box's evaluation points: a pilot run of 256 paths per point gives the samples
//!   needed (standard error ∝ 1/√samples), which is checked before timing. The worst point and channel set
//!   the count (the blue channel of surfaces lit through red or green bounces, block sides facing away from
//!   the light); the median point needs about a tenth of it, which the bench prints.
//! - `mc-radiosity`: one step of mesh-based Monte Carlo radiosity (100,000 particles) on the Cornell box at
//!   the default element size, for each method, reported as particles per second.
//!
//! Before timing, every estimate must be finite and non-negative with a finite standard error, and mesh
//! radiosity must be at least the emission everywhere. The bench prints the ray counts and the samples needed
//! for 1 % (to stderr).
//!
//! Run: `cargo bench -p radlab-pathtrace -- --warm-up-time 1 --measurement-time 5`.

#![expect(
    missing_docs,
    reason = "criterion_group! generates an undocumented public function"
)]

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use radlab_method::{Solver, evaluation_points};
use radlab_pathtrace::{
    McMethod, McRadiosityParams, McRadiositySolver, PointEstimate, PointParams, SAMPLES_PER_CHUNK,
    SurfacePoint, estimate_points,
};
use radlab_scene::{Scene, builtin};
use radlab_visibility::Accel;

fn surface_points(scene: &Scene, count: usize) -> Vec<SurfacePoint> {
    evaluation_points(scene, count, 1)
        .iter()
        .map(Into::into)
        .collect()
}

fn check(est: &[PointEstimate], what: &str) {
    for (i, e) in est.iter().enumerate() {
        assert!(
            e.mean.is_finite() && e.mean.min_element() >= 0.0 && e.std_error.is_finite(),
            "{what}: point {i} gave {e:?}"
        );
    }
}

/// Largest relative standard error over points and channels.
fn worst_relative_error(est: &[PointEstimate]) -> f64 {
    est.iter()
        .flat_map(|e| (0..3).map(move |c| e.std_error[c] / e.mean[c]))
        .fold(0.0, f64::max)
}

fn throughput(c: &mut Criterion) {
    for (name, spec) in [
        ("cornell", "cornell"),
        ("bumpy-sphere-1e6", "bumpy-sphere?faces=1000000"),
    ] {
        let scene = builtin(spec).expect("builtin scene");
        let accel = Accel::new(&scene);
        let pts = surface_points(&scene, 64);
        let params = PointParams {
            samples: 256,
            ..Default::default()
        };
        let before = accel.rays_cast();
        let est = estimate_points(&scene, &accel, &pts, &params, 7);
        let rays = accel.rays_cast() - before;
        check(&est, name);
        let paths = (pts.len() * params.samples as usize) as u64;
        eprintln!(
            "{name}: {} faces, BVH build {:.2} s, {rays} rays for {paths} paths ({:.2} rays per path)",
            scene.faces.len(),
            accel.build_time().as_secs_f64(),
            rays as f64 / paths as f64
        );
        let mut group = c.benchmark_group(format!("pathtrace/{name}"));
        group.sample_size(10);
        group.throughput(Throughput::Elements(paths));
        group.bench_function("paths", |b| {
            b.iter(|| black_box(estimate_points(&scene, &accel, &pts, &params, 7)))
        });
        group.throughput(Throughput::Elements(rays));
        group.bench_function("rays", |b| {
            b.iter(|| black_box(estimate_points(&scene, &accel, &pts, &params, 7)))
        });
        group.finish();
    }
}

fn time_to_one_percent(c: &mut Criterion) {
    let scene = builtin("cornell").expect("cornell");
    let accel = Accel::new(&scene);
    let pts = surface_points(&scene, 32);
    let pilot = PointParams {
        samples: 256,
        ..Default::default()
    };
    let est = estimate_points(&scene, &accel, &pts, &pilot, 11);
    check(&est, "pilot");
    let ratio = worst_relative_error(&est) / 0.01;
    let mut samples = ((pilot.samples as f64 * ratio * ratio * 1.1).ceil() as u32)
        .div_ceil(SAMPLES_PER_CHUNK)
        * SAMPLES_PER_CHUNK;
    // The pilot's own error estimates are noisy: grow the count until the run really reaches 1 %.
    let params = loop {
        let p = PointParams {
            samples,
            ..Default::default()
        };
        let est = estimate_points(&scene, &accel, &pts, &p, 12);
        check(&est, "1 % run");
        let worst = worst_relative_error(&est);
        if worst <= 0.01 {
            // Paths each point alone would need (standard error ∝ 1/√samples), for the spread.
            let mut need: Vec<f64> = est
                .iter()
                .map(|e| {
                    samples as f64 * (worst_relative_error(std::slice::from_ref(e)) / 0.01).powi(2)
                })
                .collect();
            need.sort_by(f64::total_cmp);
            eprintln!(
                "cornell: {samples} paths per point reach 1 % standard error in every channel at 32 \
                 evaluation points (worst {:.4} %); points alone would need median {:.0}, max {:.0}",
                worst * 100.0,
                need[need.len() / 2],
                need[need.len() - 1]
            );
            break p;
        }
        samples = (samples as f64 * (worst / 0.01).powi(2) * 1.1).ceil() as u32;
    };
    let mut group = c.benchmark_group("pathtrace/cornell");
    group.sample_size(10);
    group.bench_function("time-to-1%-32-points", |b| {
        b.iter(|| black_box(estimate_points(&scene, &accel, &pts, &params, 12)))
    });
    group.finish();
}

fn mc_radiosity(c: &mut Criterion) {
    let scene = builtin("cornell").expect("cornell");
    let accel = Accel::new(&scene);
    let mut group = c.benchmark_group("mc-radiosity/cornell");
    group.sample_size(10);
    for method in [McMethod::RandomWalk, McMethod::StochasticJacobi] {
        let params = McRadiosityParams {
            particles_per_step: 100_000,
            method,
            ..Default::default()
        };
        let mut s = McRadiositySolver::new(&scene, &accel, params.clone(), 3).expect("solver");
        s.step().expect("step");
        for (e, b) in s.element_radiosity().iter().enumerate() {
            let em = scene.emission(s.mesh().elements[e].face as usize);
            assert!(
                b.is_finite() && (*b - em).min_element() >= 0.0,
                "element {e}: {b:?}"
            );
        }
        eprintln!(
            "cornell {method:?}: {} elements, {} rays for 100000 particles",
            s.mesh().len(),
            s.stats().rays
        );
        group.throughput(Throughput::Elements(params.particles_per_step));
        group.bench_function(format!("{method:?}"), |b| {
            b.iter(|| {
                let mut s =
                    McRadiositySolver::new(&scene, &accel, params.clone(), 3).expect("solver");
                black_box(s.step().expect("step"))
            })
        });
    }
    group.finish();
}

criterion_group!(benches, throughput, time_to_one_percent, mc_radiosity);
criterion_main!(benches);

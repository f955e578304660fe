//! Criterion benches of progressive radiosity on the Cornell box (`builtin:cornell`):
//!
//! - `cornell/converge_defaults`: meshing plus shooting to the default stopping rule, default parameters.
//! - `cornell/100_shots`: the first hundred shots on the default mesh without adaptive subdivision (per-shot
//!   cost: one form factor and its rays per element).
//! - `cornell_elements/N`: to convergence without substructuring or adaptive subdivision at three element
//!   sizes (N elements); time should grow about as N² (shots ∝ patches, each shot ∝ elements). The fitted
//!   log-log slope is printed by the `measure` bench (`cargo bench --bench measure -- scaling`).
//!
//! Each bench checks its answer once before timing it: the solver must reach its stopping rule, and at the
//! defaults it must agree with matrix radiosity to within their discretisation errors. (The Cornell box is open
//! at the front, so emitted and absorbed power do not balance there; the closed-room test checks that.)

#![expect(
    missing_docs,
    reason = "criterion_group! generates an undocumented public function"
)]

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use radlab_answer::default_element_size;
use radlab_matrix::{MatrixParams, MatrixSolver};
use radlab_method::{Solution, Solver, Step, error_metric, evaluation_points};
use radlab_progressive::{ProgressiveParams, ProgressiveSolver, StopReason};
use radlab_scene::{Scene, builtin};
use radlab_visibility::Accel;

fn run<'a>(scene: &'a Scene, accel: &'a Accel, params: ProgressiveParams) -> ProgressiveSolver<'a> {
    let mut s = ProgressiveSolver::new(scene, accel, params, 1).expect("solver");
    while s.step().expect("step") == Step::Continue {}
    s
}

/// Relative L1 difference (radlab_method::error_metric) of `a` from `b` at 2,000 of the scene's evaluation
/// points.
fn difference(scene: &Scene, a: &dyn Solution, b: &dyn Solution) -> f64 {
    error_metric::difference(a, b, &evaluation_points(scene, 2000, 1)).l1
}

fn benches(c: &mut Criterion) {
    let scene = builtin("cornell").expect("cornell");
    let accel = Accel::new(&scene);

    // The answer: converged, and within the two methods' discretisation errors (about 6-7 % each against the
    // path-traced reference, `measure` bench) of matrix radiosity at its defaults.
    let check = run(&scene, &accel, ProgressiveParams::default());
    assert_eq!(check.stop_reason(), Some(StopReason::UnshotFraction));
    let mut matrix = MatrixSolver::new(&scene, &accel, MatrixParams::default(), 1).expect("matrix");
    while matrix.step().expect("matrix step") == Step::Continue {}
    let d = difference(&scene, check.solution(), matrix.solution());
    assert!(d < 0.1, "progressive and matrix radiosity differ by {d}");
    eprintln!(
        "check: progressive (defaults) against matrix (defaults): relative L1 difference {d:.4}"
    );

    let mut g = c.benchmark_group("cornell");
    g.sample_size(10);
    g.bench_function("converge_defaults", |b| {
        b.iter(|| run(&scene, &accel, ProgressiveParams::default()).shots())
    });
    let hundred = ProgressiveParams {
        adaptive: false,
        max_shots: Some(100),
        ..Default::default()
    };
    assert_eq!(run(&scene, &accel, hundred.clone()).shots(), 100);
    g.bench_function("100_shots", |b| {
        b.iter(|| run(&scene, &accel, hundred.clone()).shots())
    });
    g.finish();

    let mut g = c.benchmark_group("cornell_elements");
    g.sample_size(10);
    let d = default_element_size(&scene);
    for k in [2.0, std::f64::consts::SQRT_2, 1.0] {
        let params = ProgressiveParams {
            element_size: Some(d * k),
            patch_size: Some(d * k),
            adaptive: false,
            ..Default::default()
        };
        let s = run(&scene, &accel, params.clone());
        assert_eq!(s.stop_reason(), Some(StopReason::UnshotFraction));
        g.bench_with_input(
            BenchmarkId::from_parameter(s.element_count()),
            &params,
            |b, p| b.iter(|| run(&scene, &accel, p.clone()).shots()),
        );
    }
    g.finish();
}

criterion_group!(shooting, benches);
criterion_main!(shooting);

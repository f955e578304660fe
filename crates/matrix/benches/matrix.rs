//! Matrix radiosity on a Cornell-like box (open front, two blocks, ceiling light; ~940 elements at the
//! default element size): assembly of the form-factor matrix, then each iteration method solving the
//! assembled system from B = E to the default tolerance.
//!
//! Run: `cargo bench -p radlab-matrix -- --warm-up-time 1 --measurement-time 3`.

#![expect(
    missing_docs,
    reason = "criterion_group! generates an undocumented public function"
)]

#[path = "../tests/common/mod.rs"]
mod common;

use std::hint::black_box;

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use radlab_matrix::{Iteration, MatrixParams, MatrixSolver};
use radlab_method::{Solver, Step};
use radlab_scene::Rgb;
use radlab_visibility::Accel;

const METHODS: [Iteration; 3] = [
    Iteration::Jacobi,
    Iteration::GaussSeidel,
    Iteration::ConjugateGradient,
];

fn assemble(s: &mut MatrixSolver) {
    while !s.is_assembled() {
        s.step().expect("assembly step");
    }
}

fn run(s: &mut MatrixSolver) {
    while s.step().expect("iteration") == Step::Continue {}
}

fn matrix(c: &mut Criterion) {
    let scene = common::cornell_like(false, Rgb::splat(0.73));
    let accel = Accel::new(&scene);
    let mut assembled =
        MatrixSolver::new(&scene, &accel, MatrixParams::default(), 1).expect("solver");
    assemble(&mut assembled);
    let n = assembled.mesh().len();

    // The answer first: every method converges, and all agree within twice the tolerance.
    let area: Vec<f64> = assembled.mesh().elements.iter().map(|e| e.area).collect();
    let mut solutions = Vec::new();
    for m in METHODS {
        let mut s = assembled.clone();
        s.restart(m);
        run(&mut s);
        assert!(!s.hit_iteration_cap(), "{m:?} hit the iteration cap");
        solutions.push(s.element_radiosity().to_vec());
    }
    let norm: Rgb = area
        .iter()
        .zip(&solutions[0])
        .map(|(&a, b)| a * b.abs())
        .sum();
    for other in &solutions[1..] {
        let diff: Rgb = area
            .iter()
            .zip(other.iter().zip(&solutions[0]))
            .map(|(&a, (x, y))| a * (*x - *y).abs())
            .sum();
        let tol = MatrixParams::default().tolerance;
        assert!((diff / norm).max_element() <= 2.0 * tol, "methods disagree");
    }

    let mut g = c.benchmark_group("matrix");
    g.sample_size(10);
    g.bench_function(format!("assembly cornell-like n={n}"), |b| {
        b.iter(|| {
            let mut s =
                MatrixSolver::new(&scene, &accel, MatrixParams::default(), 1).expect("solver");
            assemble(&mut s);
            black_box(s.stats().form_factors)
        })
    });
    for m in METHODS {
        g.bench_function(format!("solve {m:?} cornell-like n={n}"), |b| {
            b.iter_batched(
                || {
                    let mut s = assembled.clone();
                    s.restart(m);
                    s
                },
                |mut s| {
                    run(&mut s);
                    black_box(s.iterations())
                },
                BatchSize::LargeInput,
            )
        });
    }
    g.finish();
}

criterion_group!(benches, matrix);
criterion_main!(benches);

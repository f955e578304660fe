//! Benchmarks of hierarchical radiosity: an ε sweep on the Cornell box (time per full solve; the answer is
//! checked against a matrix solution first), and time against the number k of input faces on the bumpy-sphere
//! family with the classic per-link gather (`gather = link`, O(k² + n) as in the literature; the default per-leaf
//! gather adds a term in elements × links above them), where the k² initial links are expected to dominate
//! eventually (fit the log-log slope of the reported times).

// criterion_group! generates an undocumented function.
#![allow(missing_docs)]

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use radlab_hierarchical::{Gather, HierarchicalParams, HierarchicalSolver};
use radlab_method::{Solution, Solver, Step, evaluation_points};
use radlab_scene::{Scene, builtin};
use radlab_visibility::Accel;

fn solve<'a>(scene: &'a Scene, accel: &'a Accel, p: HierarchicalParams) -> HierarchicalSolver<'a> {
    let mut s = HierarchicalSolver::new(scene, accel, p, 1).expect("valid parameters");
    while s.step().expect("step") == Step::Continue {}
    s
}

fn difference(scene: &Scene, a: &dyn Solution, b: &dyn Solution) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for p in evaluation_points(scene, 2000, 3) {
        let (x, y) = (
            a.radiosity_at(p.face, p.point),
            b.radiosity_at(p.face, p.point),
        );
        num += (x - y).abs().element_sum();
        den += y.abs().element_sum();
    }
    num / den
}

fn cornell_epsilon(c: &mut Criterion) {
    let scene = builtin("cornell").expect("cornell");
    let accel = Accel::new(&scene);
    let mp = radlab_matrix::MatrixParams {
        element_size: Some(40.0),
        ..radlab_matrix::MatrixParams::default()
    };
    let mut m = radlab_matrix::MatrixSolver::new(&scene, &accel, mp, 1).expect("matrix");
    while m.step().expect("matrix step") == Step::Continue {}
    let mut g = c.benchmark_group("cornell_epsilon");
    g.sample_size(10);
    for epsilon in [0.04, 0.02, 0.01, 0.005] {
        let p = HierarchicalParams {
            epsilon,
            ..HierarchicalParams::default()
        };
        let s = solve(&scene, &accel, p.clone());
        let d = difference(&scene, &s, &m);
        assert!(d < 0.2, "epsilon {epsilon}: {d} from the matrix solution");
        g.bench_with_input(BenchmarkId::from_parameter(epsilon), &p, |b, p| {
            b.iter(|| solve(&scene, &accel, p.clone()).stats())
        });
    }
    g.finish();
}

fn bumpy_sphere_faces(c: &mut Criterion) {
    let mut g = c.benchmark_group("bumpy_sphere_faces");
    g.sample_size(10);
    for faces in [200, 400, 800, 1600] {
        let scene = builtin(&format!("bumpy-sphere?faces={faces}")).expect("scene");
        let accel = Accel::new(&scene);
        let p = HierarchicalParams {
            gather: Gather::Link,
            ..HierarchicalParams::coarse()
        };
        let s = solve(&scene, &accel, p.clone());
        let leaves = s.leaves();
        assert!(leaves.iter().all(|l| l.2.is_finite()));
        assert!(leaves.iter().any(|l| l.2.max_element() > 0.0));
        g.bench_with_input(
            BenchmarkId::from_parameter(scene.face_count()),
            &p,
            |b, p| b.iter(|| solve(&scene, &accel, p.clone()).stats()),
        );
    }
    g.finish();
}

criterion_group!(benches, cornell_epsilon, bumpy_sphere_faces);
criterion_main!(benches);

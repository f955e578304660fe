//! The rays a hierarchical solve reports are the same on 1 and 2 threads: each ray is cast once whatever
//! the schedule of the work, and `Accel` counts every one of them exactly (per-thread counters, summed).

use radlab_hierarchical::{HierarchicalParams, HierarchicalSolver};
use radlab_scene::{Accel, Solver, Step};

#[test]
fn rays_reported_are_the_same_on_one_and_two_threads() {
    let scene = radlab_scene::builtin("cornell").expect("scene");
    let params = HierarchicalParams {
        epsilon: 0.04,
        ..HierarchicalParams::default()
    };
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        pool.install(|| {
            let accel = Accel::new(&scene);
            let mut s = HierarchicalSolver::new(&scene, &accel, params.clone(), 7).expect("params");
            while s.step().expect("step") == Step::Continue {}
            // Every ray the solver reports went through this Accel, and nothing else cast any.
            assert_eq!(s.stats().rays, accel.rays_cast());
            s.stats()
        })
    };
    let (one, two) = (run(1), run(2));
    assert!(one.rays > 0);
    assert_eq!(one, two);
}

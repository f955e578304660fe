//! Face-cluster hierarchy build time against the face count k, on the two detailed-mesh builtins
//! (`bumpy-sphere`, `terrain`) at k = 10³, 10⁴, 10⁵, and 10⁶ when `RADLAB_BENCH_MILLION=1` is set (a build
//! of 10⁶ faces takes tens of seconds, so ten samples of it take minutes). Greedy contraction is
//! O(k log k) (Garland, Willmott & Heckbert 2001): the fitted log-log slope of time against k should be a
//! little above one. Each scene's hierarchy is checked before timing: its detailed mesh ends as one root,
//! the room's or light's faces (not connected to it) as one root each.
#![expect(
    missing_docs,
    reason = "criterion_group! generates an undocumented public function"
)]

use criterion::{
    BenchmarkId, Criterion, SamplingMode, Throughput, criterion_group, criterion_main,
};
use radlab_face_cluster::{FaceClusterParams, FaceClusterTree};
use radlab_scene::builtin;

fn sizes() -> Vec<usize> {
    let mut k = vec![1_000, 10_000, 100_000];
    if std::env::var("RADLAB_BENCH_MILLION").is_ok_and(|v| v == "1") {
        k.push(1_000_000);
    }
    k
}

fn build_time(c: &mut Criterion) {
    let params = FaceClusterParams::default();
    let mut group = c.benchmark_group("face-cluster-build");
    group.sampling_mode(SamplingMode::Flat).sample_size(10);
    for name in ["bumpy-sphere", "terrain"] {
        for k in sizes() {
            let scene = builtin(&format!("{name}?faces={k}")).expect("builtin scene");
            let tree = FaceClusterTree::build(&scene, &params).expect("builds");
            let largest = tree
                .roots()
                .map(|r| tree.node(r).faces().len())
                .max()
                .unwrap_or(0);
            // The detailed mesh is one root; the room or light around it adds single-face roots.
            let others = tree.roots().len() - 1;
            assert!(
                largest == scene.face_count() - others && others < 16,
                "{name} k={k}: {} roots, the largest of {largest} faces",
                tree.roots().len()
            );
            group.throughput(Throughput::Elements(scene.face_count() as u64));
            group.bench_with_input(
                BenchmarkId::new(name, scene.face_count()),
                &scene,
                |b, s| b.iter(|| FaceClusterTree::build(s, &params).expect("builds")),
            );
        }
    }
    group.finish();
}

criterion_group!(benches, build_time);
criterion_main!(benches);

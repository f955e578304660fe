//! Form factors per second: the exact point-to-polygon kernel, the unoccluded area-to-area Gauss rule for
//! m = 1, 2, 4 (m² kernel evaluations each), and area-to-area with every [`VisibilitySampling`] (rays between
//! jittered points on both elements, through the shared [`Accel`]).
//!
//! Inputs: random face pairs of the furnace cube tessellated 8 × 8 per side (kernel and unoccluded rule), and
//! random element pairs of the Cornell box meshed at the default element size (with visibility: its two
//! blocks occlude). Before timing: row sums of the cube are 1 for the kernel at random points and for the
//! Gauss rule at every m (the cube is closed, so Σ_j F_ij = 1 to rounding); with visibility, `Unoccluded`
//! reproduces the unoccluded factor exactly and the jittered estimates agree with each other (all are
//! unbiased estimates of the same visible fraction) within 2% summed over the pairs.
//!
//! Run: `cargo bench -p radlab-scene --bench form_factors -- --warm-up-time 1 --measurement-time 3`.

#![expect(
    missing_docs,
    reason = "criterion_group! generates an undocumented public function"
)]

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::DVec3;
use radlab_answer::{ElementMesh, default_element_size};
use radlab_kernels::form_factor::{
    VisibilitySampling, point_polygon, polygon_polygon, polygon_polygon_unoccluded,
};
use radlab_scene::sampling;
use radlab_scene::{Polygon, builtin};
use radlab_visibility::Accel;

const PAIRS: usize = 20_000;

fn kernel_and_quadrature(c: &mut Criterion) {
    let scene = builtin("furnace-cube?tessellation=8").expect("cube");
    let polys: Vec<Polygon> = (0..scene.faces.len()).map(|f| scene.polygon(f)).collect();
    let mut r = sampling::rng(5, 0);
    let mut pick = || (sampling::uniform(&mut r) * polys.len() as f64) as usize;
    let pairs: Vec<(usize, usize)> = (0..PAIRS)
        .map(|_| {
            loop {
                let (i, j) = (pick(), pick());
                if i != j {
                    break (i, j);
                }
            }
        })
        .collect();
    let mut r = sampling::rng(5, 1);
    let points: Vec<(DVec3, DVec3, usize)> = pairs
        .iter()
        .map(|&(i, j)| {
            let x = polys[i].sample_uniform(sampling::uniform(&mut r), sampling::uniform(&mut r));
            (x, scene.faces[i].normal, j)
        })
        .collect();

    // Answers first: row sums of the closed cube.
    for (x, n, _) in points.iter().take(50) {
        let f = polys
            .iter()
            .position(|p| p.contains(*x, 1e-12) && p.normal().dot(*n) > 0.99);
        let i = f.expect("the point lies on a face");
        let sum: f64 = (0..polys.len())
            .filter(|&j| j != i)
            .map(|j| point_polygon(*x, *n, &polys[j]))
            .sum();
        assert!((sum - 1.0).abs() < 1e-12, "kernel row sum {sum}");
    }
    for m in [1, 2, 4] {
        for i in [0, 77, 200, 383] {
            let sum: f64 = (0..polys.len())
                .filter(|&j| j != i)
                .map(|j| polygon_polygon_unoccluded(&polys[i], &polys[j], m))
                .sum();
            assert!((sum - 1.0).abs() < 1e-10, "m {m} row {i}: {sum}");
        }
    }

    let mut g = c.benchmark_group("form_factor");
    g.throughput(Throughput::Elements(PAIRS as u64));
    g.bench_function("point_polygon", |b| {
        b.iter(|| {
            points
                .iter()
                .map(|(x, n, j)| point_polygon(*x, *n, &polys[*j]))
                .sum::<f64>()
        })
    });
    for m in [1u32, 2, 4] {
        g.bench_function(
            BenchmarkId::new("polygon_polygon_unoccluded", format!("m={m}")),
            |b| {
                b.iter(|| {
                    pairs
                        .iter()
                        .map(|&(i, j)| {
                            polygon_polygon_unoccluded(&polys[i], &polys[j], black_box(m))
                        })
                        .sum::<f64>()
                })
            },
        );
    }
    g.finish();
}

fn with_visibility(c: &mut Criterion) {
    let scene = builtin("cornell").expect("cornell");
    let mesh = ElementMesh::new(&scene, default_element_size(&scene));
    let accel = Accel::new(&scene);
    let n = mesh.len();
    let mut r = sampling::rng(6, 0);
    let pairs: Vec<(usize, usize)> = (0..PAIRS / 4)
        .map(|_| {
            loop {
                let i = (sampling::uniform(&mut r) * n as f64) as usize;
                let j = (sampling::uniform(&mut r) * n as f64) as usize;
                let (ei, ej) = (&mesh.elements[i], &mesh.elements[j]);
                // Pairs that face each other, so every estimate casts its rays.
                if ei.face != ej.face
                    && polygon_polygon_unoccluded(&ei.polygon, &ej.polygon, 1) > 0.0
                {
                    break (i, j);
                }
            }
        })
        .collect();
    let ff = |(i, j): (usize, usize), how: VisibilitySampling, k: usize| {
        let (ei, ej) = (&mesh.elements[i], &mesh.elements[j]);
        polygon_polygon(
            &accel,
            &ei.polygon,
            ei.face as usize,
            &ej.polygon,
            ej.face as usize,
            2,
            how,
            9,
            k as u64,
        )
    };
    let hows = [
        VisibilitySampling::Unoccluded,
        VisibilitySampling::Centre,
        VisibilitySampling::Jittered2x2,
        VisibilitySampling::Jittered4x4,
        VisibilitySampling::Jittered8x8,
    ];
    let sums: Vec<f64> = hows
        .iter()
        .map(|&how| pairs.iter().enumerate().map(|(k, &p)| ff(p, how, k)).sum())
        .collect();
    let unoccluded: f64 = pairs
        .iter()
        .map(|&(i, j)| {
            polygon_polygon_unoccluded(&mesh.elements[i].polygon, &mesh.elements[j].polygon, 2)
        })
        .sum();
    assert_eq!(sums[0], unoccluded);
    assert!(sums[4] < unoccluded, "the blocks occlude some pairs");
    for s in &sums[2..4] {
        assert!(
            (s / sums[4] - 1.0).abs() < 0.02,
            "jittered estimates disagree: {sums:?}"
        );
    }
    eprintln!(
        "cornell: {n} elements; summed F over {} pairs: unoccluded {:.4}, {:?}",
        pairs.len(),
        unoccluded,
        hows.iter().zip(&sums).collect::<Vec<_>>()
    );

    let mut g = c.benchmark_group("form_factor_visibility/cornell");
    g.throughput(Throughput::Elements(pairs.len() as u64));
    g.sample_size(10);
    for how in hows {
        g.bench_function(BenchmarkId::from_parameter(format!("{how:?}")), |b| {
            b.iter(|| {
                pairs
                    .iter()
                    .enumerate()
                    .map(|(k, &p)| ff(p, how, k))
                    .sum::<f64>()
            })
        });
    }
    g.finish();
}

criterion_group!(benches, kernel_and_quadrature, with_visibility);
criterion_main!(benches);

//! What a visibility segment costs as the scene grows: the concentric spheres (a unit sphere facing out inside
//! a radius-2 sphere facing in; Christensen 1995, §8.3) at k = 10³ … 10⁶ triangles, the scene on which the
//! volume-clustered solver's cost is measured against k.
//!
//! A hierarchical radiosity solution with O(k) links casts O(k) rays, and a top-down traversal of a bounding
//! volume hierarchy descends from the root to the leaves a segment reaches, a depth that grows as log k however
//! short the segment (Havran 2000 measured ray shooting's cost growing about logarithmically in the number of
//! objects). So the time of a ray-bound
//! O(k)-link solver grows as k·c(k), where c(k) is the time of one segment on a k-triangle scene, and its
//! log-log slope in k is 1 plus that of c. This bench measures c(k) and the nodes visited per segment, for
//! the segments such a solver casts, as bundles of 16 between two faces traversed together
//! ([`Accel::visible_many`], as the cluster links cast them):
//!
//! - `near`: between two faces of the outer sphere a few cells apart (the finest links, most of a solution's);
//! - `across`: between a face of the inner sphere and one of the outer sphere, both uniform.
//!
//! Printed: per k, the segments' mean length in face sizes (√ of the mean face area), BVH nodes and triangles
//! visited per segment (`visible_between_counting`, which no other process on the machine can disturb), and
//! nanoseconds per segment, the four sizes timed in alternation (median of 7 rounds), with the log-log
//! slopes in k of both between successive sizes and over all four. Criterion then times each size alone.
//!
//! Run: `cargo bench -p radlab-scene --bench ray_depth -- --warm-up-time 1 --measurement-time 3`.

#![expect(
    missing_docs,
    reason = "criterion_group! generates an undocumented public function"
)]

use std::hint::black_box;
use std::time::Instant;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use radlab_scene::sampling::{self, Rng};
use radlab_scene::{Scene, builtin};
use radlab_visibility::{Accel, Segment};

const SIZES: [usize; 4] = [1_000, 10_000, 100_000, 1_000_000];
/// Segments per bundle between two faces (a cluster link's visibility rays).
const BUNDLE: usize = 16;
const BUNDLES: usize = 2_000;
/// Largest index step between the two faces of a `near` bundle: a cube sphere's triangles are numbered
/// along rows of cells, so this is a few cells along a row.
const NEAR_STEP: usize = 16;
const ROUNDS: usize = 7;

struct Workload {
    near: Vec<Bundle>,
    across: Vec<Bundle>,
}

/// A bundle of segments between two faces.
type Bundle = [Segment; BUNDLE];

/// A family's bundles in a workload.
type Family = fn(&Workload) -> &[Bundle];

/// The two families of bundles, by name.
const FAMILIES: [(&str, Family); 2] = [("near", |w| &w.near), ("across", |w| &w.across)];

/// A uniform index below `n`.
fn index(r: &mut Rng, n: usize) -> usize {
    ((sampling::uniform(r) * n as f64) as usize).min(n - 1)
}

fn bundle(scene: &Scene, fp: usize, fq: usize, r: &mut Rng) -> Bundle {
    let (a, b) = (scene.polygon(fp), scene.polygon(fq));
    std::array::from_fn(|_| Segment {
        p: a.sample_uniform(sampling::uniform(r), sampling::uniform(r)),
        fp,
        q: b.sample_uniform(sampling::uniform(r), sampling::uniform(r)),
        fq,
    })
}

fn workload(scene: &Scene) -> Workload {
    // The outer sphere's faces face the centre; the inner sphere's face away from it.
    let (outer, inner): (Vec<usize>, Vec<usize>) = (0..scene.faces.len())
        .partition(|&f| scene.faces[f].normal.dot(scene.faces[f].centroid) < 0.0);
    assert!(!outer.is_empty() && !inner.is_empty(), "two spheres");
    let mut r = sampling::rng(2026, 0);
    let pick = |v: &[usize], r: &mut Rng| v[index(r, v.len())];
    let mut near = Vec::with_capacity(BUNDLES);
    while near.len() < BUNDLES {
        let i = index(&mut r, outer.len());
        let step = 1 + index(&mut r, NEAR_STEP);
        if let Some(&g) = outer.get(i + step) {
            near.push(bundle(scene, outer[i], g, &mut r));
        }
    }
    let across = (0..BUNDLES)
        .map(|_| {
            let (fp, fq) = (pick(&inner, &mut r), pick(&outer, &mut r));
            bundle(scene, fp, fq, &mut r)
        })
        .collect();
    Workload { near, across }
}

/// Casts every bundle, each one `visible_many` call; returns how many segments were unobstructed.
fn cast(a: &Accel, bundles: &[Bundle]) -> usize {
    let mut out = [false; BUNDLE];
    bundles
        .iter()
        .map(|b| {
            a.visible_many(b, &mut out);
            out.iter().filter(|&&v| v).count()
        })
        .sum()
}

/// Segments per second over the bundles; one timed pass.
fn rate(a: &Accel, bundles: &[Bundle]) -> f64 {
    let t = Instant::now();
    black_box(cast(a, bundles));
    (bundles.len() * BUNDLE) as f64 / t.elapsed().as_secs_f64()
}

/// Mean length in face sizes, nodes and triangles visited per segment; and that the packets agree with
/// single segments.
fn counts(scene: &Scene, a: &Accel, bundles: &[Bundle]) -> (f64, f64, f64) {
    let h = (scene.faces.iter().map(|f| f.area).sum::<f64>() / scene.faces.len() as f64).sqrt();
    let (mut len, mut nodes, mut tris) = (0.0, 0u64, 0u64);
    let mut out = [false; BUNDLE];
    for b in bundles {
        a.visible_many(b, &mut out);
        for (s, &v) in b.iter().zip(&out) {
            let (seen, c) = a.visible_between_counting(s.p, s.fp, s.q, s.fq);
            assert_eq!(seen, v, "a packet answers as its segments alone");
            len += (s.q - s.p).length() / h;
            nodes += c.nodes as u64;
            tris += c.triangles as u64;
        }
    }
    let n = (bundles.len() * BUNDLE) as f64;
    (len / n, nodes as f64 / n, tris as f64 / n)
}

fn slope(k0: usize, y0: f64, k1: usize, y1: f64) -> f64 {
    (y1 / y0).ln() / (k1 as f64 / k0 as f64).ln()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn ray_depth(c: &mut Criterion) {
    let cases: Vec<(Scene, Accel, Workload)> = SIZES
        .iter()
        .map(|&k| {
            let scene = builtin(&format!("concentric-spheres?faces={k}")).expect("builtin scene");
            let accel = Accel::new(&scene);
            let w = workload(&scene);
            (scene, accel, w)
        })
        .collect();
    for (family, pick) in FAMILIES {
        let mut ns: Vec<Vec<f64>> = vec![Vec::new(); SIZES.len()];
        for _ in 0..ROUNDS {
            for (i, (_, a, w)) in cases.iter().enumerate() {
                ns[i].push(1e9 / rate(a, pick(w)));
            }
        }
        let ns: Vec<f64> = ns.into_iter().map(median).collect();
        let mut prev: Option<(usize, f64, f64)> = None;
        for (i, (scene, a, w)) in cases.iter().enumerate() {
            let (len, nodes, tris) = counts(scene, a, pick(w));
            let k = scene.faces.len();
            let step = prev.map_or(String::new(), |(k0, n0, t0)| {
                format!(
                    "; slope from the previous size: nodes {:.3}, time {:.3}",
                    slope(k0, n0, k, nodes),
                    slope(k0, t0, k, ns[i])
                )
            });
            eprintln!(
                "{family} k={k}: length {len:.1} face sizes, {nodes:.1} nodes, {tris:.2} triangles, \
                 {:.1} ns a segment{step}",
                ns[i]
            );
            prev = Some((k, nodes, ns[i]));
        }
        let (k0, kn) = (cases[0].0.faces.len(), cases[SIZES.len() - 1].0.faces.len());
        eprintln!(
            "{family}: time slope over {k0}..{kn} triangles {:.3}",
            slope(k0, ns[0], kn, ns[SIZES.len() - 1])
        );
    }

    for (family, pick) in FAMILIES {
        let mut g = c.benchmark_group(format!("visibility_by_faces/{family}"));
        g.throughput(Throughput::Elements((BUNDLES * BUNDLE) as u64));
        for (scene, a, w) in &cases {
            let bundles = pick(w);
            g.bench_function(BenchmarkId::from_parameter(scene.faces.len()), |b| {
                b.iter(|| black_box(cast(a, bundles)))
            });
        }
        g.finish();
    }
}

criterion_group!(benches, ray_depth);
criterion_main!(benches);

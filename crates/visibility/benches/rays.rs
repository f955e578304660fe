//! Rays per second of the shared visibility engine ([`Accel`]) where radiosity spends them: inside
//! enclosures, from points on surfaces.
//!
//! - Closest hit (`intersect_from`, a cosine-distributed bounce from a surface point, as path tracing and
//!   mesh Monte Carlo cast) and visibility (`visible_between` two surface points, as form factors and
//!   next-event estimation cast), for each [`AccelPreset`], on three enclosures: the Cornell box (36
//!   triangles, open at the front), the Cornell box tessellated 32 × 32 (about 4 · 10⁴ triangles), and the
//!   bumpy sphere in its closed room with 10⁵ and 10⁶ triangles.
//!   Closest hit is also timed with the presets in alternation (printed), which a shared machine's drifting
//!   load cannot bias.
//! - The two BVH node tests (`NodeTestKind`: obvhs's SSE test and the eight-lane AVX2 one) of the default
//!   preset in alternation, after checking that they give the same answers and visit the same nodes
//!   (printed).
//! - Bundles of 16 segments between uniform points of two faces (a form factor's visibility rays between two
//!   patches; faces chosen by area, and uniformly), one segment at a time (`visible_between`) and as packets
//!   (`visible_many`), in alternation, after checking that both give the same answers and ray counts
//!   (printed).
//! - The 2-thread speed-up of closest hit and visibility (default preset, rays split into chunks over a rayon
//!   pool of 1 and then 2 threads, in alternation; printed), and the ray count, which must be the same.
//! - BVH build time of the bumpy sphere with 10⁶ triangles on pools of 1 and 2 threads (`Fast` and `VeryFast`).
//! - BVH build time per preset, and BVH nodes and triangles visited per ray (printed once per scene and
//!   preset, from `intersect_counting` / `visible_counting` over the same rays): a cost no other process
//!   on the machine can disturb.
//!
//! Before timing, every preset must give the same answers on every ray (face and distance of the closest
//! hit, visible or not), and, on the scenes small enough for it, the same as a brute-force loop over all
//! faces. Rays are generated outside the timed loop, deterministically.
//!
//! Run: `cargo bench -p radlab-scene --bench rays -- --warm-up-time 1 --measurement-time 3`.

#![expect(
    missing_docs,
    reason = "criterion_group! generates an undocumented public function"
)]

use std::hint::black_box;
use std::time::Instant;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::DVec3;
use radlab_scene::sampling::{self, Rng};
use radlab_scene::{FaceId, Ray, Scene, builtin};
use radlab_visibility::{Accel, AccelPreset, NodeTestKind, Segment};
use rayon::prelude::*;

const PRESETS: [AccelPreset; 4] = [
    AccelPreset::Fast,
    AccelPreset::Medium,
    AccelPreset::Quality,
    AccelPreset::VeryFast,
];
const RAYS: usize = 20_000;
/// Segments per bundle between two faces (a form factor's visibility rays between two patches).
const BUNDLE: usize = 16;

/// A face chosen with probability proportional to area, and a uniform point on it.
struct SurfaceSampler {
    cdf: Vec<f64>,
}

impl SurfaceSampler {
    fn new(scene: &Scene) -> Self {
        let mut acc = 0.0;
        let cdf = scene
            .faces
            .iter()
            .map(|f| {
                acc += f.area;
                acc
            })
            .collect();
        Self { cdf }
    }

    fn sample(&self, scene: &Scene, r: &mut Rng) -> (FaceId, DVec3) {
        let total = *self.cdf.last().expect("faces");
        let x = sampling::uniform(r) * total;
        let f = self
            .cdf
            .partition_point(|&c| c <= x)
            .min(self.cdf.len() - 1);
        let p = scene
            .polygon(f)
            .sample_uniform(sampling::uniform(r), sampling::uniform(r));
        (f, p)
    }
}

/// Bounce rays (face, origin, cosine-distributed direction), visibility segments between surface points, and
/// the same number of segments in bundles of [`BUNDLE`] between uniform points of two faces, the faces chosen
/// by area (`bundles[0]`: on the bumpy sphere mostly its room's six walls, so the bundles spread) and
/// uniformly (`bundles[1]`: mostly its small triangles, so the bundles are narrow).
struct Workload {
    bounces: Vec<(FaceId, DVec3, DVec3)>,
    segments: Vec<(DVec3, FaceId, DVec3, FaceId)>,
    bundles: [Vec<Vec<Segment>>; 2],
}

fn workload(scene: &Scene) -> Workload {
    let s = SurfaceSampler::new(scene);
    let mut r = sampling::rng(2024, 0);
    let bounces = (0..RAYS)
        .map(|_| {
            let (f, x) = s.sample(scene, &mut r);
            let n = scene.faces[f].normal;
            let d = sampling::cosine_hemisphere(
                n,
                sampling::uniform(&mut r),
                sampling::uniform(&mut r),
            );
            (f, x, d)
        })
        .collect();
    let segments = (0..RAYS)
        .map(|_| {
            let (fa, a) = s.sample(scene, &mut r);
            let (fb, b) = s.sample(scene, &mut r);
            (a, fa, b, fb)
        })
        .collect();
    let mut bundle = |by_area: bool| -> Vec<Vec<Segment>> {
        let face = |r: &mut Rng| {
            if by_area {
                s.sample(scene, r).0
            } else {
                ((sampling::uniform(r) * scene.faces.len() as f64) as usize)
                    .min(scene.faces.len() - 1)
            }
        };
        (0..RAYS / BUNDLE)
            .map(|_| {
                let fp = face(&mut r);
                let fq = face(&mut r);
                let (a, b) = (scene.polygon(fp), scene.polygon(fq));
                let mut point = |poly: &radlab_scene::Polygon| {
                    poly.sample_uniform(sampling::uniform(&mut r), sampling::uniform(&mut r))
                };
                (0..BUNDLE)
                    .map(|_| Segment {
                        p: point(&a),
                        fp,
                        q: point(&b),
                        fq,
                    })
                    .collect()
            })
            .collect()
    };
    let bundles = [bundle(true), bundle(false)];
    Workload {
        bounces,
        segments,
        bundles,
    }
}

/// Brute-force closest hit over every face in f64 (the reference for the small scenes).
fn brute_force(scene: &Scene, o: DVec3, d: DVec3, skip: FaceId) -> Option<(FaceId, f64)> {
    let mut best: Option<(FaceId, f64)> = None;
    for f in 0..scene.faces.len() {
        if f == skip {
            continue;
        }
        let p = scene.polygon(f);
        let v = p.vertices();
        let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
        let t = (v[0] - o).dot(n) / n.dot(d);
        if t.is_finite()
            && t > 0.0
            && best.is_none_or(|(_, bt)| t < bt)
            && p.contains(o + t * d, 0.0)
        {
            best = Some((f, t));
        }
    }
    best
}

fn check_answers(name: &str, scene: &Scene, accels: &[Accel], w: &Workload) {
    let diag = scene.diagonal();
    let hits: Vec<Vec<Option<(FaceId, f64)>>> = accels
        .iter()
        .map(|a| {
            w.bounces
                .iter()
                .map(|&(f, x, d)| a.intersect_from(f, x, d).map(|h| (h.face, h.t)))
                .collect()
        })
        .collect();
    // Every preset gives the same answer (faces may differ only on a tie at an edge, at the same distance).
    let mut face_ties = 0;
    for k in 0..w.bounces.len() {
        for p in &hits[1..] {
            match (hits[0][k], p[k]) {
                (Some((fa, ta)), Some((fb, tb))) => {
                    assert!(
                        (ta - tb).abs() <= 1e-9 * diag,
                        "{name}: presets disagree on ray {k}"
                    );
                    face_ties += (fa != fb) as usize;
                }
                (None, None) => {}
                _ => panic!("{name}: presets disagree on whether ray {k} hits"),
            }
        }
    }
    assert!(
        face_ties * 1000 < w.bounces.len(),
        "{name}: {face_ties} ties"
    );
    let vis: Vec<Vec<bool>> = accels
        .iter()
        .map(|a| {
            w.segments
                .iter()
                .map(|&(p, fp, q, fq)| a.visible_between(p, fp, q, fq))
                .collect()
        })
        .collect();
    for v in &vis[1..] {
        let differ = v.iter().zip(&vis[0]).filter(|(a, b)| a != b).count();
        assert!(
            differ * 10_000 <= w.segments.len(),
            "{name}: visibility differs on {differ} segments"
        );
    }
    // Against brute force, on a subset small enough to afford.
    let checks = (2_000_000 / scene.faces.len()).min(w.bounces.len());
    for (k, &(f, x, d)) in w.bounces.iter().take(checks).enumerate() {
        let want = brute_force(scene, x, d, f);
        match (hits[2][k], want) {
            (Some((_, t)), Some((_, tw))) => {
                assert!(
                    (t - tw).abs() <= 1e-9 * diag,
                    "{name}: ray {k}: t {t} vs brute force {tw}"
                )
            }
            (None, None) => {}
            (got, want) => panic!("{name}: ray {k}: {got:?} vs brute force {want:?}"),
        }
    }
    let escaped = hits[2].iter().filter(|h| h.is_none()).count();
    let blocked = vis[2].iter().filter(|v| !**v).count();
    eprintln!(
        "{name}: answers agree across presets ({checks} rays also against brute force); {escaped} of {} \
         bounce rays leave the scene, {blocked} of {} segments are blocked",
        w.bounces.len(),
        w.segments.len()
    );
}

/// Closest-hit rays per second of `a` over the workload's bounces (one timed pass).
fn closest_rate(a: &Accel, w: &Workload) -> f64 {
    let t = Instant::now();
    let mut faces = 0usize;
    for &(f, x, d) in &w.bounces {
        if let Some(h) = a.intersect_from(f, x, d) {
            faces += h.face;
        }
    }
    black_box(faces);
    w.bounces.len() as f64 / t.elapsed().as_secs_f64()
}

/// Visibility rays per second of `a` over the workload's segments (one timed pass).
fn visibility_rate(a: &Accel, w: &Workload) -> f64 {
    let t = Instant::now();
    let seen = w
        .segments
        .iter()
        .filter(|&&(p, fp, q, fq)| a.visible_between(p, fp, q, fq))
        .count();
    black_box(seen);
    w.segments.len() as f64 / t.elapsed().as_secs_f64()
}

/// Visibility rays per second over the workload's bundles, one segment at a time (`visible_between`) or a
/// bundle at a time (`visible_many`); one timed pass.
fn bundle_rate(a: &Accel, bundles: &[Vec<Segment>], packets: bool) -> f64 {
    let t = Instant::now();
    let mut seen = 0usize;
    let mut out = [false; BUNDLE];
    for b in bundles {
        if packets {
            a.visible_many(b, &mut out);
            seen += out.iter().filter(|&&v| v).count();
        } else {
            seen += b
                .iter()
                .filter(|s| a.visible_between(s.p, s.fp, s.q, s.fq))
                .count();
        }
    }
    black_box(seen);
    (bundles.len() * BUNDLE) as f64 / t.elapsed().as_secs_f64()
}

/// Bundles of segments between two faces one segment at a time and as packets: first the same answers and
/// ray counts, then rays per second of each in alternation (median of 9 rounds) and their ratio; for faces
/// chosen by area and uniformly.
fn packet_comparison(name: &str, a: &Accel, w: &Workload) {
    for (bundles, chosen) in w.bundles.iter().zip(["by area", "uniformly"]) {
        let mut out = [false; BUNDLE];
        let (mut blocked, before) = (0usize, a.rays_cast());
        for b in bundles {
            a.visible_many(b, &mut out);
            let one: Vec<bool> = b
                .iter()
                .map(|s| a.visible_between(s.p, s.fp, s.q, s.fq))
                .collect();
            assert_eq!(out.as_slice(), one, "{name}: a packet answers differently");
            blocked += one.iter().filter(|&&v| !v).count();
        }
        assert_eq!(
            a.rays_cast() - before,
            2 * (bundles.len() * BUNDLE) as u64,
            "{name}: packets count other rays"
        );
        let rounds = 9;
        let (mut single, mut packed) = (Vec::new(), Vec::new());
        for _ in 0..rounds {
            single.push(bundle_rate(a, bundles, false));
            packed.push(bundle_rate(a, bundles, true));
        }
        let (s, p) = (median(&mut single), median(&mut packed));
        eprintln!(
            "{name}: bundles of {BUNDLE} segments between two faces chosen {chosen} ({blocked} of {} blocked), \
             in alternation, median of {rounds} rounds: one by one {:.3} M rays/s, packets {:.3} M rays/s \
             ({:.2}×), same answers",
            bundles.len() * BUNDLE,
            s / 1e6,
            p / 1e6,
            p / s
        );
    }
}

/// The median of `v` (sorted in place).
fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Closest-hit rays per second of each preset, timed in alternation over several rounds (median of each),
/// so that the load of a shared machine, which drifts between criterion's groups, falls on all presets alike.
fn interleaved_comparison(name: &str, accels: &[Accel], w: &Workload) {
    let rounds = 9;
    let mut rates = vec![Vec::with_capacity(rounds); accels.len()];
    for _ in 0..rounds {
        for (a, r) in accels.iter().zip(&mut rates) {
            r.push(closest_rate(a, w));
        }
    }
    let m: Vec<f64> = rates.iter_mut().map(|r| median(r)).collect();
    eprintln!(
        "{name}: interleaved closest hit, median of {rounds} rounds: Fast {:.3} M rays/s, Medium {:.3} \
         ({:.2}× Fast), Quality {:.3} ({:.2}× Fast)",
        m[0] / 1e6,
        m[1] / 1e6,
        m[1] / m[0],
        m[2] / 1e6,
        m[2] / m[0]
    );
}

/// The two node tests ([`NodeTestKind`]) of one BVH side by side: first the same answers on every ray (face
/// and distance bit for bit, visibility, nodes and triangles visited), then closest-hit and visibility rays
/// per second of each, timed in alternation (median of 9 rounds), and their ratio.
fn node_test_comparison(name: &str, scene: &Scene, w: &Workload) {
    let portable = {
        let mut a = Accel::new(scene);
        a.set_node_test(NodeTestKind::Portable);
        a
    };
    let mut avx2 = Accel::new(scene);
    if !avx2.set_node_test(NodeTestKind::Avx2) {
        eprintln!("{name}: no AVX2 on this processor; node tests not compared");
        return;
    }
    let accels = [portable, avx2];
    for &(f, x, d) in &w.bounces {
        let [a, b] = accels.each_ref().map(|a| {
            let (h, c) = a.intersect_counting(&Ray::new(x, d));
            (
                a.intersect_from(f, x, d).map(|h| (h.face, h.t.to_bits())),
                h.map(|h| (h.face, h.t.to_bits())),
                c,
            )
        });
        assert_eq!(a, b, "{name}: node tests disagree on a closest-hit ray");
    }
    for &(p, fp, q, fq) in &w.segments {
        let [a, b] = accels
            .each_ref()
            .map(|a| (a.visible_between(p, fp, q, fq), a.visible_counting(p, q)));
        assert_eq!(a, b, "{name}: node tests disagree on a segment");
    }
    let rounds = 9;
    let mut rates: [[Vec<f64>; 2]; 2] = Default::default();
    for _ in 0..rounds {
        for (k, a) in accels.iter().enumerate() {
            rates[0][k].push(closest_rate(a, w));
            rates[1][k].push(visibility_rate(a, w));
        }
    }
    for (test, r) in ["closest hit", "visibility"].iter().zip(&mut rates) {
        let (portable, avx2) = (median(&mut r[0]), median(&mut r[1]));
        eprintln!(
            "{name}: {test}, node tests in alternation, median of {rounds} rounds: Portable {:.3} M rays/s, \
             Avx2 {:.3} M rays/s ({:.2}×), same answers",
            portable / 1e6,
            avx2 / 1e6,
            avx2 / portable
        );
    }
}

/// Rays per second of the default preset on pools of 1 and 2 threads, in alternation (median of each), and
/// the speed-up; also checks that the ray count does not depend on the number of threads.
fn thread_scaling(name: &str, a: &Accel, w: &Workload) {
    let rounds = 7;
    let pools: Vec<rayon::ThreadPool> = [1, 2]
        .iter()
        .map(|&n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .expect("pool")
        })
        .collect();
    let mut rates: [[Vec<f64>; 2]; 2] = Default::default();
    let mut counts = [0u64; 2];
    for _ in 0..rounds {
        for (k, pool) in pools.iter().enumerate() {
            let before = a.rays_cast();
            // Rays per second of `cast` (one ray per item, summing what it returns) over `n` items.
            let rate = |n: usize, cast: &(dyn Fn(usize) -> usize + Sync)| {
                let t = Instant::now();
                let sum: usize =
                    pool.install(|| (0..n).into_par_iter().with_min_len(256).map(cast).sum());
                black_box(sum);
                n as f64 / t.elapsed().as_secs_f64()
            };
            rates[0][k].push(rate(w.bounces.len(), &|i| {
                let (f, x, d) = w.bounces[i];
                a.intersect_from(f, x, d).map_or(0, |h| h.face)
            }));
            rates[1][k].push(rate(w.segments.len(), &|i| {
                let (p, fp, q, fq) = w.segments[i];
                usize::from(a.visible_between(p, fp, q, fq))
            }));
            counts[k] = a.rays_cast() - before;
        }
    }
    assert_eq!(counts[0], counts[1], "{name}: ray counts differ");
    for (test, r) in ["closest hit", "visibility"].iter().zip(&mut rates) {
        let (one, two) = (median(&mut r[0]), median(&mut r[1]));
        eprintln!(
            "{name}: {test}, median of {rounds} alternating rounds: 1 thread {:.3} M rays/s, 2 threads {:.3} M rays/s, speed-up {:.2}×",
            one / 1e6,
            two / 1e6,
            two / one
        );
    }
}

fn bench_scene(c: &mut Criterion, name: &str, spec: &str) {
    let t = Instant::now();
    let scene = builtin(spec).expect("builtin scene");
    let generate = t.elapsed();
    let accels: Vec<Accel> = PRESETS
        .iter()
        .map(|&p| Accel::with_preset(&scene, p))
        .collect();
    let w = workload(&scene);
    eprintln!(
        "{name}: {} faces, {} triangles, generated in {:.2?}",
        scene.faces.len(),
        accels[0].triangle_count(),
        generate
    );
    for (preset, a) in PRESETS.iter().zip(&accels) {
        // Without the `from` face: a ray leaving a surface's front never hits that surface anyway.
        let (mut hn, mut ht, mut vn, mut vt) = (0u64, 0u64, 0u64, 0u64);
        for &(_, x, d) in &w.bounces {
            let c = a.intersect_counting(&Ray::new(x, d)).1;
            (hn, ht) = (hn + c.nodes as u64, ht + c.triangles as u64);
        }
        for &(p, _, q, _) in &w.segments {
            let c = a.visible_counting(p, q).1;
            (vn, vt) = (vn + c.nodes as u64, vt + c.triangles as u64);
        }
        let (nh, nv) = (w.bounces.len() as f64, w.segments.len() as f64);
        eprintln!(
            "{name} {preset:?}: build {:.3?}, {} bytes; per closest-hit ray {:.2} nodes, {:.2} triangles; \
             per visibility ray {:.2} nodes, {:.2} triangles",
            a.build_time(),
            a.bytes(),
            hn as f64 / nh,
            ht as f64 / nh,
            vn as f64 / nv,
            vt as f64 / nv
        );
    }
    check_answers(name, &scene, &accels, &w);
    interleaved_comparison(name, &accels, &w);
    node_test_comparison(name, &scene, &w);
    packet_comparison(name, &accels[0], &w);
    thread_scaling(name, &accels[0], &w);

    let mut g = c.benchmark_group(format!("closest_hit/{name}"));
    g.throughput(Throughput::Elements(w.bounces.len() as u64));
    for (preset, a) in PRESETS.iter().zip(&accels) {
        g.bench_function(BenchmarkId::from_parameter(format!("{preset:?}")), |b| {
            b.iter(|| {
                let mut faces = 0usize;
                for &(f, x, d) in &w.bounces {
                    if let Some(h) = a.intersect_from(f, x, d) {
                        faces += h.face;
                    }
                }
                black_box(faces)
            })
        });
    }
    g.finish();
    let mut g = c.benchmark_group(format!("visibility/{name}"));
    g.throughput(Throughput::Elements(w.segments.len() as u64));
    for (preset, a) in PRESETS.iter().zip(&accels) {
        g.bench_function(BenchmarkId::from_parameter(format!("{preset:?}")), |b| {
            b.iter(|| {
                w.segments
                    .iter()
                    .filter(|&&(p, fp, q, fq)| a.visible_between(p, fp, q, fq))
                    .count()
            })
        });
    }
    g.finish();
}

fn rays(c: &mut Criterion) {
    bench_scene(c, "cornell", "cornell");
    bench_scene(c, "cornell-32", "cornell?tessellation=32");
    bench_scene(c, "bumpy-sphere-100k", "bumpy-sphere?faces=100000");
    bench_scene(c, "bumpy-sphere-1M", "bumpy-sphere?faces=1000000");
}

fn build(c: &mut Criterion) {
    let scene = builtin("cornell?tessellation=32").expect("builtin scene");
    let mut g = c.benchmark_group("build/cornell-32");
    g.sample_size(10);
    g.throughput(Throughput::Elements(
        Accel::with_preset(&scene, AccelPreset::Fast).triangle_count() as u64,
    ));
    for preset in PRESETS {
        g.bench_function(BenchmarkId::from_parameter(format!("{preset:?}")), |b| {
            b.iter(|| Accel::with_preset(&scene, preset).triangle_count())
        });
    }
    g.finish();
    let scene = builtin("bumpy-sphere?faces=1000000").expect("builtin scene");
    let mut g = c.benchmark_group("build/bumpy-sphere-1M");
    g.sample_size(10);
    g.throughput(Throughput::Elements(
        Accel::new(&scene).triangle_count() as u64
    ));
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        g.bench_function(
            BenchmarkId::new("Fast", format!("{threads}-threads")),
            |b| b.iter(|| pool.install(|| Accel::new(&scene).triangle_count())),
        );
        g.bench_function(
            BenchmarkId::new("VeryFast", format!("{threads}-threads")),
            |b| {
                b.iter(|| {
                    pool.install(|| {
                        Accel::with_preset(&scene, AccelPreset::VeryFast).triangle_count()
                    })
                })
            },
        );
    }
    g.finish();
}

criterion_group!(benches, rays, build);
criterion_main!(benches);

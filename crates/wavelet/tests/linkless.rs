//! Linkless shooting (Stamminger, Schirmacher, Slusallek & Seidel 1998) against the linked solver: the same
//! Galerkin system, so the same answer within the oracle's tolerance; the furnace B = E/(1 − ρ) at ρ =
//! 0.999; energy balance in a closed room; the link cache changes no number and saves kernel evaluations.

use glam::DVec3;
use radlab_method::{Solution, Solver, Stats, Step};
use radlab_scene::{Rgb, Scene, SceneBuilder};
use radlab_testkit::{add_box, material, room};
use radlab_visibility::Accel;
use radlab_wavelet::{
    Basis, Engines, WaveletOracle, WaveletParams, WaveletReconstruction, WaveletSolver,
};

fn solve<'a>(scene: &'a Scene, accel: &'a Accel, params: WaveletParams) -> WaveletSolver<'a> {
    let mut s = WaveletSolver::new(scene, accel, params, 7).expect("solver");
    for _ in 0..10_000 {
        if s.step().expect("step") != Step::Continue {
            return s;
        }
    }
    panic!("no convergence");
}

/// Points at (s, t) ∈ {1/8, 3/8, 5/8, 7/8}² of every quad face.
fn points(scene: &Scene) -> Vec<(usize, DVec3)> {
    let mut out = Vec::new();
    for f in 0..scene.face_count() {
        let p = scene.polygon(f);
        let v = p.vertices();
        if v.len() != 4 {
            continue;
        }
        for j in 0..4 {
            for i in 0..4 {
                let (s, t) = ((2 * i + 1) as f64 / 8.0, (2 * j + 1) as f64 / 8.0);
                let q = v[0] * (1.0 - s) * (1.0 - t)
                    + v[1] * s * (1.0 - t)
                    + v[2] * s * t
                    + v[3] * (1.0 - s) * t;
                out.push((f, q));
            }
        }
    }
    out
}

/// Σ |a − b| / Σ |b| over the points (all channels).
fn relative_l1(a: &dyn Solution, b: &dyn Solution, pts: &[(usize, DVec3)]) -> f64 {
    let (mut d, mut n) = (0.0, 0.0);
    for &(f, p) in pts {
        let (x, y) = (a.radiosity_at(f, p), b.radiosity_at(f, p));
        d += (x - y).abs().element_sum();
        n += y.abs().element_sum();
    }
    d / n
}

/// (Σ A E, Σ A (1 − ρ) H) over the leaves, H the mean irradiance coefficient: emitted and absorbed power.
fn power_balance(s: &WaveletSolver<'_>) -> (Rgb, Rgb) {
    macro_rules! scan {
        ($r:expr) => {{
            let e = &$r.engine;
            let (mut emitted, mut absorbed) = (Rgb::ZERO, Rgb::ZERO);
            for i in 0..e.nodes().len() as u32 {
                if e.is_leaf(i) {
                    let n = &e.nodes()[i as usize];
                    emitted += n.area * n.emission;
                    absorbed +=
                        n.area * (Rgb::ONE - n.reflectance) * e.irradiance()[i as usize].0[0];
                }
            }
            (emitted, absorbed)
        }};
    }
    match s.engines() {
        Engines::K1(r) => scan!(r),
        Engines::K4(r) => scan!(r),
        Engines::K9(r) => scan!(r),
    }
}

fn link_count(s: &WaveletSolver<'_>) -> usize {
    match s.engines() {
        Engines::K1(r) => r.engine.link_count(),
        Engines::K4(r) => r.engine.link_count(),
        Engines::K9(r) => r.engine.link_count(),
    }
}

fn counter(s: &WaveletSolver<'_>, name: &str) -> u64 {
    s.counters()
        .into_iter()
        .find(|(n, _)| *n == name)
        .map(|(_, v)| v)
        .unwrap_or_else(|| panic!("no counter {name}"))
}

fn show(label: &str, st: &Stats) {
    eprintln!(
        "{label}: {} elements, {} links, {} kernel evaluations, {} rays, {} bytes",
        st.elements, st.links, st.form_factors, st.rays, st.bytes
    );
}

/// The furnace at ρ = 0.999, shot without links, links between leaves of one level (ε far below every
/// link's estimate, elements of half a side, as the linked solver's furnace test): every leaf mean E/(1 − ρ)
/// and every non-constant coefficient zero, to the f32 storage of the tensors magnified by 1/(1 − ρ) = 1000
/// (1e-7 × 1000), after a few sweeps (the coarse correction removes the furnace's mode once no element is
/// split any more).
#[test]
fn the_furnace_holds_when_shooting() {
    let mut b = SceneBuilder::new("furnace");
    let m = material(&mut b, "m", 0.999, 1.0);
    add_box(&mut b, DVec3::ZERO, DVec3::ONE, 1, m, false);
    let scene = b.build().expect("scene");
    let accel = Accel::new(&scene);
    let want = 1000.0;
    for basis in [Basis::Haar, Basis::M2, Basis::M3] {
        let params = WaveletParams {
            basis,
            epsilon: 1e-9,
            oracle: WaveletOracle::F,
            min_element_size: Some(0.5),
            tolerance: 1e-9,
            linkless: true,
            ..WaveletParams::default()
        };
        let s = solve(&scene, &accel, params);
        assert_eq!(link_count(&s), 0, "{basis:?}: linkless holds no links");
        macro_rules! scan {
            ($r:expr) => {{
                let e = &$r.engine;
                let (mut hi, mut mean, mut n) = (0.0f64, 0.0f64, 0);
                for i in 0..e.nodes().len() as u32 {
                    if e.is_leaf(i) {
                        n += 1;
                        mean = mean.max((e.radiosity()[i as usize].x - want).abs() / want);
                        for c in &e.exitance()[i as usize].0[1..] {
                            hi = hi.max(c.abs().max_element() / want);
                        }
                    }
                }
                (hi, mean, n)
            }};
        }
        let (coef, mean, leaves) = match s.engines() {
            Engines::K1(r) => scan!(r),
            Engines::K4(r) => scan!(r),
            Engines::K9(r) => scan!(r),
        };
        eprintln!(
            "{basis:?}: {leaves} leaves, mean off {mean:.2e}, coefficient {coef:.2e}, sweeps {}",
            counter(&s, "sweeps")
        );
        assert_eq!(leaves, 24, "{basis:?}");
        assert!(mean < 1e-3, "{basis:?}: mean off by {mean}");
        assert!(coef < 1e-3, "{basis:?}: non-constant coefficient {coef}");
    }
}

/// Linked and linkless solve the same system B = E + M B with links refined by the same oracle at the same
/// ε; what differs is the light each link is weighed by (the source's radiosity, or each shot's unshot
/// part), so each link's accepted error is at most ε of the scene's mean radiosity either way. Over the
/// bounces that error is multiplied by at most 1/(1 − ρ_max): the answers at points agree to ε/(1 − ρ_max)
/// (+ the two convergence tolerances). The room is closed, so what is emitted is absorbed; the discrete
/// operator gains or loses power only through its links' quadrature, whose error the oracle bounds per link
/// by ε of the scene's mean radiosity: the balance holds to ε in both. Linkless holds no link.
#[test]
fn linkless_matches_linked_and_balances_power() {
    let scene = room("room", &|_| {});
    let accel = Accel::new(&scene);
    let pts = points(&scene);
    let rho_max = 0.7;
    for basis in [Basis::Haar, Basis::M2] {
        let params = WaveletParams {
            basis,
            epsilon: 0.02,
            min_element_size: Some(0.05),
            reconstruction: WaveletReconstruction::Basis,
            ..WaveletParams::default()
        };
        let linked = solve(&scene, &accel, params.clone());
        let linkless = solve(
            &scene,
            &accel,
            WaveletParams {
                linkless: true,
                ..params.clone()
            },
        );
        show(&format!("{basis:?} linked"), &linked.stats());
        show(&format!("{basis:?} linkless"), &linkless.stats());
        assert_eq!(link_count(&linkless), 0);
        let d = relative_l1(&linkless, &linked, &pts);
        let bound = params.epsilon / (1.0 - rho_max) + 2.0 * params.tolerance;
        eprintln!("{basis:?}: relative L1 linkless vs linked {d:.3e} (bound {bound:.3e})");
        assert!(d < bound, "{basis:?}: {d} ≥ {bound}");
        for (label, s) in [("linked", &linked), ("linkless", &linkless)] {
            let (e, a) = power_balance(s);
            let off = ((a - e).abs() / e.max(Rgb::splat(1e-30))).max_element();
            eprintln!("{basis:?} {label}: absorbed/emitted − 1 = {off:.2e}");
            assert!(
                off < params.epsilon,
                "{basis:?} {label}: power off by {off}"
            );
        }
    }
}

/// The cache only saves work: the same leaves, radiosity and answers bit for bit, fewer kernel
/// evaluations and rays, hits reported.
#[test]
fn the_link_cache_changes_no_number() {
    let scene = room("room", &|_| {});
    let accel = Accel::new(&scene);
    let pts = points(&scene);
    let params = WaveletParams {
        basis: Basis::M2,
        epsilon: 0.02,
        min_element_size: Some(0.05),
        linkless: true,
        reconstruction: WaveletReconstruction::Basis,
        ..WaveletParams::default()
    };
    let plain = solve(&scene, &accel, params.clone());
    let cached = solve(
        &scene,
        &accel,
        WaveletParams {
            link_cache_mib: 64.0,
            ..params
        },
    );
    assert_eq!(plain.leaves(), cached.leaves());
    for &(f, p) in &pts {
        assert_eq!(plain.radiosity_at(f, p), cached.radiosity_at(f, p));
    }
    let (a, b) = (plain.stats(), cached.stats());
    show("no cache", &a);
    show("cache", &b);
    assert_eq!(counter(&plain, "link_cache_hits"), 0);
    assert!(counter(&cached, "link_cache_hits") > 0);
    assert!(
        b.form_factors < a.form_factors,
        "{} vs {}",
        b.form_factors,
        a.form_factors
    );
    assert!(b.rays < a.rays, "{} vs {}", b.rays, a.rays);
}

/// Shooting is deterministic for any thread count: links are computed in parallel but applied in a fixed
/// order, so one thread and three give the same leaves and answers bit for bit.
#[test]
fn shooting_does_not_depend_on_the_thread_count() {
    let scene = room("room", &|_| {});
    let accel = Accel::new(&scene);
    let pts = points(&scene);
    let params = WaveletParams {
        basis: Basis::M2,
        epsilon: 0.05,
        min_element_size: Some(0.05),
        linkless: true,
        link_cache_mib: 1.0,
        reconstruction: WaveletReconstruction::Basis,
        ..WaveletParams::default()
    };
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        pool.install(|| {
            let s = solve(&scene, &accel, params.clone());
            let answers: Vec<Rgb> = pts.iter().map(|&(f, p)| s.radiosity_at(f, p)).collect();
            (s.leaves(), answers, s.stats().form_factors)
        })
    };
    assert_eq!(run(1), run(3));
}

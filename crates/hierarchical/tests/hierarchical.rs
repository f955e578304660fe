//! Cross-module behaviour of hierarchical radiosity against answers nobody here chose: the furnace
//! (B = E/(1 − ρ) in any closed uniform scene), Howell's plate form factors, energy balance, the matrix method on
//! the same scene, and invariances (scale, thread count, schedule).

use glam::{DVec3, dvec3};
use radlab_answer::Reconstruction;
use radlab_hierarchical::{Gather, HierarchicalParams, HierarchicalSolver, Oracle, Schedule};
use radlab_method::{MethodParams, Solution, Solver, Step, evaluation_points};
use radlab_scene::{Material, Rgb, Scene, SceneBuilder};
use radlab_visibility::Accel;

/// The defaults, answering points with the leaves' own values (`constant`): what these tests compare.
fn leaf_params() -> HierarchicalParams {
    HierarchicalParams {
        answer: radlab_answer::AnswerParams {
            reconstruction: Reconstruction::Constant,
            ..radlab_answer::AnswerParams::default()
        },
        ..HierarchicalParams::default()
    }
}

fn solve<'a>(scene: &'a Scene, accel: &'a Accel, p: HierarchicalParams) -> HierarchicalSolver<'a> {
    let mut s = HierarchicalSolver::new(scene, accel, p, 7).expect("valid parameters");
    while s.step().expect("step") == Step::Continue {}
    s
}

/// A unit box (inward faces, one quad each) with a 0.25 × 0.25 light just below the ceiling and a floating
/// cube of side 0.25 casting a shadow: occlusion and interreflection in 13 faces.
fn shadow_box() -> Scene {
    let mut b = SceneBuilder::new("shadow-box");
    let white = b
        .add_material(Material::new("white", Rgb::splat(0.7), Rgb::ZERO).expect("m"))
        .expect("m");
    let red = b
        .add_material(Material::new("red", Rgb::new(0.6, 0.1, 0.1), Rgb::ZERO).expect("m"))
        .expect("m");
    let light = b
        .add_material(Material::new("light", Rgb::ZERO, Rgb::splat(20.0)).expect("m"))
        .expect("m");
    let quad = |b: &mut SceneBuilder, o: DVec3, u: DVec3, v: DVec3, m: u32| {
        b.add_polygon_points(&[o, o + u, o + u + v, o + v], m, "box")
            .expect("quad");
    };
    let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
    // Room: normals u × v point inward.
    quad(&mut b, DVec3::ZERO, x, y, white); // floor z = 0, +z
    quad(&mut b, z, y, x, white); // ceiling, -z
    quad(&mut b, DVec3::ZERO, y, z, red); // x = 0, +x
    quad(&mut b, x, z, y, white); // x = 1, -x
    quad(&mut b, DVec3::ZERO, z, x, white); // y = 0, +y
    quad(&mut b, y, x, z, white); // y = 1, -y
    // Light facing down, just below the ceiling.
    let l = dvec3(0.375, 0.375, 0.999);
    quad(&mut b, l, 0.25 * y, 0.25 * x, light);
    // Floating cube [0.4, 0.65]² × [0.3, 0.55], outward normals.
    let (o, s) = (dvec3(0.4, 0.4, 0.3), 0.25);
    let (sx, sy, sz) = (s * x, s * y, s * z);
    quad(&mut b, o, sy, sx, white); // bottom, -z
    quad(&mut b, o + sz, sx, sy, white); // top, +z
    quad(&mut b, o, sz, sy, white); // x-, -x
    quad(&mut b, o + sx, sy, sz, white); // x+, +x
    quad(&mut b, o, sx, sz, white); // y-, -y
    quad(&mut b, o + sy, sz, sx, white); // y+, +y
    b.build().expect("scene")
}

/// Area-weighted relative L1 difference of two solutions at shared evaluation points.
fn difference(scene: &Scene, a: &dyn Solution, b: &dyn Solution) -> f64 {
    let pts = evaluation_points(scene, 2000, 11);
    let (mut num, mut den) = (0.0, 0.0);
    for p in &pts {
        let (x, y) = (
            a.radiosity_at(p.face, p.point),
            b.radiosity_at(p.face, p.point),
        );
        num += (x - y).abs().element_sum();
        den += y.abs().element_sum();
    }
    num / den
}

#[test]
fn furnace_cube_and_sphere_give_e_over_one_minus_rho() {
    for spec in [
        "furnace-cube?tessellation=2",
        "furnace-sphere?tessellation=2",
    ] {
        for rho in [0.0, 0.5, 0.9, 0.999] {
            let scene = radlab_scene::builtin(&format!("{spec}&reflectance={rho}&emission=2"))
                .expect("builtin");
            let accel = Accel::new(&scene);
            let exact = 2.0 / (1.0 - rho);
            for (oracle, reconstruction) in [
                (Oracle::F, Reconstruction::Constant),
                (Oracle::Variation, Reconstruction::Gouraud),
                (Oracle::F, Reconstruction::FinalGather),
            ] {
                let p = HierarchicalParams {
                    oracle,
                    answer: radlab_answer::AnswerParams {
                        reconstruction,
                        ..radlab_answer::AnswerParams::default()
                    },
                    epsilon: 0.01,
                    min_element_size: Some(scene.diagonal() / 30.0),
                    visibility: radlab_kernels::form_factor::VisibilitySampling::Jittered2x2,
                    ..leaf_params()
                };
                let s = solve(&scene, &accel, p);
                if oracle == Oracle::F || rho > 0.0 {
                    assert!(
                        s.stats().elements > scene.face_count() as u64,
                        "{spec}: refined"
                    );
                }
                for (f, _, b) in s.leaves() {
                    let rel = (b - Rgb::splat(exact)).abs().max_element() / exact;
                    assert!(
                        rel < 0.01,
                        "{spec} rho={rho} {oracle:?}: face {f} B={b} vs {exact}"
                    );
                }
                for p in evaluation_points(&scene, 300, 3) {
                    let b = s.radiosity_at(p.face, p.point);
                    let rel = (b - Rgb::splat(exact)).abs().max_element() / exact;
                    assert!(
                        rel < 0.01,
                        "{spec} rho={rho} {reconstruction:?}: B={b} vs {exact}"
                    );
                }
            }
        }
    }
}

#[test]
fn classic_link_gather_errs_near_rho_one_where_leaf_gather_does_not() {
    // The per-link mean pushed down (HSA91) gives leaves near the cube's edges form-factor sums far from one;
    // that error is magnified by 1/(1 − ρ). The leaf gather's sums are exact.
    let scene =
        radlab_scene::builtin("furnace-cube?tessellation=1&reflectance=0.9").expect("scene");
    let accel = Accel::new(&scene);
    let spread = |gather| {
        let p = HierarchicalParams {
            gather,
            oracle: Oracle::F,
            schedule: Schedule::TwoStage,
            epsilon: 0.05,
            min_element_size: Some(scene.diagonal() / 30.0),
            ..leaf_params()
        };
        let s = solve(&scene, &accel, p);
        let bs: Vec<f64> = s.leaves().iter().map(|l| l.2.x).collect();
        let (lo, hi) = bs
            .iter()
            .fold((f64::MAX, 0.0f64), |a, &b| (a.0.min(b), a.1.max(b)));
        (hi - lo) / 10.0
    };
    assert!(spread(Gather::Leaf) < 1e-9);
    assert!(spread(Gather::Link) > 0.05, "{}", spread(Gather::Link));
}

#[test]
fn plates_match_howells_form_factors() {
    // Receiver's area-mean radiosity is ρ E F: parallel coaxial unit squares F = 0.199825 (Howell C-11),
    // perpendicular squares sharing an edge F = 0.200044 (Howell C-14).
    for (spec, f) in [
        ("parallel-squares?reflectance=0.5&emission=1", 0.199825),
        ("perpendicular-squares?reflectance=0.5&emission=1", 0.200044),
    ] {
        let scene = radlab_scene::builtin(spec).expect("scene");
        let accel = Accel::new(&scene);
        for gather in [Gather::Leaf, Gather::Link] {
            let p = HierarchicalParams {
                gather,
                ..leaf_params()
            };
            let s = solve(&scene, &accel, p);
            let (mut a, mut ab) = (0.0, 0.0);
            for (face, area, b) in s.leaves() {
                if face == 0 {
                    a += area;
                    ab += area * b.x;
                }
            }
            let mean = ab / a;
            let exact = 0.5 * f;
            assert!(
                (mean - exact).abs() < 2e-3 * exact,
                "{spec} {gather:?}: {mean} vs {exact}"
            );
        }
    }
}

#[test]
fn error_against_matrix_falls_as_epsilon_shrinks() {
    let scene = shadow_box();
    let accel = Accel::new(&scene);
    let h = 1.0 / 8.0;
    // Constant elements on both sides: the comparison is of the two discrete solutions, not of a
    // reconstruction.
    let mp = radlab_matrix::MatrixParams {
        element_size: Some(h),
        answer: radlab_answer::AnswerParams {
            reconstruction: radlab_answer::Reconstruction::Constant,
            ..radlab_answer::AnswerParams::default()
        },
        ..radlab_matrix::MatrixParams::default()
    };
    let mut m = radlab_matrix::MatrixSolver::new(&scene, &accel, mp, 5).expect("matrix");
    while m.step().expect("matrix step") == Step::Continue {}
    let mut errors = Vec::new();
    for epsilon in [0.2, 0.05, 0.0125, 0.003] {
        let p = HierarchicalParams {
            epsilon,
            oracle: Oracle::F,
            min_element_size: Some(h),
            ..leaf_params()
        };
        let s = solve(&scene, &accel, p);
        errors.push((epsilon, difference(&scene, &s, &m), s.stats().elements));
    }
    for w in errors.windows(2) {
        assert!(w[1].1 < w[0].1, "not decreasing: {errors:?}");
    }
    assert!(errors[errors.len() - 1].1 < 0.03, "{errors:?}");
}

#[test]
fn links_per_element_stay_bounded_as_elements_grow() {
    // Hanrahan, Salzman & Aupperle 1991: with the F oracle each element has at most about 1/ε links, however many elements there
    // are. Fixed geometry and ε; a smaller minimum element size lets the mesh grow.
    let scene = shadow_box();
    let accel = Accel::new(&scene);
    let epsilon = 0.02;
    let mut ratios = Vec::new();
    for min_size in [1.0 / 8.0, 1.0 / 16.0, 1.0 / 32.0, 1.0 / 64.0] {
        let p = HierarchicalParams {
            epsilon,
            oracle: Oracle::F,
            schedule: Schedule::TwoStage,
            min_element_size: Some(min_size),
            ..leaf_params()
        };
        let mut s = HierarchicalSolver::new(&scene, &accel, p, 1).expect("solver");
        // Refinement only: the links do not depend on the solution with the F oracle.
        while s.engine().residual().is_none() {
            assert_eq!(s.step().expect("step"), Step::Continue);
        }
        let st = s.stats();
        ratios.push((min_size, st.links as f64 / st.elements as f64, st.elements));
    }
    assert!(
        ratios[3].2 > 8 * ratios[0].2,
        "elements should grow: {ratios:?}"
    );
    for r in &ratios {
        assert!(r.1 < 1.0 / epsilon, "{ratios:?}");
    }
    for w in ratios.windows(2) {
        assert!(w[1].1 < 1.1 * w[0].1, "links per element grew: {ratios:?}");
    }
}

#[test]
fn emitted_power_is_absorbed_in_a_closed_unoccluded_scene() {
    // A cube of 24 quads with varied reflectance and two emitting faces; convex, so visibility is exact.
    let mut b = SceneBuilder::new("balance");
    let mats: Vec<u32> = (0..5)
        .map(|i| {
            let e = if i == 0 {
                Rgb::new(5.0, 3.0, 1.0)
            } else {
                Rgb::ZERO
            };
            let rho = Rgb::new(0.2 + 0.15 * i as f64, 0.8 - 0.1 * i as f64, 0.5);
            b.add_material(Material::new(&format!("m{i}"), rho, e).expect("m"))
                .expect("m")
        })
        .collect();
    let faces = [
        (DVec3::ZERO, DVec3::X, DVec3::Y),
        (DVec3::Z, DVec3::Y, DVec3::X),
        (DVec3::ZERO, DVec3::Y, DVec3::Z),
        (DVec3::X, DVec3::Z, DVec3::Y),
        (DVec3::ZERO, DVec3::Z, DVec3::X),
        (DVec3::Y, DVec3::X, DVec3::Z),
    ];
    let mut k = 0;
    for (o, u, v) in faces {
        for j in 0..2 {
            for i in 0..2 {
                let p = o + 0.5 * (i as f64 * u + j as f64 * v);
                let m = mats[k % 5];
                k += 1;
                b.add_polygon_points(&[p, p + 0.5 * u, p + 0.5 * (u + v), p + 0.5 * v], m, "q")
                    .expect("quad");
            }
        }
    }
    let scene = b.build().expect("scene");
    let accel = Accel::new(&scene);
    // Rows are exact (each leaf's form factors sum to one), and so are columns up to quadrature: a source
    // node sends its leaves' radiosity weighted by how much each sees the receiver.
    for epsilon in [0.08, 0.02] {
        let p = HierarchicalParams {
            tolerance: 1e-8,
            epsilon,
            oracle: Oracle::F,
            ..leaf_params()
        };
        let s = solve(&scene, &accel, p);
        assert_power_balanced(&s, &format!("epsilon {epsilon}"));
    }
}

/// A unit box whose sides are 3 × 3 quads (inward normals), the centre of the ceiling a flush emitter
/// (ρ = 0, so it absorbs what reaches it): convex, so nothing is occluded, yet lit unevenly.
fn flush_lamp_box() -> Scene {
    let mut b = SceneBuilder::new("flush-lamp-box");
    let wall = b
        .add_material(Material::new("wall", Rgb::new(0.6, 0.5, 0.3), Rgb::ZERO).expect("m"))
        .expect("m");
    let lamp = b
        .add_material(Material::new("lamp", Rgb::ZERO, Rgb::splat(10.0)).expect("m"))
        .expect("m");
    let sides = [
        (DVec3::ZERO, DVec3::X, DVec3::Y),
        (DVec3::Z, DVec3::Y, DVec3::X), // the ceiling, normal −z
        (DVec3::ZERO, DVec3::Y, DVec3::Z),
        (DVec3::X, DVec3::Z, DVec3::Y),
        (DVec3::ZERO, DVec3::Z, DVec3::X),
        (DVec3::Y, DVec3::X, DVec3::Z),
    ];
    for (side, (o, u, v)) in sides.into_iter().enumerate() {
        let (u, v) = (u / 3.0, v / 3.0);
        for j in 0..3 {
            for i in 0..3 {
                let p = o + i as f64 * u + j as f64 * v;
                let m = if side == 1 && i == 1 && j == 1 {
                    lamp
                } else {
                    wall
                };
                b.add_polygon_points(&[p, p + u, p + u + v, p + v], m, "q")
                    .expect("quad");
            }
        }
    }
    b.build().expect("scene")
}

/// Asserts that the power absorbed at the leaves, Σ A (1 − ρ) H, differs from the emitted power by no more
/// than what may remain in a convex scene when each link's exchange is integrated over its receiver's leaves
/// (the gather) and weighted over its source's leaves (what the source sends): Σ over links of the source's
/// brightest leaf times the difference of the two quadratures of the same exact A_r F_rs, Σ_t A_t F_{t→s}
/// and Σ_y A_y F_{y→r}, plus what visibility rays that miss take (nothing occludes in a convex scene), plus
/// the solver's remaining error (its estimate, relative to the leaves' total power Σ A B).
fn assert_power_balanced(s: &HierarchicalSolver<'_>, what: &str) {
    let e = s.engine();
    let nodes = e.nodes();
    let leaves_below = |i: u32| {
        let mut out = Vec::new();
        let mut stack = vec![i];
        while let Some(j) = stack.pop() {
            if e.is_leaf(j) {
                out.push(j);
            } else {
                stack.extend(e.children(j));
            }
        }
        out
    };
    let (mut absorbed, mut bound) = (Rgb::ZERO, Rgb::ZERO);
    for i in 0..nodes.len() as u32 {
        let n = &nodes[i as usize];
        if e.is_leaf(i) {
            absorbed += n.area * (Rgb::ONE - n.reflectance) * e.irradiance()[i as usize];
        }
        let recv = leaves_below(i);
        for l in e.links_of(i) {
            let src = &nodes[l.source as usize];
            let ys = leaves_below(l.source);
            let q_recv: f64 = recv
                .iter()
                .map(|&t| nodes[t as usize].area * e.kernel().kernel_mean(&nodes[t as usize], src))
                .sum();
            let q_src: f64 = ys
                .iter()
                .map(|&y| nodes[y as usize].area * e.kernel().kernel_mean(&nodes[y as usize], n))
                .sum();
            let brightest = ys
                .iter()
                .fold(Rgb::ZERO, |m, &y| m.max(e.radiosity()[y as usize]));
            let v = l.visibility as f64;
            bound += brightest * ((v * (q_recv - q_src)).abs() + (1.0 - v) * q_recv);
        }
    }
    let residual = e.residual().expect("solved");
    for (_, a, b) in s.leaves() {
        bound += residual * a * b;
    }
    let emitted = s.scene().emitted_power();
    let imbalance = (absorbed - emitted).abs() / emitted;
    let bound = bound / emitted;
    for k in 0..3 {
        assert!(
            imbalance[k] <= bound[k],
            "{what}, channel {k}: imbalance {imbalance} exceeds the quadrature and visibility bound {bound}"
        );
    }
}

#[test]
fn emitted_power_is_absorbed_under_the_light_driven_default_schedule() {
    // The default oracle and schedule refine links from lit sources after solving, so receivers see one
    // face through links at different levels: near ones through small elements, far ones through its whole
    // area. A link from an inner node must then send the mean of its leaves weighted by how much each sees
    // the receiver (A_y F_{y→r}); their area mean hands every leaf the same share of the far receivers,
    // whatever its near ones took, and the column sums of the operator vary within a face against its
    // radiosity (dark corners over-send, bright centres under-send): 1% to 2% of the power was lost here.
    // What may remain: the receiver-side and the source-side quadratures of each link's exchange
    // (Σ_t A_t F_{t→s} over the receiver's leaves and Σ_y A_y F_{y→r} over the source's, the same exact
    // A_r F_rs), and visibility rays that miss (nothing occludes in a convex box), at the source's
    // brightest leaf; the solver's own error is below its tolerance.
    let scene = flush_lamp_box();
    let accel = Accel::new(&scene);
    let p = HierarchicalParams {
        tolerance: 1e-9,
        ..leaf_params()
    };
    let s = solve(&scene, &accel, p);
    assert!(
        s.stats().elements > 4 * scene.face_count() as u64,
        "refined"
    );
    assert_power_balanced(&s, "defaults");
}

/// The closed unit room of radlab-testkit's test scenes with a panel (ρ = 0.5, facing up) a millimetre above
/// its floor over x, y ∈ [0.13, 0.71]: with elements no smaller than 0.25 the panel's edges cross floor
/// leaves, which then lie partly under it, where they see only its back.
fn covered_room() -> Scene {
    radlab_testkit::room("covered-room", &|b| {
        let m = radlab_testkit::material(b, "panel", 0.5, 0.0);
        let (lo, hi, z) = (0.13, 0.71, 1e-3);
        b.add_polygon_points(
            &[
                dvec3(lo, lo, z),
                dvec3(hi, lo, z),
                dvec3(hi, hi, z),
                dvec3(lo, hi, z),
            ],
            m,
            "panel",
        )
        .expect("panel");
    })
}

/// Energy balance across a contact. A leaf that straddles the panel's edge receives only on its open share
/// o; held as an area mean B̄ = o B and sent from its whole area, (1 − o) of what it sends would go into the
/// panel's back (which absorbs it): the loss L = Σ (1 − o) o A B over the straddling leaves, computed from
/// the same solution (it must be a visible share of the emitted power, or the scene tests nothing). Held over
/// the open part (B, H) and sent with weights o A F, what is absorbed, Σ o A (1 − ρ) H, matches what is
/// emitted, Σ o A E, up to the mismatch at each straddling leaf between its open share o (16 stratified
/// probe points) and what its links' visibility (16 stratified rays each) lets through, V: the leaf's light
/// reaches others in the ratio V/o, and its gains are capped where V/o > 1, so it gains or loses
/// |V − o| A B. Each estimate is resolved to 1/16 of the leaf, |V − o| ≤ 2/16: the imbalance must be at
/// most (2/16) Σ A B over the straddling leaves, plus the solver's remaining error. Without open shares it
/// is L, which must exceed that bound.
#[test]
fn energy_balance_across_a_contact() {
    let scene = covered_room();
    let accel = Accel::new(&scene);
    let p = HierarchicalParams {
        tolerance: 1e-8,
        min_element_size: Some(0.25),
        ..leaf_params()
    };
    let s = solve(&scene, &accel, p);
    let e = s.engine();
    let (open, h, b) = (e.open_shares(), e.irradiance(), e.radiosity());
    let (mut emitted, mut absorbed, mut loss, mut power, mut mismatch) =
        (Rgb::ZERO, Rgb::ZERO, Rgb::ZERO, Rgb::ZERO, Rgb::ZERO);
    let (mut straddling, mut sealed) = (0, 0);
    for (i, n) in e.nodes().iter().enumerate() {
        if !e.is_leaf(i as u32) {
            continue;
        }
        let o = open[i];
        emitted += o * n.area * n.emission;
        absorbed += o * n.area * (Rgb::ONE - n.reflectance) * h[i];
        power += o * n.area * b[i];
        if o == 0.0 {
            sealed += 1;
        } else if o < 1.0 {
            straddling += 1;
            loss += (1.0 - o) * o * n.area * b[i];
            mismatch += 2.0 / 16.0 * n.area * b[i];
        }
    }
    let imbalance = (emitted - absorbed).abs();
    let bound = mismatch + e.residual().expect("solved") * power;
    println!(
        "{straddling} straddling leaves, {sealed} sealed; emitted {emitted}, absorbed {absorbed}; \
         imbalance {imbalance}, bound {bound}, loss without open shares {loss}"
    );
    assert!(straddling >= 4, "{straddling}");
    for c in 0..3 {
        assert!(loss[c] > bound[c], "loss {loss} within the bound {bound}");
        assert!(
            imbalance[c] <= bound[c],
            "channel {c}: imbalance {imbalance} > the open shares' resolution {bound}"
        );
    }
}

#[test]
fn schedules_reach_the_same_answer() {
    // With the geometric oracle and α = 1 every schedule builds the same links (rays are drawn per pair of
    // elements, whatever order they were made in), so the answers agree to the solver's tolerance. With the
    // light-driven oracle, interleaved and scheduled refine from the solution and agree to a fraction of the
    // method's error; two-stage sees emission only when it refines (Willmott 2000, §2.4.3) and is not compared.
    let scene = shadow_box();
    let accel = Accel::new(&scene);
    let run = |schedule, oracle| {
        let p = HierarchicalParams {
            schedule,
            oracle,
            alpha: if oracle == Oracle::F { 1.0 } else { 2.0 },
            epsilon: 0.02,
            tolerance: 1e-6,
            ..leaf_params()
        };
        solve(&scene, &accel, p)
    };
    let f: Vec<_> = [
        Schedule::TwoStage,
        Schedule::Interleaved,
        Schedule::Scheduled,
    ]
    .into_iter()
    .map(|s| run(s, Oracle::F))
    .collect();
    for a in &f {
        assert_eq!(a.stats().links, f[0].stats().links);
        for b in &f {
            let d = difference(&scene, a, b);
            assert!(d < 1e-5, "F oracle: schedules differ by {d}");
        }
    }
    let a = run(Schedule::Interleaved, Oracle::Variation);
    let b = run(Schedule::Scheduled, Oracle::Variation);
    let d = difference(&scene, &a, &b);
    assert!(
        d < 0.01,
        "variation oracle: interleaved and scheduled differ by {d}"
    );
}

#[test]
fn identical_for_any_thread_count() {
    let scene = shadow_box();
    let accel = Accel::new(&scene);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        pool.install(|| {
            let s = solve(&scene, &accel, leaf_params());
            (s.engine().radiosity().to_vec(), s.stats())
        })
    };
    let (a, sa) = run(1);
    let (b, sb) = run(2);
    // The stats include the rays cast, counted exactly on any number of threads.
    assert!(sa.rays > 0);
    assert_eq!(sa, sb);
    assert!(a.iter().zip(&b).all(|(x, y)| x.to_array() == y.to_array()));
}

#[test]
fn scaled_scenes_give_the_same_answer() {
    // At the defaults, and with a minimum size that elements reach exactly (edge 1/16: a power of two, so
    // whether an element of edge 1/8 may split is a tie that rounding decides differently at other scales).
    let params = |scale: f64| {
        [
            leaf_params(),
            HierarchicalParams {
                oracle: Oracle::F,
                epsilon: 0.02,
                min_element_size: Some(scale / 16.0),
                ..leaf_params()
            },
        ]
    };
    let base = radlab_scene::builtin("perpendicular-squares").expect("scene");
    let accel = Accel::new(&base);
    for (k, p) in params(1.0).into_iter().enumerate() {
        let reference = solve(&base, &accel, p);
        for scale in [1e-4, 1e4] {
            let spec = format!("perpendicular-squares?width={scale}&height={scale}&length={scale}");
            let scene = radlab_scene::builtin(&spec).expect("scene");
            let accel = Accel::new(&scene);
            let s = solve(&scene, &accel, params(scale)[k].clone());
            assert_eq!(
                s.stats().elements,
                reference.stats().elements,
                "{scale} {k}"
            );
            assert_eq!(s.stats().links, reference.stats().links, "{scale} {k}");
            for (x, y) in s.leaves().iter().zip(reference.leaves()) {
                assert!(
                    (x.2 - y.2).abs().max_element() < 1e-9,
                    "{scale} {k}: {} vs {}",
                    x.2,
                    y.2
                );
            }
        }
    }
}

#[test]
fn radiosity_at_finds_each_leaf_and_gouraud_is_continuous() {
    let scene = shadow_box();
    let accel = Accel::new(&scene);
    let constant = solve(
        &scene,
        &accel,
        HierarchicalParams {
            answer: radlab_answer::AnswerParams {
                reconstruction: Reconstruction::Constant,
                ..radlab_answer::AnswerParams::default()
            },
            ..HierarchicalParams::coarse()
        },
    );
    let e = constant.engine();
    for i in 0..e.nodes().len() as u32 {
        if e.is_leaf(i) {
            let n = &e.nodes()[i as usize];
            assert_eq!(
                constant.radiosity_at(n.face, n.centroid),
                e.radiosity()[i as usize]
            );
        }
    }
    let gouraud = solve(
        &scene,
        &accel,
        HierarchicalParams {
            answer: radlab_answer::AnswerParams {
                reconstruction: Reconstruction::Gouraud,
                ..radlab_answer::AnswerParams::default()
            },
            ..HierarchicalParams::coarse()
        },
    );
    // Walk a line across the floor in small steps: Gouraud output never jumps, constant output does.
    let jump = |s: &HierarchicalSolver| {
        let mut worst: f64 = 0.0;
        let n = 4000;
        let mut prev = s.radiosity_at(0, dvec3(0.001, 0.37, 0.0));
        for k in 1..=n {
            let x = 0.001 + 0.998 * k as f64 / n as f64;
            let b = s.radiosity_at(0, dvec3(x, 0.37, 0.0));
            worst = worst.max((b - prev).abs().max_element());
            prev = b;
        }
        worst
    };
    let (jg, jc) = (jump(&gouraud), jump(&constant));
    assert!(jg < 0.2 * jc, "gouraud {jg} constant {jc}");
}

#[test]
fn bad_parameters_are_errors_that_name_them() {
    let scene = shadow_box();
    let accel = Accel::new(&scene);
    let cases = [
        (
            "epsilon",
            HierarchicalParams {
                epsilon: -1.0,
                ..leaf_params()
            },
        ),
        (
            "min_element_size",
            HierarchicalParams {
                min_element_size: Some(f64::NAN),
                ..leaf_params()
            },
        ),
        (
            "quadrature",
            HierarchicalParams {
                quadrature: 1,
                oracle: Oracle::Variation,
                ..leaf_params()
            },
        ),
    ];
    for (name, p) in cases {
        let e = HierarchicalSolver::new(&scene, &accel, p, 0)
            .expect_err("rejected")
            .to_string();
        assert!(e.contains(name), "{e}");
    }
    let tiny = HierarchicalParams {
        memory_budget_mib: 1e-3,
        ..leaf_params()
    };
    let mut s = HierarchicalSolver::new(&scene, &accel, tiny, 0).expect("valid");
    let mut result = Ok(Step::Continue);
    while let Ok(Step::Continue) = result {
        result = s.step();
    }
    let e = result.expect_err("over budget").to_string();
    assert!(e.contains("memory_budget_mib"), "{e}");
    assert!(HierarchicalParams::from_pairs(&[("gather".into(), "leaf".into())]).is_ok());
}

/// A solve stopped by its own `max_steps` cap, before its tolerance was met, reports [`Step::Capped`], not
/// [`Step::Converged`] (radlab's reports call such a run "step-limit"); the same solve without the cap
/// converges.
#[test]
fn a_solve_at_its_step_cap_says_so() {
    let scene = shadow_box();
    let accel = Accel::new(&scene);
    // Steps until the solver stops (at most 100,000): what its last step said.
    let last_step = |p: HierarchicalParams| {
        let mut s = HierarchicalSolver::new(&scene, &accel, p, 7).expect("valid parameters");
        (0..100_000)
            .map(|_| s.step().expect("step"))
            .find(|&r| r != Step::Continue)
    };
    let capped = HierarchicalParams {
        max_steps: 2,
        ..leaf_params()
    };
    assert_eq!(last_step(capped), Some(Step::Capped));
    assert_eq!(last_step(leaf_params()), Some(Step::Converged));
}

#[test]
fn a_floor_gathers_the_side_of_a_cube_whose_plane_its_samples_miss() {
    // The cube's x = 2 side (face 9) stands a little above the floor (face 4), which is one 2.5 × 2.5 quad:
    // the floor's Gauss points and centroid all lie on the far side of that side's plane (x < 2), yet the
    // floor beyond it (x > 2) sees it whole, unoccluded (no leaf is sealed, so no open share intervenes). Each floor leaf there must gather exactly its own kernel mean toward the side,
    // F = mean over its Gauss points of the point-to-polygon factor (closed form): a link dropped because
    // the floor's samples missed the side's front would give 0 and lose that light, a leak that the
    // furnace at ρ = 0.9 magnifies tenfold.
    let scene = radlab_testkit::furnace_with_cube(0.9, 1.0, 0.25);
    let accel = Accel::new(&scene);
    let p = HierarchicalParams {
        epsilon: 0.05,
        ..leaf_params()
    };
    let s = solve(&scene, &accel, p.clone());
    let e = s.engine();
    let side = scene.polygon(9);
    let rows = e.row_sums_through(&|_r, src, _l| src.face == 9);
    let mut checked = 0;
    for i in 0..e.nodes().len() as u32 {
        let n = &e.nodes()[i as usize];
        let c = n.centroid;
        if !e.is_leaf(i) || n.face != 4 || c.x < 2.0 || !(1.0..2.0).contains(&c.z) {
            continue;
        }
        if n.polygon.vertices().iter().any(|v| v.x < 2.0) {
            continue; // only leaves wholly beyond the side's plane
        }
        let exact: f64 = radlab_kernels::form_factor::receiver_points(&n.polygon, p.quadrature)
            .iter()
            .map(|(x, w)| w * radlab_kernels::form_factor::point_polygon(*x, n.normal, &side))
            .sum();
        let got = rows[i as usize].x;
        assert!(
            (got - exact).abs() <= 1e-6 * exact.max(1e-3),
            "floor leaf at {c}: gathers {got} from the cube's side, its kernel mean is {exact}"
        );
        checked += 1;
    }
    assert!(checked >= 2, "{checked} floor leaves in front of the side");
}

/// An occluded furnace: the Cornell box closed by a front wall, every surface at ρ = 0.5 and E = 1, has
/// B = E/(1 − ρ) = 2 at every point light reaches, blocks or not, so the open leaves' mean radiosity (weights
/// o A) must be 2. Each leaf's row sum Σ_l c_{t,l}/ō_l estimates its exact row, 1: a coarse link's visibility
/// is one fraction for the whole receiver, so leaves that see its source more than the receiver as a whole
/// get rows above 1 and those that see it less get rows below, by a few per cent, the link's power
/// unchanged. Capping every row at 1 (as straddling leaves' rows must be, where the open-share estimate and
/// the visibility rays disagree) kept the deficits and dropped the excesses: the leaves' mean fell 1.0% short
/// of 2 here (measured −1.035%), the bias of the hierarchical methods on the Cornell box. What remains, +0.08%,
/// is the visibility estimates' own bias and the cap of the straddling leaves; the bound is the ±0.3% bias
/// radlab's defaults are held to on the Cornell box (docs/defaults.md).
#[test]
fn an_occluded_furnace_keeps_its_light() {
    let scene = radlab_testkit::cornell_furnace(0.5, 1.0);
    let accel = Accel::new(&scene);
    let s = solve(&scene, &accel, leaf_params());
    let mean = s.engine().open_mean_radiosity(|_| true).x;
    let bias = mean / 2.0 - 1.0;
    assert!(
        bias.abs() <= 3e-3,
        "open leaves' mean radiosity {mean:.5} against 2: bias {:+.3}%",
        100.0 * bias
    );
}

//! The final gather over the face-cluster tree (`reconstruction = "final-gather"`): exact against Howell's
//! closed forms where every node is opened or the light is an emitter, within the point transfer's (R/r)²
//! where a far node is gathered whole, a closed sphere's factors summing to one, a per-query cost that grows
//! far slower than the faces, the solver's answers in a furnace and across thread counts, gathered values (a
//! second bounce) as one Jacobi iteration with its work counted, and the flat gather's near field
//! (`near_field = "sub-polygons"`) exact for direct light, in the furnace, and with its work counted.

mod common;
use common::{params, solve, try_params};

use std::collections::HashMap;

use glam::dvec3;
use radlab_answer::NearValues;
use radlab_answer::final_gather::NEAR_VALUES_MIN_FACTOR;
use radlab_face_cluster::{
    ClusterGather, DEFAULT_OPENING, FaceClusterParams, FaceClusterSolver, FaceClusterTree,
    FaceContext, GatherValues, NearField,
};
use radlab_kernels::form_factor::closed_form::point_to_parallel_rectangle_corner as corner;
use radlab_kernels::form_factor::point_polygon;
use radlab_method::{MethodParams, Solution};
use radlab_scene::{Material, Rgb, Scene, SceneBuilder, builtin};
use radlab_visibility::Accel;

/// Howell's factor from a differential area at (x, y, 0) facing +z to the parallel w × d rectangle
/// [0, w] × [0, d] at height h: four corner rectangles (Howell B-3).
fn to_rectangle(x: f64, y: f64, w: f64, d: f64, h: f64) -> f64 {
    corner(x, y, h) + corner(w - x, y, h) + corner(x, d - y, h) + corner(w - x, d - y, h)
}

/// Two parallel unit squares, neither emitting, each one connected mesh: the bottom (z = 0, facing up,
/// ρ = 0.5) as 4 × 4 quads, the top (z = `h`, facing down) as 8 × 8 quads.
fn two_plates(h: f64) -> Scene {
    let mut b = SceneBuilder::new("two plates");
    let grey = b
        .add_material(Material::new("grey", Rgb::splat(0.5), Rgb::ZERO).expect("valid"))
        .expect("valid");
    let mut grid = |n: usize, z: f64, up: bool| {
        let first = b.vertex_count() as u32;
        for j in 0..=n {
            for i in 0..=n {
                b.add_vertex(dvec3(i as f64 / n as f64, j as f64 / n as f64, z), "plates")
                    .expect("finite");
            }
        }
        let id = |i: usize, j: usize| first + (j * (n + 1) + i) as u32;
        for j in 0..n {
            for i in 0..n {
                let mut c = [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)];
                if !up {
                    c.reverse();
                }
                b.add_polygon(&c, grey, "plates").expect("valid");
            }
        }
    };
    grid(4, 0.0, true);
    grid(8, h, false);
    b.build().expect("scene")
}

fn context(scene: &Scene) -> FaceContext<'_> {
    let tree = FaceClusterTree::build(scene, &FaceClusterParams::default()).expect("tree");
    FaceContext::new(tree, scene)
}

/// The top plate sends B = 1, the bottom nothing: the bottom's irradiance is Howell's factor to the top. At
/// opening 0 every node is opened down to the faces, whose exact factors sum to Howell's (1e-12). At the
/// default opening the top plate (bounding radius R ≈ 0.71 at distance r ≈ 10, R/r below the opening) is
/// gathered whole by its power vector: one kernel evaluation and its four samples' weights instead of 64, within the point transfer's
/// error, of order (R/r)² = 0.5% (measured +0.33% at all three points).
#[test]
fn a_far_plate_is_gathered_whole_within_its_point_transfer_error() {
    let h = 10.0;
    let scene = two_plates(h);
    let accel = Accel::new(&scene);
    let ctx = context(&scene);
    let values: Vec<Rgb> = (0..scene.face_count())
        .map(|f| Rgb::splat(if f >= 16 { 1.0 } else { 0.0 }))
        .collect();
    let exact = ClusterGather::new(&ctx, values.clone(), HashMap::new(), 0.0, 3);
    let whole = ClusterGather::new(&ctx, values, HashMap::new(), DEFAULT_OPENING, 3);
    for (x, y) in [(0.5, 0.5), (0.1, 0.05), (0.93, 0.41)] {
        let p = dvec3(x, y, 0.0);
        let f = (0..16)
            .find(|&f| scene.polygon(f).contains(p, 1e-9))
            .expect("a bottom face");
        let want = 0.5 * to_rectangle(x, y, 1.0, 1.0, h);
        let (k0, k1) = (exact.kernel_evaluations(), whole.kernel_evaluations());
        let b0 = exact.radiosity_at(&ctx, &accel, f, p, false).x;
        let b1 = whole.radiosity_at(&ctx, &accel, f, p, false).x;
        assert!(
            (b0 - want).abs() <= 1e-12 * want,
            "({x}, {y}): {b0} vs {want}"
        );
        let r_over = (0.5f64.sqrt() / h).powi(2);
        assert!(
            (b1 - want).abs() <= r_over * want,
            "({x}, {y}): {b1} vs {want}, {:.3}% off",
            100.0 * (b1 / want - 1.0)
        );
        let (d0, d1) = (
            exact.kernel_evaluations() - k0,
            whole.kernel_evaluations() - k1,
        );
        assert!(d1 + 59 <= d0, "{d1} kernel evaluations against {d0}");
    }
}

/// The inside of a closed sphere, every face sending B = 1: from any point the faces fill the hemisphere, so
/// the irradiance is 1. Exact at opening 0 (the point-to-polygon factors of a closed mesh sum to one); at the
/// default opening far nodes are gathered by their power vectors (measured: at most 0.22% off over 24 faces'
/// centroids, 768 faces).
#[test]
fn a_closed_sphere_fills_the_hemisphere() {
    let scene = builtin("furnace-sphere?tessellation=8&reflectance=0.5&emission=0").expect("scene");
    let accel = Accel::new(&scene);
    let ctx = context(&scene);
    let ones = vec![Rgb::ONE; scene.face_count()];
    let mut worst = 0.0f64;
    for (opening, tol) in [(0.0, 1e-9), (DEFAULT_OPENING, 0.01)] {
        let g = ClusterGather::new(&ctx, ones.clone(), HashMap::new(), opening, 5);
        for f in (0..scene.face_count()).step_by(32) {
            let b = g
                .radiosity_at(&ctx, &accel, f, scene.faces[f].centroid, false)
                .x;
            let irradiance = b / 0.5;
            assert!(
                (irradiance - 1.0).abs() <= tol,
                "opening {opening}, face {f}: irradiance {irradiance}"
            );
            if opening > 0.0 {
                worst = worst.max((irradiance - 1.0).abs());
            }
        }
    }
    assert!(
        worst > 0.0,
        "the default opening gathered every face exactly"
    );
}

/// Gathered values are one Jacobi iteration of the radiosity equation before the final gather. Inside a closed
/// sphere of E = 1, ρ = 0.5 (a furnace: B = 2), every face given the value B₀ = 1: the inside's factors sum to
/// one, so with every node opened one gather gives B₁ = E + ρ B₀ = 1.5 and a gather over values gathered first
/// B₂ = E + ρ B₁ = 1.75 (1e-9). The values' gather is charged: before any query the regathered gather has
/// counted exactly the kernel evaluations of one query at every face's centroid, and the point kernels that
/// weight each whole emitter's rays (every face here emits: one weight for each of the query's rays).
#[test]
fn gathered_values_are_one_jacobi_iteration_and_their_work_is_counted() {
    let scene = builtin("furnace-sphere?tessellation=6&reflectance=0.5&emission=1").expect("scene");
    let accel = Accel::new(&scene);
    let ctx = context(&scene);
    let ones = vec![Rgb::ONE; scene.face_count()];
    let once = ClusterGather::new(&ctx, ones.clone(), HashMap::new(), 0.0, 5);
    for f in 0..scene.face_count() {
        once.radiosity_at(&ctx, &accel, f, scene.faces[f].centroid, false);
    }
    let (values_work, values_rays) = (once.kernel_evaluations(), once.rays());
    let twice = ClusterGather::regathered(&ctx, &accel, ones, HashMap::new(), (0.0, 0.0), 5);
    assert_eq!(twice.kernel_evaluations(), values_work + values_rays);
    assert!(twice.rays() > 0);
    for f in (0..scene.face_count()).step_by(17) {
        let x = scene.faces[f].centroid;
        let (b1, b2) = (
            once.radiosity_at(&ctx, &accel, f, x, false).x,
            twice.radiosity_at(&ctx, &accel, f, x, false).x,
        );
        assert!((b1 - 1.5).abs() <= 1e-9, "face {f}: one gather {b1}");
        assert!((b2 - 1.75).abs() <= 1e-9, "face {f}: two gathers {b2}");
    }
}

/// Near values are gathered values where the query point is near: inside a closed sphere of ρ = 0.5 and no
/// emission, with every face given the value B₀ = 1, the flat gather reads a face whose factor from the point is
/// at least `NEAR_VALUES_MIN_FACTOR` at its value gathered once more, ρ B₀ = 0.5 (the inside's factors sum to
/// one), and every other face at 1, so at a face's centroid x, B = ρ (Σ_near 0.5 F + Σ_far F) = 0.5 − 0.25
/// Σ_near F_{x→j}, with F Baum's exact factor (1e-9). On a sphere of 12 faces every face is near every
/// centroid: two gathers, 0.25; on one of 108 the factors from a centroid run from 0 to 0.019, only some are
/// near, and B lies strictly between two gathers' 0.25 and one gather's 0.5. Over gathered values (each
/// 0.5) the near faces read 0.25 and the answer is half that. The values are gathered once, at
/// their first use: a second pass over the same queries counts the kernel evaluations of a gather over the
/// solution's values, and the first pass more (the re-gathers, charged to answering).
#[test]
fn near_values_are_a_second_gather_of_the_faces_near_the_point() {
    for (n, every_face_near) in [(1, true), (3, false)] {
        let scene = builtin(&format!(
            "furnace-sphere?tessellation={n}&reflectance=0.5&emission=0"
        ))
        .expect("scene");
        let accel = Accel::new(&scene);
        let ctx = context(&scene);
        let ones = vec![Rgb::ONE; scene.face_count()];
        let plain = ClusterGather::new(&ctx, ones.clone(), HashMap::new(), 0.0, 5);
        let near = ClusterGather::new(&ctx, ones.clone(), HashMap::new(), 0.0, 5)
            .with_near_values(NearValues::Regathered);
        // Over gathered values (each ρ B₀ = 0.5) near faces read 0.25: every term halves.
        let twice_near =
            ClusterGather::regathered(&ctx, &accel, ones, HashMap::new(), (0.0, 0.0), 5)
                .with_near_values(NearValues::Regathered);
        let queries: Vec<usize> = (0..scene.face_count()).step_by(5).collect();
        let mut strictly_between = 0;
        for &f in &queries {
            let x = scene.faces[f].centroid;
            let n_x = scene.faces[f].normal;
            let near_factors: f64 = (0..scene.face_count())
                .filter(|&j| j != f)
                .map(|j| point_polygon(x, n_x, &scene.polygon(j)))
                .filter(|&ff| ff >= NEAR_VALUES_MIN_FACTOR)
                .sum();
            let want = 0.5 - 0.25 * near_factors;
            let b = near.radiosity_at(&ctx, &accel, f, x, false).x;
            assert!((b - want).abs() <= 1e-9, "{n}, face {f}: {b} vs {want}");
            let b2 = twice_near.radiosity_at(&ctx, &accel, f, x, false).x;
            assert!(
                (b2 - want / 2.0).abs() <= 1e-9,
                "{n}, face {f}, over gathered values: {b2} vs {}",
                want / 2.0
            );
            if every_face_near {
                assert!((b - 0.25).abs() <= 1e-9, "face {f}: {b}");
            }
            strictly_between += usize::from(b > 0.25 + 1e-6 && b < 0.5 - 1e-6);
            plain.radiosity_at(&ctx, &accel, f, x, false);
        }
        if !every_face_near {
            assert_eq!(strictly_between, queries.len());
        }
        let first = near.kernel_evaluations();
        for &f in &queries {
            near.radiosity_at(&ctx, &accel, f, scene.faces[f].centroid, false);
        }
        assert_eq!(
            near.kernel_evaluations() - first,
            plain.kernel_evaluations()
        );
        assert!(first > plain.kernel_evaluations());
    }
}

/// A far node's visibility ray goes to a sample drawn in proportion to the point kernel toward the query
/// point: over an even grid of 100,000 draws each sample of a terrain node is chosen with frequency w_s / Σ w
/// (within 2e-5), a sample whose face turns away from the point or lies behind its plane never, and where
/// every weight is 0 the draws spread evenly.
#[test]
fn far_visibility_samples_follow_the_point_kernel() {
    let scene = builtin("terrain?faces=2000&octaves=4").expect("scene");
    let tree = FaceClusterTree::build(&scene, &FaceClusterParams::default()).expect("tree");
    let x = scene.faces[7].centroid;
    let normal = scene.faces[7].normal;
    let draws = 100_000;
    let mut checked = 0;
    for m in (0..tree.nodes().len()).step_by(41) {
        let (samples, normals) = (tree.samples(m), tree.sample_normals(m));
        let w: Vec<f64> = samples
            .iter()
            .zip(normals)
            .map(|(y, ns)| {
                let v = x - *y;
                ns.dot(v).max(0.0) * normal.dot(-v).max(0.0) / v.length_squared().powi(2)
            })
            .collect();
        let total: f64 = w.iter().sum();
        let mut count = vec![0usize; samples.len()];
        for i in 0..draws {
            let y = tree.sample_toward(m, x, normal, (i as f64 + 0.5) / draws as f64);
            count[samples.iter().position(|s| *s == y).expect("a sample")] += 1;
        }
        for (s, (&c, &ws)) in count.iter().zip(&w).enumerate() {
            let want = if total > 0.0 {
                ws / total
            } else {
                1.0 / samples.len() as f64
            };
            let got = c as f64 / draws as f64;
            assert!(
                (got - want).abs() <= 2e-5,
                "node {m}, sample {s}: drawn {got}, kernel share {want}"
            );
            if total > 0.0 && ws == 0.0 {
                assert_eq!(c, 0);
            }
        }
        checked += usize::from(total > 0.0 && w.contains(&0.0));
    }
    assert!(checked > 0, "no node had a sample turned away");
}

/// Kernel evaluations per query on one 4-octave terrain tessellated at 2,000 and 32,000 faces, every face
/// sending B = 1: the tree gather's grow by less than 2.5 (measured 2.11, from 475 to 1,000, counting the
/// four sample weights of each far node; 1.94, from 180 to 350, without them, where a release probe went on to
/// 458 and 567 at 128,000 and 512,000 faces, about 100 more per × 4, as log k), the flat gather's (opening 0)
/// by more than 8 (measured 12.6: it visits every face in front of the point).
#[test]
fn work_per_query_grows_far_slower_than_the_faces() {
    let per_query = |k: usize, opening: f64| {
        let scene = builtin(&format!("terrain?faces={k}&octaves=4")).expect("scene");
        let accel = Accel::new(&scene);
        let ctx = context(&scene);
        let g = ClusterGather::new(
            &ctx,
            vec![Rgb::ONE; scene.face_count()],
            HashMap::new(),
            opening,
            1,
        );
        let queries: Vec<usize> = (0..64).map(|i| i * scene.face_count() / 64).collect();
        for &f in &queries {
            g.radiosity_at(&ctx, &accel, f, scene.faces[f].centroid, false);
        }
        g.kernel_evaluations() as f64 / queries.len() as f64
    };
    let tree = per_query(32_000, DEFAULT_OPENING) / per_query(2_000, DEFAULT_OPENING);
    let flat = per_query(32_000, 0.0) / per_query(2_000, 0.0);
    assert!(tree < 2.5, "tree gather: × {tree}");
    assert!(flat > 8.0, "flat gather: × {flat}");
}

/// Direct light from an emitter (ρ = 0, so B = E whatever the solve) onto a parallel receiver: emitters are
/// always opened down to their faces, so the solver's final-gather answer is ρ E times Howell's factor
/// (1e-12) at every opening, whatever ε left in the solution, and so is the flat gather with its near field
/// (which moves light within non-emitting faces only).
#[test]
fn direct_light_from_an_emitter_is_exact_at_every_opening() {
    let (w, d, h, e, rho) = (1.0, 0.6, 0.7, 2.0, 0.4);
    let scene = builtin(&format!(
        "parallel-squares?width={w}&depth={d}&distance={h}&emission={e}&reflectance={rho}&tessellation=4"
    ))
    .expect("scene");
    let accel = Accel::new(&scene);
    for (opening, near_field) in [
        ("0", "\"off\""),
        ("0.25", "\"off\""),
        ("0.9", "\"off\""),
        ("0", "\"sub-polygons\""),
    ] {
        let p = params(&[
            ("reconstruction", "final-gather"),
            ("gather_opening", opening),
            ("near_field", near_field),
            ("epsilon", "0.01"),
        ]);
        let mut s = FaceClusterSolver::new(&scene, &accel, p, 7).expect("solver");
        solve(&mut s);
        for (x, y) in [(0.5, 0.3), (0.1, 0.05), (0.93, 0.41)] {
            let p = dvec3(x, y, 0.0);
            let f = (0..scene.face_count())
                .find(|&f| !scene.material(f).is_emitter() && scene.polygon(f).contains(p, 1e-9))
                .expect("a receiver face");
            let b = s.radiosity_at(f, p).x;
            let want = rho * e * to_rectangle(x, y, w, d, h);
            assert!(
                (b - want).abs() <= 1e-12 * want,
                "opening {opening}, near field {near_field}, ({x}, {y}): {b} vs {want}"
            );
        }
    }
}

/// Concentric spheres, every face E = 1 and ρ = 0.5, a furnace: B = 2 everywhere. The final gather at every
/// face's centroid, over the solve at ε = 1e-3 with one ray per link, has an area mean within 1% of 2
/// (measured 2.0036; 2.0004 over gathered values) and the same bits on one and two threads, over the
/// solution's values and over gathered ones, by the tree gather and by the flat gather with its near field.
#[test]
fn final_gather_holds_the_furnace_on_any_thread_count() {
    let scene = builtin("concentric-spheres?faces=600&reflectance=0.5").expect("scene");
    let accel = Accel::new(&scene);
    let run = |threads: usize, values: &str, flat: &[(&str, &str)]| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        pool.install(|| {
            let mut pairs = vec![
                ("reconstruction", "final-gather"),
                ("epsilon", "0.001"),
                ("visibility", "centre"),
                ("gather_values", values),
            ];
            pairs.extend_from_slice(flat);
            let mut s = FaceClusterSolver::new(&scene, &accel, params(&pairs), 3).expect("solver");
            solve(&mut s);
            s.face_radiosity()
        })
    };
    let near = [("gather_opening", "0"), ("near_field", "\"sub-polygons\"")];
    for (values, flat) in [
        ("\"solution\"", &[][..]),
        ("\"gathered\"", &[][..]),
        ("\"solution\"", &near[..]),
        ("\"gathered\"", &near[..]),
    ] {
        let (one, two) = (run(1, values, flat), run(2, values, flat));
        let total: f64 = one.iter().map(|x| x.1).sum();
        let mean = one.iter().map(|x| x.1 * x.2.x).sum::<f64>() / total;
        assert!(
            (mean - 2.0).abs() <= 0.02,
            "{values} {flat:?}: area-mean B = {mean}, want 2"
        );
        for (a, b) in one.iter().zip(&two) {
            assert_eq!(
                a.2.to_array().map(f64::to_bits),
                b.2.to_array().map(f64::to_bits)
            );
        }
    }
}

/// An opening outside [0, 1) is refused, naming the key and the range, and so is an opening without final-gather
/// answers (it would change nothing).
#[test]
fn an_opening_outside_zero_to_one_or_without_a_final_gather_is_refused() {
    let refused = |pairs: &[(&str, &str)]| try_params(pairs).expect_err("refused").to_string();
    for bad in ["1", "1.5", "-0.1", "\"wide\""] {
        let err = refused(&[("reconstruction", "final-gather"), ("gather_opening", bad)]);
        assert!(
            err.contains("gather_opening") && err.contains("[0, 1)"),
            "{bad}: {err}"
        );
    }
    let err = refused(&[("reconstruction", "gouraud"), ("gather_opening", "0.1")]);
    assert!(
        err.contains("gather_opening") && err.contains("gouraud") && err.contains("final-gather"),
        "{err}"
    );
    let ok = params(&[("reconstruction", "final-gather"), ("gather_opening", "0")]);
    assert_eq!(ok.engine.answer.gather_opening, 0.0);
    assert!(ok.validate().is_ok());
}

/// Gathered values' parameters: `gather_values` takes solution or gathered and only with final-gather answers;
/// `values_opening` lies in [0, 1) and only with gathered values. Each refusal names its key and the fix.
/// `near_values` goes with either values and either near field.
#[test]
fn gathered_values_parameters_are_checked() {
    let refused = |pairs: &[(&str, &str)]| try_params(pairs).expect_err("refused").to_string();
    let fg = ("reconstruction", "final-gather");
    let err = refused(&[fg, ("gather_values", "\"twice\"")]);
    assert!(
        err.contains("gather_values") && err.contains("solution or gathered"),
        "{err}"
    );
    let err = refused(&[
        ("reconstruction", "gouraud"),
        ("gather_values", "\"gathered\""),
    ]);
    assert!(
        err.contains("gather_values") && err.contains("final-gather"),
        "{err}"
    );
    let err = refused(&[fg, ("values_opening", "0.3")]);
    assert!(
        err.contains("values_opening") && err.contains("gather_values = \"gathered\""),
        "{err}"
    );
    for bad in ["1", "-0.5", "\"coarse\""] {
        let err = refused(&[
            fg,
            ("gather_values", "\"gathered\""),
            ("values_opening", bad),
        ]);
        assert!(
            err.contains("values_opening") && err.contains("[0, 1)"),
            "{bad}: {err}"
        );
    }
    // Near values apply over gathered values and through the flat gather's near field alike.
    for (values, near_values) in [
        ("\"gathered\"", "\"solution\""),
        ("\"solution\"", "\"regathered\""),
    ] {
        let ok = params(&[
            fg,
            ("gather_opening", "0"),
            ("gather_values", values),
            ("near_field", "\"sub-polygons\""),
            ("near_values", near_values),
        ]);
        assert!(ok.validate().is_ok());
    }
    let ok = params(&[
        fg,
        ("gather_values", "\"gathered\""),
        ("values_opening", "0.25"),
    ]);
    assert_eq!(
        (ok.gather_values, ok.values_opening),
        (GatherValues::Gathered, 0.25)
    );
    assert!(ok.validate().is_ok());
}

/// The near field's work is charged to answering. The first pass over some queries also builds the near
/// faces' values (tree gathers at their centroids); a second pass over the same queries finds those values
/// kept, so its kernel evaluations are the shared flat gather's own: one per source face other than the
/// query's, at least half the faces a query. And the shared gather's sources (at least one element value per
/// face) add to the bytes held, beyond what the same answers hold without the near field.
#[test]
fn near_field_work_and_memory_are_counted() {
    let scene = builtin("terrain?faces=400&relief=0.5").expect("scene");
    let accel = Accel::new(&scene);
    let k = scene.face_count() as u64;
    let queries: Vec<usize> = (0..scene.face_count()).step_by(7).collect();
    let answer = |near_field: &str| {
        let p = params(&[
            ("reconstruction", "final-gather"),
            ("gather_opening", "0"),
            ("near_field", near_field),
            ("epsilon", "0.001"),
        ]);
        let mut s = FaceClusterSolver::new(&scene, &accel, p, 11).expect("solver");
        solve(&mut s);
        let mut passes = [0; 2];
        for pass in &mut passes {
            let before = s.answer_kernel_evaluations();
            for &f in &queries {
                s.radiosity_at(f, scene.faces[f].centroid);
            }
            *pass = s.answer_kernel_evaluations() - before;
        }
        (passes, radlab_method::Solver::stats(&s).bytes)
    };
    let n = queries.len() as u64;
    let (off, off_bytes) = answer("\"off\"");
    let ([first, second], near_bytes) = answer("\"sub-polygons\"");
    assert!(
        off[0] >= n,
        "without the near field: {} for {n} queries",
        off[0]
    );
    assert!(
        second >= n * k / 2,
        "a second pass: {second} kernels for {n} queries over {k} faces"
    );
    assert!(first > second, "first pass {first}, second {second}");
    let sources = k as usize * std::mem::size_of::<radlab_answer::gouraud::ElementValue>();
    assert!(
        near_bytes >= off_bytes + sources as u64,
        "bytes {near_bytes} with the near field, {off_bytes} without"
    );
}

/// `near_field` takes off or sub-polygons, and only for the flat final gather (final-gather answers at
/// gather_opening = 0); each refusal names the key and the fix.
#[test]
fn near_field_parameters_are_checked() {
    let refused = |pairs: &[(&str, &str)]| try_params(pairs).expect_err("refused").to_string();
    let fg = ("reconstruction", "final-gather");
    let sub = ("near_field", "\"sub-polygons\"");
    let err = refused(&[fg, ("gather_opening", "0"), ("near_field", "\"near\"")]);
    assert!(
        err.contains("near_field") && err.contains("off or sub-polygons"),
        "{err}"
    );
    let err = refused(&[("reconstruction", "gouraud"), sub]);
    assert!(
        err.contains("near_field") && err.contains("final-gather"),
        "{err}"
    );
    for opening in [None, Some("0.1")] {
        let mut pairs = vec![fg, sub];
        pairs.extend(opening.map(|o| ("gather_opening", o)));
        let err = refused(&pairs);
        assert!(
            err.contains("near_field") && err.contains("gather_opening = 0"),
            "{opening:?}: {err}"
        );
    }
    let ok = params(&[fg, ("gather_opening", "0"), sub]);
    assert_eq!(ok.near_field, NearField::SubPolygons);
    assert!(ok.validate().is_ok());
}

//! Volume-clustered hierarchical radiosity against answers nobody here chose: the A/4 identity, the form factor
//! (R/D)² from a point to a sphere, the known quarter bias of isotropic clusters against exact point-to-polygon
//! factors, the furnace B = E/(1 − ρ) on Christensen's concentric spheres, energy balance, plain hierarchical
//! radiosity on the Cornell box, the link count from one root link, thread count and scale invariance.

use std::sync::Arc;

use glam::{DVec3, dvec3};
use radlab_answer::Reconstruction;
use radlab_hierarchical::{HierarchicalParams, HierarchicalSolver, NodeKind, Patch, Schedule};
use radlab_kernels::form_factor::{VisibilitySampling, point_polygon};
use radlab_method::{Solution, Solver, Step};
use radlab_scene::{Material, Rgb, Scene, SceneBuilder, builtin, sampling};
use radlab_visibility::Accel;
use radlab_volume_cluster::normal_cone::{NormalCone, Side};
use radlab_volume_cluster::{
    Alpha, ClusterNode, ClusterSolver, ClusterTree, Directional, Isotropic, RowNormalisation,
    Transfer, TransferMode, VolumeClusterParams, VolumeClusterSolver,
};

fn solve(s: &mut dyn Solver) {
    for _ in 0..10_000 {
        if s.step().expect("step") == Step::Converged {
            return;
        }
    }
    panic!("did not converge");
}

fn params(transfer: Transfer, epsilon: f64) -> VolumeClusterParams {
    let mut p = VolumeClusterParams {
        transfer,
        ..VolumeClusterParams::default()
    };
    p.engine.epsilon = epsilon;
    p.engine.answer.reconstruction = Reconstruction::Constant;
    p
}

/// Linking exactly the given roots, never refining: ε too large for any link, links made once.
fn frozen() -> VolumeClusterParams {
    let mut p = VolumeClusterParams::default();
    p.engine.answer.reconstruction = Reconstruction::Constant;
    p.engine.epsilon = 1e30;
    p.engine.schedule = Schedule::TwoStage;
    p.engine.visibility = VisibilitySampling::Unoccluded;
    p
}

fn material(b: &mut SceneBuilder, rho: f64, e: f64) -> u32 {
    b.add_material(
        Material::new(&format!("m{rho}-{e}"), Rgb::splat(rho), Rgb::splat(e)).expect("material"),
    )
    .expect("material")
}

/// Adds an axis-aligned square of side `s` centred at `c` with normal `n` (±x or ±z), as `cells`² × 2
/// triangles.
fn add_square(b: &mut SceneBuilder, c: DVec3, n: DVec3, s: f64, cells: usize, m: u32) {
    let (u, v) = sampling::basis(n);
    let h = s / cells as f64;
    for i in 0..cells {
        for j in 0..cells {
            let p = |a: usize, bb: usize| {
                c + u * (a as f64 * h - s / 2.0) + v * (bb as f64 * h - s / 2.0)
            };
            let (p0, p1, p2, p3) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            // Orient to n.
            let (q1, q3) = if (p1 - p0).cross(p3 - p0).dot(n) > 0.0 {
                (p1, p3)
            } else {
                (p3, p1)
            };
            b.add_polygon_points(&[p0, q1, p2], m, "square")
                .expect("triangle");
            b.add_polygon_points(&[p0, p2, q3], m, "square")
                .expect("triangle");
        }
    }
}

/// Unit directions on a Fibonacci lattice (near-uniform, deterministic).
fn fibonacci(n: usize) -> Vec<DVec3> {
    let g = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let phi = g * i as f64;
            dvec3(r * phi.cos(), r * phi.sin(), z)
        })
        .collect()
}

#[test]
fn isotropic_quarter_is_the_direction_average_of_projected_area() {
    // 300 random triangles: the mean over directions of Σ A_i max(0, n_i·d) is Σ A_i / 4 exactly.
    let mut b = SceneBuilder::new("random");
    let m = material(&mut b, 0.5, 0.0);
    let mut rng = sampling::rng(7, 0);
    let mut pt = || {
        dvec3(
            sampling::uniform(&mut rng),
            sampling::uniform(&mut rng),
            sampling::uniform(&mut rng),
        )
    };
    for _ in 0..300 {
        let a = pt();
        let _ = b.add_polygon_points(&[a, a + 0.2 * pt(), a + 0.2 * pt()], m, "t");
    }
    let scene = b.build().expect("scene");
    let tree = Arc::new(ClusterTree::build(&scene));
    let root = ClusterNode::root(Arc::clone(&tree), &scene);
    let dirs = fibonacci(40_000);
    let mean: f64 = dirs
        .iter()
        .map(|d| {
            scene
                .faces
                .iter()
                .map(|f| f.area * f.normal.dot(*d).max(0.0))
                .sum::<f64>()
        })
        .sum::<f64>()
        / dirs.len() as f64;
    let area: f64 = scene.faces.iter().map(|f| f.area).sum();
    assert!(
        (mean / (area / 4.0) - 1.0).abs() < 1e-3,
        "{mean} vs {}",
        area / 4.0
    );
    assert!((root.projected_area(DVec3::X) - area / 4.0).abs() < 1e-12 * area);
    assert!((root.area() - area).abs() < 1e-12 * area);
}

/// An outward tessellated unit sphere (emitting E = 1, ρ = 0) and a small patch (ρ = 0.5) facing it on the
/// x axis at centre distance `d`. Returns the scene and the sphere's faces.
fn sphere_and_patch(d: f64) -> (Scene, Vec<usize>) {
    let spheres = builtin("concentric-spheres?faces=6000").expect("scene");
    let mut b = SceneBuilder::new("sphere-patch");
    let light = material(&mut b, 0.0, 1.0);
    let grey = material(&mut b, 0.5, 0.0);
    let mut sphere = Vec::new();
    for f in 0..spheres.face_count() {
        if spheres.faces[f].centroid.length() < 1.5 {
            let p = spheres.polygon(f);
            b.add_polygon_points(p.vertices(), light, "sphere")
                .expect("face");
            sphere.push(sphere.len());
        }
    }
    add_square(&mut b, dvec3(d, 0.0, 0.0), -DVec3::X, 0.01, 1, grey);
    (b.build().expect("scene"), sphere)
}

fn patch_factor<M: TransferMode>(d: f64) -> f64 {
    let (scene, sphere) = sphere_and_patch(d);
    let accel = Accel::new(&scene);
    let tree = Arc::new(ClusterTree::build_over(&scene, sphere));
    let patch = scene.face_count() - 1;
    let roots = vec![
        ClusterNode::root(Arc::clone(&tree), &scene),
        ClusterNode::Patch(Patch::root(&scene, patch - 1)),
        ClusterNode::Patch(Patch::root(&scene, patch)),
    ];
    let mut s = ClusterSolver::<M>::from_roots(
        &scene,
        &accel,
        &frozen(),
        1,
        tree,
        roots,
        &[(1, 0), (2, 0)],
    )
    .expect("solver");
    solve(&mut s);
    let b = s.radiosity_at(patch, scene.faces[patch].centroid);
    b.x / 0.5
}

#[test]
fn a_sphere_as_one_cluster_gives_the_point_factor_r_over_d_squared() {
    // F from a small patch facing a sphere of radius R at centre distance D is (R/D)² (Howell's B-catalogue).
    for d in [2.0, 4.0] {
        let want = 1.0 / (d * d);
        for (name, f) in [
            ("isotropic", patch_factor::<Isotropic>(d)),
            ("alpha", patch_factor::<Alpha>(d)),
        ] {
            assert!(
                (f / want - 1.0).abs() < 0.01,
                "{name} at D = {d}: F = {f}, want {want}"
            );
        }
    }
}

/// A flat plate of 200 triangles (ρ = 0.5) facing up, under a small light 5 above. Returns (cluster B,
/// exact B) per plate face.
fn plate_under_light<M: TransferMode>() -> Vec<(f64, f64)> {
    plate_and_light::<M>(5.0)
}

/// The plate with a small light at height `z` facing it (from above if `z` > 0, from behind its plane if
/// `z` < 0). Returns (cluster B, exact B) per plate face.
fn plate_and_light<M: TransferMode>(z: f64) -> Vec<(f64, f64)> {
    let mut b = SceneBuilder::new("plate");
    let grey = material(&mut b, 0.5, 0.0);
    let light = material(&mut b, 0.0, 1.0);
    add_square(&mut b, DVec3::ZERO, DVec3::Z, 1.0, 10, grey);
    add_square(
        &mut b,
        dvec3(0.0, 0.0, z),
        -z.signum() * DVec3::Z,
        0.05,
        1,
        light,
    );
    let scene = b.build().expect("scene");
    let accel = Accel::new(&scene);
    let plate: Vec<usize> = (0..200).collect();
    let tree = Arc::new(ClusterTree::build_over(&scene, plate.clone()));
    let roots = vec![
        ClusterNode::root(Arc::clone(&tree), &scene),
        ClusterNode::Patch(Patch::root(&scene, 200)),
        ClusterNode::Patch(Patch::root(&scene, 201)),
    ];
    let mut s = ClusterSolver::<M>::from_roots(
        &scene,
        &accel,
        &frozen(),
        1,
        tree,
        roots,
        &[(0, 1), (0, 2)],
    )
    .expect("solver");
    solve(&mut s);
    plate
        .iter()
        .map(|&f| {
            let c = scene.faces[f].centroid;
            let exact: f64 = [200, 201]
                .iter()
                .map(|&l| 0.5 * point_polygon(c, DVec3::Z, &scene.polygon(l)).max(0.0))
                .sum();
            (s.radiosity_at(f, c).x, exact)
        })
        .collect()
}

#[test]
fn a_flat_cluster_facing_a_light_gets_a_quarter_under_isotropic_and_its_share_under_alpha() {
    let iso = plate_under_light::<Isotropic>();
    let (sum_c, sum_e) = iso.iter().fold((0.0, 0.0), |a, (c, e)| (a.0 + c, a.1 + e));
    // The light's distance varies by 1% over the plate, so the ratio of means is 1/4 within 2%.
    assert!(
        (sum_c / sum_e / 0.25 - 1.0).abs() < 0.02,
        "isotropic: {}",
        sum_c / sum_e
    );
    // α: each face's own cosine share of the light's field, taken to first order about the plate's centroid
    // (the normal cones' receiver), whose error is second order in the plate's bounding radius R = √2/2 over
    // the distance r = 5, about 2 (R/r)² = 4% (crate::normal_cone's gather); and the light's own cosine is
    // taken toward the plate's centroid, so a corner face is off by 1 − 5/√(25 + 0.5) ≈ 0.99% more at most.
    let (r_over_d, cosine) = (0.5f64.sqrt() / 5.0, 0.0101);
    let tolerance = cosine + 2.0 * r_over_d * r_over_d;
    for (c, e) in plate_under_light::<Alpha>() {
        assert!((c / e - 1.0).abs() < tolerance, "alpha: {c} vs {e}");
    }
}

#[test]
fn no_face_of_a_cluster_receives_light_from_behind_its_plane() {
    // A light below the plate, facing up at its back: every face's exact irradiance is zero. The directional
    // receiver used to take the order-2 harmonic lobe of every link into the cluster, 1/16 of its peak in the
    // direction opposite the lobe (Ramamoorthi & Hanrahan 2001's truncation): B = 0.5 · 0.0625 · F. The normal
    // cones give the plate (all normals +z) nothing from a source behind it, exactly, under α and directional.
    for (name, faces) in [
        ("alpha", plate_and_light::<Alpha>(-5.0)),
        ("directional", plate_and_light::<Directional>(-5.0)),
    ] {
        for (c, e) in faces {
            assert_eq!(e, 0.0);
            assert_eq!(c, 0.0, "{name}: a face lit from behind its plane");
        }
    }
    // From the front, directional gathers the link at the plate as α does: each face takes the light's
    // field to first order about the plate's centroid, whose error is second order in the plate's bounding
    // radius R = √2/2 over the distance r = 5, about 2 (R/r)² = 4% (crate::normal_cone's gather), on top of
    // 1% from the light's own cosine.
    let (r_over_d, cosine) = (0.5f64.sqrt() / 5.0, 0.0101);
    let tolerance = cosine + 2.0 * r_over_d * r_over_d;
    for (c, e) in plate_under_light::<Directional>() {
        assert!((c / e - 1.0).abs() < tolerance, "directional: {c} vs {e}");
    }
}

/// Relative imbalance of a closed scene: (absorbed − emitted)/emitted per channel, absorbed = Σ A (1 − ρ) H with
/// H = (B − E)/ρ from each face's solved radiosity.
fn energy_imbalance(scene: &Scene, faces: &[(usize, f64, Rgb)]) -> f64 {
    let (mut emitted, mut absorbed) = (0.0, 0.0);
    for &(f, a, b) in faces {
        let (rho, e) = (scene.reflectance(f).x, scene.emission(f).x);
        emitted += a * e;
        if rho > 0.0 {
            absorbed += a * (1.0 - rho) * (b.x - e) / rho;
        }
    }
    (absorbed - emitted) / emitted
}

/// The area-mean error of B against E/(1 − ρ) and the energy imbalance of a solve of the concentric spheres.
fn furnace(rho: f64, t: Transfer, rows: RowNormalisation) -> (f64, f64) {
    let scene = builtin(&format!("concentric-spheres?faces=600&reflectance={rho}")).expect("scene");
    let accel = Accel::new(&scene);
    let mut p = params(t, 1e-4);
    p.row_normalisation = rows;
    let mut s = VolumeClusterSolver::new(&scene, &accel, p, 1).expect("solver");
    solve(&mut s);
    let faces = s.face_radiosity();
    let area: f64 = faces.iter().map(|f| f.1).sum();
    let mean = faces.iter().map(|f| f.1 * f.2.x).sum::<f64>() / area;
    (mean * (1.0 - rho) - 1.0, energy_imbalance(&scene, &faces))
}

#[test]
fn concentric_spheres_are_a_furnace_at_moderate_albedo_without_row_normalisation() {
    // B = E/(1 − ρ) everywhere (Christensen 1995 §8.3). At ρ = 0.5 α and directional links meet it within 1%
    // on the area mean; isotropic clusters lose energy (a cluster of the sphere seen face-on is a quarter of
    // its true projected area), as documented. Near ρ = 1 every transfer's point-approximation defect in the
    // form-factor row sums (about 3e-4 for α here) is multiplied by ρ/(1 − ρ): the crate documentation gives
    // the measured errors at ρ = 0.9 … 0.999.
    for t in [Transfer::Alpha, Transfer::Directional, Transfer::Isotropic] {
        let (err, imbalance) = furnace(0.5, t, RowNormalisation::Off);
        match t {
            Transfer::Alpha | Transfer::Directional => {
                assert!(err.abs() < 0.01, "{t:?}: mean error {err}");
                // Both the mean error and the imbalance measure the same row-sum defect.
                assert!(imbalance.abs() < 0.02, "{t:?}: imbalance {imbalance}");
            }
            Transfer::Isotropic => assert!(err < -0.01, "isotropic no longer biased low? {err}"),
        }
    }
}

#[test]
fn closed_scene_row_normalisation_makes_the_concentric_spheres_a_furnace_at_rho_0_999() {
    // A test of the `closed-scenes` option, not of the transfers: the concentric spheres are closed (every
    // enclosure ray hits the front of a face), so the option rescales each leaf's row to one, as an
    // enclosure's exact form factors sum (Goral et al. 1984). With every row one, the furnace B = E/(1 − ρ)
    // is the discrete operator's own solution, whatever the transfer, and what is left is the iteration's
    // stopping error (tolerance 1e-4 by default). This fails if the enclosure rays miss that the scene is
    // closed or the rescaling misses a row; without the option α is −24%, directional −28% and isotropic
    // −96% here (crate documentation), which is why it is not the default.
    for t in [Transfer::Alpha, Transfer::Directional, Transfer::Isotropic] {
        let (err, imbalance) = furnace(0.999, t, RowNormalisation::ClosedScenes);
        assert!(err.abs() < 0.01, "{t:?}: mean error {err}");
        assert!(imbalance.abs() < 0.01, "{t:?}: imbalance {imbalance}");
    }
}

/// A closed box (side 2) lit by a ceiling light, holding `n` random small triangles (seeded).
fn box_with_triangles(n: usize, scale: f64) -> Scene {
    let mut b = SceneBuilder::new("box-triangles");
    let wall = material(&mut b, 0.6, 0.0);
    let light = material(&mut b, 0.0, 10.0);
    let grey = material(&mut b, 0.5, 0.0);
    let s = scale;
    for (c, n) in [
        (dvec3(0.0, 0.0, -1.0), DVec3::Z),
        (dvec3(0.0, 0.0, 1.0), -DVec3::Z),
        (dvec3(-1.0, 0.0, 0.0), DVec3::X),
        (dvec3(1.0, 0.0, 0.0), -DVec3::X),
        (dvec3(0.0, -1.0, 0.0), DVec3::Y),
        (dvec3(0.0, 1.0, 0.0), -DVec3::Y),
    ] {
        add_square(&mut b, c * s, n, 2.0 * s, 2, wall);
    }
    add_square(
        &mut b,
        dvec3(0.0, 0.0, 0.99) * s,
        -DVec3::Z,
        0.5 * s,
        1,
        light,
    );
    let mut rng = sampling::rng(11, 0);
    let mut u = || 2.0 * sampling::uniform(&mut rng) - 1.0;
    for _ in 0..n {
        let c = dvec3(u(), u(), u()) * 0.8;
        let (p, q) = (dvec3(u(), u(), u()) * 0.05, dvec3(u(), u(), u()) * 0.05);
        let _ = b.add_polygon_points(&[c * s, (c + p) * s, (c + q) * s], grey, "t");
    }
    b.build().expect("scene")
}

#[test]
fn ten_thousand_triangles_solve_from_one_root_link_with_links_far_below_k_squared() {
    let scene = box_with_triangles(10_000, 1.0);
    let k = scene.face_count() as u64;
    let accel = Accel::new(&scene);
    let mut p = params(Transfer::Isotropic, 1e-3);
    p.engine.visibility = VisibilitySampling::Centre;
    let mut s = VolumeClusterSolver::new(&scene, &accel, p, 1).expect("solver");
    assert_eq!(s.stats().links, 1, "one root self-link to start");
    solve(&mut s);
    let st = s.stats();
    assert!(st.links * 100 < k * k, "{} links for k = {k}", st.links);
    let b = s.face_radiosity();
    assert!(
        b.iter()
            .all(|f| f.2.is_finite() && f.2.min_element() >= 0.0)
    );
    // The box's walls are lit.
    assert!(b[0].2.x > 0.0);
}

#[test]
fn results_do_not_depend_on_threads_or_scene_scale() {
    let run = |scale: f64, threads: usize| {
        let scene = box_with_triangles(300, scale);
        let accel = Accel::new(&scene);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        pool.install(|| {
            let mut s = VolumeClusterSolver::new(&scene, &accel, params(Transfer::Alpha, 1e-3), 1)
                .expect("solver");
            solve(&mut s);
            (s.face_radiosity(), s.stats())
        })
    };
    let (one, st1) = run(1.0, 1);
    let (two, st2) = run(1.0, 2);
    assert_eq!(st1, st2);
    for (a, b) in one.iter().zip(&two) {
        assert_eq!(a.2, b.2, "face {}", a.0);
    }
    for scale in [1e-4, 1e4] {
        let (s, st) = run(scale, 2);
        assert_eq!(
            (st.links, st.elements),
            (st1.links, st1.elements),
            "scale {scale}"
        );
        for (a, b) in one.iter().zip(&s) {
            assert!(
                (a.2 - b.2).abs().max_element() <= 1e-9 * a.2.abs().max_element().max(1e-300),
                "scale {scale}: face {}: {} vs {}",
                a.0,
                a.2,
                b.2
            );
        }
    }
}

#[test]
fn cornell_box_approaches_hierarchical_radiosity_as_epsilon_falls() {
    let scene = builtin("cornell").expect("scene");
    let accel = Accel::new(&scene);
    let mut h =
        HierarchicalSolver::new(&scene, &accel, HierarchicalParams::default(), 1).expect("solver");
    solve(&mut h);
    // Per-face means of the hierarchical leaves over their open areas (the floor under the blocks, which
    // light never reaches, left out), as the volume-cluster engine pulls a face's radiosity up.
    let reference: Vec<Rgb> = (0..scene.face_count())
        .map(|f| h.engine().open_mean_radiosity(|p| p.face == f))
        .collect();
    let mut errors = Vec::new();
    for eps in [1e-2, 1e-3, 1e-4] {
        let mut s = VolumeClusterSolver::new(&scene, &accel, params(Transfer::Alpha, eps), 1)
            .expect("solver");
        solve(&mut s);
        // Area-weighted relative L1 of per-face mean radiosity.
        let (mut num, mut den) = (0.0, 0.0);
        for (f, a, b) in s.face_radiosity() {
            let r = reference[f];
            num += a * (b - r).abs().element_sum();
            den += a * r.abs().element_sum();
        }
        errors.push(num / den);
    }
    // Falls with ε down to the reference's own accuracy (hierarchical radiosity at its defaults is itself
    // about 1% from converged on this scene), then stays there.
    assert!(errors[0] > errors[1] && errors[0] > errors[2], "{errors:?}");
    assert!(errors[1] < 0.01 && errors[2] < 0.01, "{errors:?}");
}

#[test]
fn straddled_clusters_taken_whole_keep_the_furnace_at_fewer_kernel_evaluations() {
    // Under α and directional a link that straddles a receiving cluster's faces is handed down to the faces
    // along the line where the sphere turns away from the source; with `straddle_angle` θ a straddled cluster
    // whose normal cone is at most θ wide takes it whole, every face receiving the faces' mean clamped cosine
    // (within sin(2θ)/2 of a face square to the link). On the concentric spheres, where B = E/(1 − ρ)
    // everywhere (Christensen 1995 §8.3), the furnace holds as well either way, each face moves by little, and
    // taking straddled links whole spends fewer kernel evaluations.
    let scene = builtin("concentric-spheres?faces=1000&reflectance=0.5").expect("scene");
    let accel = Accel::new(&scene);
    for t in [Transfer::Alpha, Transfer::Directional] {
        let run = |angle: f64| {
            let mut p = params(t, 1e-4);
            p.straddle_angle = angle;
            let mut s = VolumeClusterSolver::new(&scene, &accel, p, 1).expect("solver");
            solve(&mut s);
            (s.face_radiosity(), s.stats())
        };
        let (exact, st0) = run(0.0);
        let (whole, st1) = run(30.0);
        let furnace = |faces: &[(usize, f64, Rgb)]| {
            let area: f64 = faces.iter().map(|f| f.1).sum();
            faces.iter().map(|f| f.1 * f.2.x).sum::<f64>() / area * 0.5 - 1.0
        };
        let moved = exact
            .iter()
            .zip(&whole)
            .map(|(a, b)| (b.2.x / a.2.x - 1.0).abs())
            .fold(0.0, f64::max);
        // Measured: 3.05 M → 2.95 M kernel evaluations (at 1,000 faces few clusters are flat enough; the
        // saving grows with the mesh), furnace (α / directional) +0.04 / +0.06% → +0.01 / +0.03%, faces
        // within 1.44%.
        assert!(
            st1.form_factors < st0.form_factors,
            "{t:?}: {} kernel evaluations taking straddled links whole, {} handing them down",
            st1.form_factors,
            st0.form_factors
        );
        assert!(moved < 0.03, "{t:?}: a face moved by {moved}");
        for (name, faces) in [("handed down", &exact), ("whole", &whole)] {
            let err = furnace(faces);
            assert!(err.abs() < 0.01, "{t:?}, {name}: furnace {err}");
        }
    }
}

#[test]
fn a_memory_budget_too_small_for_the_cluster_hierarchy_is_refused_with_the_key_to_raise() {
    // The hierarchy down to the faces is built before any link, and alone holds more than 0.1 MiB here.
    let scene = builtin("concentric-spheres?faces=1000").expect("scene");
    let accel = Accel::new(&scene);
    let mut p = params(Transfer::Alpha, 1e-4);
    p.engine.memory_budget_mib = 0.1;
    let e = VolumeClusterSolver::new(&scene, &accel, p.clone(), 1)
        .expect_err("over budget")
        .to_string();
    assert!(e.contains("memory_budget_mib"), "{e}");
    p.engine.memory_budget_mib = 16.0;
    let s = VolumeClusterSolver::new(&scene, &accel, p, 1).expect("within budget");
    assert!(s.stats().bytes > (0.1 * 1024.0 * 1024.0) as u64);
}

/// The normals of a tessellated cap: the points of a 200,000-point Fibonacci lattice on the unit sphere within
/// `theta` of `axis`, each with area weight 1 + (i mod 3) so the area mean differs from the plain mean.
fn cap(axis: DVec3, theta: f64) -> Vec<(f64, DVec3)> {
    fibonacci(200_000)
        .into_iter()
        .enumerate()
        .map(|(i, v)| (1.0 + (i % 3) as f64, v))
        .filter(|(_, v)| axis.dot(*v).clamp(-1.0, 1.0).acos() <= theta)
        .collect()
}

#[test]
fn mean_clamped_cosine_is_within_its_bound_of_the_faces() {
    // The faces' exact area-mean clamped cosine (1/A) Σ A_i max(0, n_i·u) against the cone's estimate,
    // over directions u sweeping from facing the cap whole, through straddling it, to behind it.
    let axis = dvec3(0.3, -0.2, 1.0).normalize();
    let side = axis.any_orthonormal_vector();
    for theta in [0.02f64, 0.09, 0.3] {
        let faces = cap(axis, theta);
        let cone = NormalCone::of(faces.iter().copied());
        assert!((cone.half_angle - theta).abs() < 0.01 * theta + 0.005);
        let area: f64 = faces.iter().map(|f| f.0).sum();
        let bound = (2.0 * cone.half_angle).sin() / 2.0;
        let (mut worst, mut straddled) = (0.0f64, 0);
        for k in 0..=200 {
            let phi = std::f64::consts::FRAC_PI_2 + (k as f64 / 100.0 - 1.0) * 2.0 * theta;
            let u = (phi.cos() * axis + phi.sin() * side).normalize();
            let exact = faces
                .iter()
                .map(|(a, n)| a * n.dot(u).max(0.0))
                .sum::<f64>()
                / area;
            let estimate = cone.mean_clamped_cosine(u);
            let err = (estimate - exact).abs();
            match cone.side(u) {
                Side::Front | Side::Back => {
                    assert!(err < 1e-12, "θ {theta}, φ {phi}: {estimate} vs {exact}")
                }
                Side::Straddle => {
                    straddled += 1;
                    worst = worst.max(err);
                    assert!(err <= bound, "θ {theta}, φ {phi}: {estimate} vs {exact}");
                }
            }
        }
        assert!(
            straddled > 50,
            "θ {theta}: {straddled} straddling directions"
        );
        // The bound is the worst any spread of cosines could do; on a cap the estimate is far inside it
        // (measured 0.036–0.041 of it at these three widths).
        assert!(
            worst < bound / 20.0,
            "θ {theta}: worst {worst} of bound {bound}"
        );
    }
}

/// An occluded furnace (radlab-testkit's `cornell_furnace`: the Cornell box closed by a front wall, every
/// surface at ρ = 0.5 and E = 1) has B = E/(1 − ρ) = 2 wherever light reaches, blocks or not, so the mean
/// radiosity of the walls', ceiling's and blocks' leaves (no contact seals any of them) must be 2 under every
/// transfer. The floor's leaves along the blocks' feet lie partly under them: held as area means and sent from
/// their whole area, they sent into the blocks' undersides the light their open parts reflect (Baum et al.
/// 1991's leak) until the transport estimated their open shares. Here the leak was smaller than at face
/// clusters (the mean measured −0.29% without open shares, +0.19% with them; the method's signed error on
/// the Cornell box went from −0.88% to −0.12%), so the bound, the ±0.3% Cornell bias radlab's defaults are
/// held to (docs/defaults.md), does not tell the two apart: that the floor's straddling leaves get open
/// shares between 0 and 1 does.
#[test]
fn an_occluded_furnace_keeps_its_light() {
    let scene = radlab_testkit::cornell_furnace(0.5, 1.0);
    let accel = Accel::new(&scene);
    // Off the floor: no contact seals any part of the walls, the ceiling or the blocks.
    let off_floor = |n: &ClusterNode<'_>| n.face().is_some_and(|f| scene.faces[f].centroid.y > 0.0);
    for transfer in [Transfer::Isotropic, Transfer::Alpha, Transfer::Directional] {
        let p = VolumeClusterParams {
            transfer,
            ..VolumeClusterParams::default()
        };
        let mut s = VolumeClusterSolver::new(&scene, &accel, p, 1).expect("solver");
        solve(&mut s);
        let (mean, straddling) = match &s {
            VolumeClusterSolver::Isotropic(s) => furnace_leaves(s, off_floor),
            VolumeClusterSolver::Alpha(s) => furnace_leaves(s, off_floor),
            VolumeClusterSolver::Directional(s) => furnace_leaves(s, off_floor),
        };
        let bias = mean / 2.0 - 1.0;
        assert!(
            bias.abs() <= 3e-3,
            "{transfer:?}: the mean radiosity off the floor {mean:.5} against 2: bias {:+.3}%",
            100.0 * bias
        );
        assert!(
            straddling > 0,
            "{transfer:?}: no leaf straddles the blocks' feet (open share strictly between 0 and 1)"
        );
    }
}

/// The mean radiosity of the leaves `keep` accepts over their open areas, and how many leaves straddle a
/// contact (open share strictly between 0 and 1).
fn furnace_leaves<'a, M: TransferMode>(
    s: &ClusterSolver<'a, M>,
    keep: impl Fn(&ClusterNode<'a>) -> bool,
) -> (f64, usize) {
    let e = s.engine();
    let straddling = (0..e.nodes().len() as u32)
        .filter(|&i| e.is_leaf(i) && e.open_shares()[i as usize] > 0.0)
        .filter(|&i| e.open_shares()[i as usize] < 1.0)
        .count();
    (e.open_mean_radiosity(keep).x, straddling)
}

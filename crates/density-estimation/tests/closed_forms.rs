//! Density estimation against closed forms: the furnace (B = E/(1 − ρ) everywhere, up to the edges and
//! corners, where only the local linear correction holds it) and Lambert's point-to-polygon factor for direct
//! light on Howell's parallel plates (B = ρ E F, with the estimate's bias bounded by ½ h² Λ(x) max‖∇²H‖,
//! local_linear.rs).

use glam::{DVec2, DVec3};
use radlab_density_estimation::{
    BoundaryCorrection, DensityEstimationParams, DensityEstimationSolver,
};
use radlab_kernels::form_factor::point_polygon;
use radlab_method::{Solver, Step};
use radlab_scene::{FaceId, Scene, builtin};
use radlab_testkit::mean_se;
use radlab_visibility::Accel;

/// Solves to convergence and returns the solver.
fn solve<'a>(
    scene: &'a Scene,
    accel: &'a Accel,
    params: &DensityEstimationParams,
    seed: u64,
) -> DensityEstimationSolver<'a> {
    let mut s = DensityEstimationSolver::new(scene, accel, params.clone(), seed).expect("build");
    while s.step().expect("step") == Step::Continue {}
    s
}

const SEEDS: u64 = 6;

#[test]
fn furnace_to_the_edges_and_corners() {
    let rho = 0.5;
    let exact = 1.0 / (1.0 - rho);
    let scene = builtin(&format!("furnace-cube?reflectance={rho}&tessellation=2")).expect("cube");
    let accel = Accel::new(&scene);
    // Probes on every quad at its corners, edge midpoints and centre, 0.2 % in from the quad's edges; each
    // classed by how many cube edges it lies next to (2: a corner of a cube side, 1: an edge, 0: inside).
    let mut probes: Vec<(FaceId, DVec3, usize)> = Vec::new();
    for f in 0..scene.face_count() {
        let poly = scene.polygon(f);
        for s in [0.002, 0.5, 0.998] {
            for t in [0.002, 0.5, 0.998] {
                let p = poly.point_at(s, t);
                let near = p
                    .to_array()
                    .iter()
                    .filter(|&&c| !(0.01..=0.99).contains(&c))
                    .count();
                // One coordinate is the side's plane.
                probes.push((f, p, near - 1));
            }
        }
    }
    for boundary in [BoundaryCorrection::LocalLinear, BoundaryCorrection::None] {
        let params = DensityEstimationParams {
            particles: 40_000,
            steps: 2,
            boundary,
            ..Default::default()
        };
        // Per run, the mean of B over each class of probe.
        let mut per_class: [Vec<f64>; 3] = Default::default();
        for seed in 1..=SEEDS {
            let s = solve(&scene, &accel, &params, seed);
            let mut sum = [0.0; 3];
            let mut n = [0usize; 3];
            for &(f, p, c) in &probes {
                use radlab_method::Solution;
                sum[c] += s.radiosity_at(f, p).x;
                n[c] += 1;
            }
            for c in 0..3 {
                per_class[c].push(sum[c] / n[c] as f64);
            }
        }
        for (c, name) in ["inside", "edges", "corners"].iter().enumerate() {
            let (m, se) = mean_se(&per_class[c]);
            let dev = (m - exact).abs();
            match boundary {
                // Unbiased for a flat density up to the boundary: only noise (t with 5 degrees of freedom:
                // |t| > 4.5 has probability 0.6 %).
                BoundaryCorrection::LocalLinear => {
                    assert!(
                        dev < 4.5 * se,
                        "local linear, {name}: {m} ± {se}, exact {exact}"
                    )
                }
                // The plain kernel loses the part of its disc outside the side: B = E + ρ H/2 on an edge,
                // E + ρ H/4 in a corner.
                _ if c > 0 => {
                    let expected = 1.0 + rho * exact * [1.0, 0.5, 0.25][c];
                    assert!(
                        dev > 10.0 * se,
                        "the plain kernel must fail at the {name}: {m} ± {se}"
                    );
                    assert!(
                        (m - expected).abs() < 4.5 * se + 0.02 * exact,
                        "plain kernel, {name}: {m} ± {se}, expected about {expected}"
                    );
                }
                _ => assert!(dev < 4.5 * se, "plain kernel, inside: {m} ± {se}"),
            }
        }
    }
}

/// Largest spectral norm of the Hessian of `field` (in the plane spanned by `t1`, `t2`) over a 7 × 7 grid
/// covering the disc of radius `h` about `x` (central differences, step 1e-3 h).
fn max_hessian(field: &impl Fn(DVec3) -> f64, x: DVec3, t1: DVec3, t2: DVec3, h: f64) -> f64 {
    let d = 1e-3 * h;
    let mut worst: f64 = 0.0;
    for i in 0..7 {
        for j in 0..7 {
            let (a, b) = (-1.0 + i as f64 / 3.0, -1.0 + j as f64 / 3.0);
            if a * a + b * b > 1.0 + 1e-9 {
                continue;
            }
            let p = x + (a * t1 + b * t2) * h;
            let f0 = field(p);
            let fxx = (field(p + d * t1) - 2.0 * f0 + field(p - d * t1)) / (d * d);
            let fyy = (field(p + d * t2) - 2.0 * f0 + field(p - d * t2)) / (d * d);
            let fxy =
                (field(p + d * (t1 + t2)) - field(p + d * (t1 - t2)) - field(p - d * (t1 - t2))
                    + field(p - d * (t1 + t2)))
                    / (4.0 * d * d);
            let tr = (fxx + fyy) / 2.0;
            let disc = (((fxx - fyy) / 2.0).powi(2) + fxy * fxy).sqrt();
            worst = worst.max(tr.abs() + disc);
        }
    }
    worst
}

#[test]
fn lambert_on_parallel_plates_within_the_bias_bound() {
    let scene = builtin("parallel-squares?tessellation=4").expect("plates");
    let accel = Accel::new(&scene);
    let emitters = scene.emitters();
    let receiver: Vec<FaceId> = (0..scene.face_count())
        .filter(|f| !emitters.contains(f))
        .collect();
    let n = scene.faces[receiver[0]].normal;
    let rho = scene.reflectance(receiver[0]).x;
    // Irradiance H = Σ E F_{dx→emitter}, exact.
    let field = |p: DVec3| -> f64 {
        emitters
            .iter()
            .map(|&e| scene.emission(e).x * point_polygon(p, n, &scene.polygon(e)))
            .sum()
    };
    let params = DensityEstimationParams {
        particles: 50_000,
        steps: 2,
        ..Default::default()
    };
    let probes: Vec<(FaceId, DVec3)> = receiver
        .iter()
        .flat_map(|&f| {
            let poly = scene.polygon(f);
            [0.001, 0.5, 0.999]
                .into_iter()
                .flat_map(move |s| [0.001, 0.5, 0.999].map(|t| (f, poly.point_at(s, t))))
        })
        .collect();
    let mut runs: Vec<Vec<f64>> = vec![Vec::new(); probes.len()];
    let mut bound = vec![0.0f64; probes.len()];
    for seed in 1..=SEEDS {
        let s = solve(&scene, &accel, &params, seed);
        let surfaces = s.surfaces();
        for (k, &(f, p)) in probes.iter().enumerate() {
            use radlab_method::Solution;
            runs[k].push(s.radiosity_at(f, p).x);
            let si = surfaces.of_face[f] as usize;
            let surface = &surfaces.surfaces[si];
            let h = s.bandwidth(si);
            let x: DVec2 = surface.project(p);
            let l = surface
                .domain
                .weights(x, h, BoundaryCorrection::LocalLinear)
                .expect("weights");
            let (t1, t2) = radlab_scene::sampling::basis(n);
            let b = rho
                * 0.5
                * h
                * h
                * surface.domain.bias_factor(x, h, l)
                * max_hessian(&field, p, t1, t2, h);
            bound[k] = bound[k].max(b);
        }
    }
    assert!(
        receiver
            .iter()
            .all(|&f| s_same_surface(&scene, receiver[0], f))
    );
    let (mut err, mut allowed, mut total) = (0.0, 0.0, 0.0);
    for (k, &(_, p)) in probes.iter().enumerate() {
        let (m, se) = mean_se(&runs[k]);
        let exact = rho * field(p);
        err += (m - exact).abs();
        allowed += bound[k] + 3.0 * se;
        total += exact;
    }
    assert!(
        err <= allowed,
        "relative L1 error {:.3e} exceeds the bias bound plus 3 standard errors {:.3e}",
        err / total,
        allowed / total
    );
}

/// The receiver's 16 quads are one surface (coplanar, one material, edge-connected).
fn s_same_surface(scene: &Scene, a: FaceId, b: FaceId) -> bool {
    let s = radlab_density_estimation::surfaces::Surfaces::new(scene, 0.9);
    s.of_face[a] == s.of_face[b]
}

#[test]
fn furnace_through_the_display_mesh_and_the_final_gather() {
    use radlab_density_estimation::DensityReconstruction;
    use radlab_method::Solution;
    let rho = 0.5;
    let exact = 1.0 / (1.0 - rho);
    let scene = builtin(&format!("furnace-cube?reflectance={rho}&tessellation=2")).expect("cube");
    let accel = Accel::new(&scene);
    let probes: Vec<(FaceId, DVec3)> = (0..scene.face_count())
        .flat_map(|f| {
            let poly = scene.polygon(f);
            [0.01, 0.5, 0.99]
                .into_iter()
                .flat_map(move |s| [0.01, 0.5, 0.99].map(|t| (f, poly.point_at(s, t))))
        })
        .collect();
    for reconstruction in [
        DensityReconstruction::Mesh,
        DensityReconstruction::FinalGather,
    ] {
        let params = DensityEstimationParams {
            particles: 40_000,
            steps: 2,
            reconstruction,
            element_size: Some(0.25),
            ..Default::default()
        };
        let means: Vec<f64> = (1..=SEEDS)
            .map(|seed| {
                let s = solve(&scene, &accel, &params, seed);
                probes
                    .iter()
                    .map(|&(f, p)| s.radiosity_at(f, p).x)
                    .sum::<f64>()
                    / probes.len() as f64
            })
            .collect();
        let (m, se) = mean_se(&means);
        assert!(
            (m - exact).abs() < 4.5 * se,
            "{reconstruction:?}: {m} ± {se}, exact {exact}"
        );
    }
}

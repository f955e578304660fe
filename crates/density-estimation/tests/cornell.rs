//! Density estimation against the path tracer on the Cornell box and on a bumped sphere of 10,000 faces (where
//! surfaces are curved groups of faces): the mean radiosity over 128 evaluation points per channel. The kernel estimate's bias (O(h²)∇²H, blur of the light's footprint and shadows) has no closed
//! form on this scene, so it is held to the project's coarse Cornell-box target, 3 % of the mean (as the photon
//! map's test is), plus four standard errors of the difference (three seeds here, the path tracer's own
//! errors there); the measured bias is printed.

use radlab_density_estimation::surfaces::Surfaces;
use radlab_density_estimation::{DensityEstimationParams, DensityEstimationSolver};
use radlab_method::{Solver, Step, evaluation_points};
use radlab_pathtrace::{PointParams, estimate_points, surface_points};
use radlab_scene::{Rgb, Scene, builtin};
use radlab_testkit::ChannelMeans;
use radlab_visibility::Accel;

#[test]
fn mean_agrees_with_the_path_tracer_on_the_cornell_box() {
    agrees_with_the_path_tracer(&builtin("cornell").expect("scene"));
}

#[test]
fn bumpy_sphere_is_estimated_over_groups_of_faces() {
    let scene = builtin("bumpy-sphere?faces=10000").expect("scene");
    let cos = 30f64.to_radians().cos();
    let s = Surfaces::new(&scene, cos);
    // Every face within the cone of its surface's seed normal.
    for (f, &k) in s.of_face.iter().enumerate() {
        let surface = &s.surfaces[k as usize];
        assert!(surface.faces.contains(&f));
        assert!(scene.faces[f].normal.dot(surface.normal) >= cos);
    }
    // Triangles too small to hold particles are grouped: on average well over ten faces a surface.
    let per_surface = scene.face_count() as f64 / s.surfaces.len() as f64;
    eprintln!(
        "{} faces in {} surfaces",
        scene.face_count(),
        s.surfaces.len()
    );
    assert!(per_surface > 10.0, "{per_surface} faces a surface");
    agrees_with_the_path_tracer(&scene);
}

fn agrees_with_the_path_tracer(scene: &Scene) {
    let accel = Accel::new(scene);
    let pts = surface_points(&evaluation_points(scene, 128, 3));
    let reference = estimate_points(
        scene,
        &accel,
        &pts,
        &PointParams {
            samples: 1024,
            ..PointParams::default()
        },
        99,
    );
    let params = DensityEstimationParams {
        particles: 100_000,
        steps: 2,
        ..Default::default()
    };
    let runs: Vec<Vec<Rgb>> = (1..=3)
        .map(|seed| {
            let mut s =
                DensityEstimationSolver::new(scene, &accel, params.clone(), seed).expect("valid");
            while s.step().expect("step") == Step::Continue {}
            pts.iter()
                .map(|p| s.solution().radiosity_at(p.face, p.point))
                .collect()
        })
        .collect();
    let reference: Vec<(Rgb, Rgb)> = reference.iter().map(|e| (e.mean, e.std_error)).collect();
    for c in 0..3 {
        let m = ChannelMeans::new(&reference, &runs, c);
        eprintln!(
            "{}, channel {c}: {:.5} ± {:.5} vs path tracing {:.5} ± {:.5}: {:+.4}",
            scene.name,
            m.mean,
            m.se,
            m.reference,
            m.reference_se,
            m.mean / m.reference - 1.0
        );
        // 3 %: the photon map's coarse target for a biased estimate, plus four standard errors.
        assert!(
            m.agrees(0.03, 4.0),
            "channel {c}: {m:?} (tolerance {})",
            m.tolerance(0.03, 4.0)
        );
    }
}

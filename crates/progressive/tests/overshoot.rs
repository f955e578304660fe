//! Overshooting (Feda & Purgathofer 1992; Gortler, Cohen & Slusallek 1993) against plain Southwell shooting
//! (Cohen, Chen, Wallace & Greenberg 1988): the furnace answer B = E/(1 − ρ) in fewer shots, the same fixed point
//! as plain shooting, and a stopping rule that still bounds the error when unshot radiosity goes negative.
//!
//! The bound used throughout: the unshot radiosity is the residual r = E + ρ F S − S of the linear system
//! (S the radiosity shot so far) and the displayed radiosity is B = E + ρ F S, so the error is
//! B* − B = ρ F (I − ρ F)⁻¹ r. In the power norm ‖x‖ = Σ_p A_p |x_p| the operator ρ F has norm at most ρ_max
//! (reciprocity, A_i F_ij = A_j F_ji, and Σ_i F_ji ≤ 1), so ‖B* − B‖ ≤ ρ_max/(1 − ρ_max) · ‖r‖ whatever the
//! signs of r; the stopping rule ‖r‖ ≤ f Φ (per channel) then gives ‖B* − B‖ ≤ ρ_max f Φ/(1 − ρ_max), and in a
//! furnace, where ‖B*‖ = Φ/(1 − ρ), a relative L1 error of at most ρ f.

use radlab_kernels::form_factor::VisibilitySampling;
use radlab_method::{Solver, Step};
use radlab_progressive::{Overshoot, ProgressiveParams, ProgressiveSolver, StopReason};
use radlab_scene::{Rgb, Scene, builtin};
use radlab_visibility::Accel;

mod common;
use common::closed_room;

fn run(solver: &mut ProgressiveSolver) {
    while solver.step().expect("step") == Step::Continue {}
}

/// Largest reflectance of any face, per channel.
fn rho_max(scene: &Scene) -> Rgb {
    (0..scene.face_count())
        .map(|f| scene.reflectance(f))
        .fold(Rgb::ZERO, Rgb::max)
}

#[test]
fn furnace_is_reached_in_fewer_shots_than_plain_shooting() {
    // 24 patches (one per input face), exact kernel row sums: the discrete answer is E/(1 − ρ) exactly, for ρ up
    // to 0.999, both variants stopping on the unshot fraction f = 0.5 %, which bounds the relative L1 error by
    // ρ f and keeps every element within 1 %.
    let stop = 5e-3;
    for rho in [0.5, 0.9, 0.99, 0.999] {
        let scene = builtin(&format!(
            "furnace-cube?reflectance={rho}&emission=2&tessellation=2"
        ))
        .expect("scene");
        let accel = Accel::new(&scene);
        let exact = 2.0 / (1.0 - rho);
        let mut shots = Vec::new();
        for overshoot in [Overshoot::None, Overshoot::Ambient] {
            let params = ProgressiveParams {
                element_size: Some(0.5),
                patch_size: Some(0.5),
                visibility: VisibilitySampling::Centre,
                adaptive: false,
                stop_unshot_fraction: stop,
                overshoot,
                ..Default::default()
            };
            let mut solver = ProgressiveSolver::new(&scene, &accel, params, 1).expect("solver");
            run(&mut solver);
            assert_eq!(solver.stop_reason(), Some(StopReason::UnshotFraction));
            let elements = solver.elements();
            let area: f64 = elements.iter().map(|e| e.area).sum();
            let l1: f64 = elements
                .iter()
                .map(|e| e.area * (e.radiosity.x - exact).abs())
                .sum::<f64>()
                / (area * exact);
            let worst = elements
                .iter()
                .map(|e| (e.radiosity - Rgb::splat(exact)).abs().max_element() / exact)
                .fold(0.0, f64::max);
            println!(
                "furnace rho={rho} {overshoot:?}: {} shots, unshot fraction {:.2e}, relative L1 error {l1:.2e} \
                 (bound rho*f = {:.2e}), worst element {worst:.2e}",
                solver.shots(),
                solver.unshot_fraction(),
                rho * solver.unshot_fraction()
            );
            assert!(
                l1 <= rho * solver.unshot_fraction() * (1.0 + 1e-9),
                "rho {rho} {overshoot:?}: L1 {l1} above the residual bound"
            );
            assert!(worst < 0.01, "rho {rho} {overshoot:?}: worst {worst}");
            if overshoot == Overshoot::None {
                // Plain shooting only adds light: its error is a shortfall everywhere.
                assert!(
                    elements.iter().all(|e| e.radiosity.x <= exact),
                    "rho {rho}: plain shooting overshot"
                );
            }
            shots.push(solver.shots());
        }
        assert!(
            shots[1] < shots[0],
            "rho {rho}: overshooting took {} shots, plain {}",
            shots[1],
            shots[0]
        );
    }
}

#[test]
fn overshooting_converges_to_the_fixed_point_of_plain_shooting() {
    // Closed room with an occluder and colour, fixed mesh (every pair's factor is the same whatever the order of
    // shots): both variants solve one linear system. Each stops at ‖r‖ ≤ f Φ, so each element of each is within
    // ρ_max f Φ / ((1 − ρ_max) A_e) of the system's solution (one element can hold at most the whole power-norm
    // error), and the two within twice that.
    let scene = closed_room(1.0);
    let accel = Accel::new(&scene);
    let phi = scene.emitted_power();
    let rmax = rho_max(&scene);
    let solve = |overshoot, stop| {
        let params = ProgressiveParams {
            stop_unshot_fraction: stop,
            overshoot,
            ..ProgressiveParams::fixed_mesh(0.2, VisibilitySampling::Jittered2x2)
        };
        let mut s = ProgressiveSolver::new(&scene, &accel, params, 7).expect("solver");
        run(&mut s);
        assert_eq!(s.stop_reason(), Some(StopReason::UnshotFraction));
        (s.elements(), s.shots(), s.unshot_fraction())
    };
    let (plain, plain_shots, fp) = solve(Overshoot::None, 1e-6);
    let (over, over_shots, fo) = solve(Overshoot::Ambient, 1e-6);
    println!("closed room, stop 1e-6: plain {plain_shots} shots, overshooting {over_shots} shots");
    assert_eq!(plain.len(), over.len());
    let scale = rmax / (Rgb::ONE - rmax) * phi;
    let mut worst: f64 = 0.0;
    for (a, b) in plain.iter().zip(&over) {
        assert_eq!(a.polygon, b.polygon);
        let bound = scale * (fp + fo) / a.area;
        let d = (a.radiosity - b.radiosity).abs();
        assert!(d.cmple(bound).all(), "{d:?} > {bound:?}");
        worst = worst.max((d / bound).max_element());
    }
    println!("largest difference / bound: {worst:.2e}");

    // The stopping rule at the default fraction bounds the error in the power norm, negative unshot or not.
    let (coarse, coarse_shots, f) = solve(Overshoot::Ambient, 2e-3);
    let err: Rgb = coarse
        .iter()
        .zip(&plain)
        .map(|(c, p)| c.area * (c.radiosity - p.radiosity).abs())
        .sum();
    let bound = scale * (f + fp);
    println!(
        "overshooting to f = {f:.2e} in {coarse_shots} shots: power-norm error {err:?}, bound {bound:?}"
    );
    assert!(err.cmple(bound).all(), "{err:?} > {bound:?}");
}

#[test]
fn overshooting_never_lights_a_closed_unlit_interior() {
    // A furnace cube with a light, and far away a closed, unlit box (inward normals) of high reflectance: no
    // light reaches it, so its radiosity is exactly zero, even though overshooting anticipates ambient light
    // everywhere light has been.
    let lit = builtin("furnace-cube?reflectance=0.9&tessellation=2").expect("scene");
    let mut b = radlab_scene::SceneBuilder::new("two rooms");
    let m_lit = b
        .add_material(radlab_scene::Material::new("lit", Rgb::splat(0.9), Rgb::ONE).expect("m"))
        .expect("m");
    let m_dark = b
        .add_material(radlab_scene::Material::new("dark", Rgb::splat(0.95), Rgb::ZERO).expect("m"))
        .expect("m");
    for f in 0..lit.face_count() {
        let pts = lit.polygon(f).vertices().to_vec();
        b.add_polygon_points(&pts, m_lit, "lit").expect("f");
        let far: Vec<_> = pts
            .iter()
            .map(|p| *p + radlab_scene::glam::DVec3::new(3.0, 0.0, 0.0))
            .collect();
        b.add_polygon_points(&far, m_dark, "dark").expect("f");
    }
    let scene = b.build().expect("scene");
    let accel = Accel::new(&scene);
    let params = ProgressiveParams {
        element_size: Some(0.25),
        overshoot: Overshoot::Ambient,
        ..Default::default()
    };
    let mut solver = ProgressiveSolver::new(&scene, &accel, params, 3).expect("solver");
    run(&mut solver);
    let mut dark = 0;
    for e in solver.elements() {
        if scene.material(e.face).name == "dark" {
            assert_eq!(e.radiosity, Rgb::ZERO);
            dark += 1;
        } else {
            assert!(e.radiosity.is_finite() && e.radiosity.min_element() > 0.0);
        }
    }
    assert!(dark > 0);
}

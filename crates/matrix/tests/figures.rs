//! Figures for the crate's report, printed rather than asserted (the asserting tests live in matrix.rs).
//! Run: `cargo test --release -p radlab-matrix --test figures -- --ignored --nocapture`.

mod common;

use std::time::Instant;

use radlab_matrix::{Iteration, MatrixParams, MatrixSolver, VisibilitySampling};
use radlab_method::{Solver, Step};
use radlab_scene::{Rgb, builtin};
use radlab_visibility::Accel;

fn run(s: &mut MatrixSolver) {
    while s.step().expect("step") == Step::Continue {}
}

fn assemble(s: &mut MatrixSolver) {
    while !s.is_assembled() {
        s.step().expect("assembly");
    }
}

#[test]
#[ignore = "prints figures; run by hand"]
fn cornell_assembly_and_solve_times() {
    let scene = common::cornell_like(false, Rgb::splat(0.73));
    let accel = Accel::new(&scene);
    println!("threads: {}", rayon::current_num_threads());
    for (vis, q) in [
        (VisibilitySampling::Jittered4x4, 2),
        (VisibilitySampling::Jittered2x2, 2),
        (VisibilitySampling::Jittered4x4, 1),
        (VisibilitySampling::Jittered4x4, 3),
    ] {
        let params = MatrixParams {
            visibility: vis,
            quadrature: q,
            ..MatrixParams::default()
        };
        let mut s = MatrixSolver::new(&scene, &accel, params, 1).expect("solver");
        let t = Instant::now();
        assemble(&mut s);
        let ta = t.elapsed().as_secs_f64();
        let st = s.stats();
        let n = s.mesh().len();
        // Row sums and the reciprocity correction.
        let (mut max_diag, mut max_row, mut worst) = (0.0f64, 0.0f64, 0);
        for i in 0..n {
            if s.form_factor(i, i).abs() > max_diag {
                worst = i;
            }
            max_diag = max_diag.max(s.form_factor(i, i).abs());
            max_row = max_row.max((0..n).map(|j| s.form_factor(i, j)).sum::<f64>());
        }
        println!(
            "cornell-like open: n = {n}, {vis:?} q = {q}: assembly {ta:.2} s in {} steps, {} rays, \
             {} form factors, max |F'_ii| = {max_diag:.2e} (face {}, centroid {}), max row sum = {max_row:.6}",
            st.steps,
            st.rays,
            st.form_factors,
            s.mesh().elements[worst].face,
            s.mesh().elements[worst].centroid
        );
        let mut hist = [0usize; 5];
        for i in 0..n {
            let d = s.form_factor(i, i).abs();
            let k = if d < 1e-4 {
                0
            } else if d < 1e-3 {
                1
            } else if d < 1e-2 {
                2
            } else if d < 3e-2 {
                3
            } else {
                4
            };
            hist[k] += 1;
        }
        println!("  |F'_ii| elements <1e-4, <1e-3, <1e-2, <3e-2, larger: {hist:?}");
        for m in [
            Iteration::Jacobi,
            Iteration::GaussSeidel,
            Iteration::ConjugateGradient,
        ] {
            s.restart(m);
            let t = Instant::now();
            run(&mut s);
            println!(
                "  {m:?}: {} iterations, {:.3} s, residual {:.2e}",
                s.iterations(),
                t.elapsed().as_secs_f64(),
                s.stats().residual.unwrap_or(f64::NAN)
            );
        }
    }
}

#[test]
#[ignore = "prints figures; run by hand"]
fn closed_cornell_row_sums() {
    for vis in [
        VisibilitySampling::Centre,
        VisibilitySampling::Jittered2x2,
        VisibilitySampling::Jittered4x4,
        VisibilitySampling::Jittered8x8,
    ] {
        let scene = common::cornell_like(true, Rgb::splat(0.73));
        let accel = Accel::new(&scene);
        let mut s = MatrixSolver::new(
            &scene,
            &accel,
            MatrixParams {
                visibility: vis,
                element_size: Some(50.0),
                ..MatrixParams::default()
            },
            1,
        )
        .expect("solver");
        assemble(&mut s);
        let n = s.mesh().len();
        let (mut sum_dev, mut max_dev, mut area) = (0.0, 0.0f64, 0.0);
        for (i, e) in s.mesh().elements.iter().enumerate() {
            let r: f64 = (0..n).map(|j| s.form_factor(i, j)).sum();
            if r == 0.0 {
                continue; // floor under a block: sees only the block's backs
            }
            sum_dev += e.area * (r - 1.0).abs();
            area += e.area;
            max_dev = max_dev.max((r - 1.0).abs());
        }
        println!(
            "closed cornell-like n = {n} {vis:?}: row sums − 1: area-mean |dev| {:.2e}, max {:.2e}",
            sum_dev / area,
            max_dev
        );
        let mut line = String::from("  per face (area-mean row sum − 1):");
        for f in 0..scene.faces.len() {
            let (mut d, mut a) = (0.0, 0.0);
            for i in s.mesh().elements_of(f) {
                let r: f64 = (0..n).map(|j| s.form_factor(i, j)).sum();
                let e = &s.mesh().elements[i];
                d += e.area * (r - 1.0);
                a += e.area;
            }
            line += &format!(" {f}:{:+.1e}", d / a);
        }
        println!("{line}");
    }
}

#[test]
#[ignore = "prints figures; run by hand"]
fn iteration_counts_against_reflectance() {
    for rho in [0.3, 0.9, 0.99, 0.999] {
        let scene =
            builtin(&format!("furnace-cube?reflectance={rho}&tessellation=4")).expect("scene");
        let accel = Accel::new(&scene);
        let mut s = MatrixSolver::new(
            &scene,
            &accel,
            MatrixParams {
                element_size: Some(0.25),
                ..MatrixParams::default()
            },
            1,
        )
        .expect("solver");
        assemble(&mut s);
        let mut line = format!("furnace cube ρ = {rho}, n = {}:", s.mesh().len());
        for m in [
            Iteration::Jacobi,
            Iteration::GaussSeidel,
            Iteration::ConjugateGradient,
        ] {
            s.restart(m);
            run(&mut s);
            let err = s
                .element_radiosity()
                .iter()
                .map(|b| (b.x * (1.0 - rho) - 1.0).abs())
                .fold(0.0, f64::max);
            line += &format!(" {m:?} {} it (max rel err {err:.1e});", s.iterations());
        }
        println!("{line}");
    }
    for rho in [0.5, 0.9, 0.99, 0.999] {
        let scene = common::cornell_grey(true, rho);
        let accel = Accel::new(&scene);
        let mut s = MatrixSolver::new(
            &scene,
            &accel,
            MatrixParams {
                element_size: Some(100.0),
                ..MatrixParams::default()
            },
            1,
        )
        .expect("solver");
        assemble(&mut s);
        let mut line = format!(
            "closed grey cornell-like ρ = {rho}, n = {}:",
            s.mesh().len()
        );
        for m in [
            Iteration::Jacobi,
            Iteration::GaussSeidel,
            Iteration::ConjugateGradient,
        ] {
            s.restart(m);
            let t = Instant::now();
            run(&mut s);
            line += &format!(
                " {m:?} {} it ({:.3} s{});",
                s.iterations(),
                t.elapsed().as_secs_f64(),
                if s.hit_iteration_cap() { ", cap" } else { "" }
            );
        }
        println!("{line}");
    }
}

#[test]
#[ignore = "prints figures; run by hand"]
fn howell_errors_against_mesh_and_quadrature() {
    for (spec, f_howell) in [
        ("parallel-squares", 0.199825),
        ("perpendicular-squares", 0.200044),
    ] {
        let scene = builtin(spec).expect("scene");
        let accel = Accel::new(&scene);
        for q in [1, 2, 3] {
            for k in [6, 12, 24, 48] {
                let s = {
                    let mut s = MatrixSolver::new(
                        &scene,
                        &accel,
                        MatrixParams {
                            element_size: Some(1.0 / k as f64),
                            quadrature: q,
                            ..MatrixParams::default()
                        },
                        1,
                    )
                    .expect("solver");
                    run(&mut s);
                    s
                };
                let (mut sum, mut area) = (0.0, 0.0);
                for (e, b) in s.mesh().elements.iter().zip(s.element_radiosity()) {
                    if !scene.material(e.face as usize).is_emitter() {
                        sum += e.area * b.x;
                        area += e.area;
                    }
                }
                let f = sum / area / 0.5;
                println!(
                    "{spec} q = {q} {k}×{k}: F = {f:.7} rel err {:+.2e}",
                    f / f_howell - 1.0
                );
            }
        }
    }
}

#[test]
#[ignore = "prints figures; run by hand"]
fn builtin_cornell_default_parameters() {
    let scene = match builtin("cornell") {
        Ok(s) => s,
        Err(e) => {
            println!("builtin cornell unavailable: {e}");
            return;
        }
    };
    let t = Instant::now();
    let accel = Accel::new(&scene);
    println!(
        "builtin cornell: {} faces, BVH {:.2} s, threads {}",
        scene.faces.len(),
        t.elapsed().as_secs_f64(),
        rayon::current_num_threads()
    );
    let mut s = MatrixSolver::new(&scene, &accel, MatrixParams::default(), 1).expect("solver");
    let t = Instant::now();
    assemble(&mut s);
    let st = s.stats();
    println!(
        "  n = {}, assembly {:.2} s in {} steps, {} rays, {} form factors, {:.1} MB",
        s.mesh().len(),
        t.elapsed().as_secs_f64(),
        st.steps,
        st.rays,
        st.form_factors,
        st.bytes as f64 / 1e6
    );
    for m in [
        Iteration::Jacobi,
        Iteration::GaussSeidel,
        Iteration::ConjugateGradient,
    ] {
        s.restart(m);
        let t = Instant::now();
        run(&mut s);
        println!(
            "  {m:?}: {} iterations, {:.3} s, residual {:.2e}",
            s.iterations(),
            t.elapsed().as_secs_f64(),
            s.stats().residual.unwrap_or(f64::NAN)
        );
    }
}

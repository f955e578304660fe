//! The conformance suite: every method in the runner's registry ([`radlab_runner::methods::methods`]) on the
//! same small scenes whose answers nobody here chose, so a method registered later is covered without editing
//! this file.
//!
//! Cases and their exact answers:
//! - **furnace cube and sphere** at ρ = 0, 0.5, 0.9, 0.99, 0.999: a closed enclosure of uniform ρ and E has
//!   B = E/(1 − ρ) everywhere (the kernel's rows sum to 1 at every point); within 1 %.
//! - **Howell's plates**: parallel coaxial squares and perpendicular squares sharing an edge (Howell's catalogue,
//!   C-11 and C-14), a black emitter lighting a receiver that sees nothing else, so the receiver's radiosity at
//!   x is B(x) = ρ E F_{dx→emitter}, the point-to-polygon form factor (Lambert's contour integral; Baum,
//!   Rushmeier & Winget 1989, eq. 3). A method with constant elements of diameter d holds, at x, the value of
//!   B at some point of x's element (an element mean is attained somewhere in it), so its error at x is at
//!   most d |∇B| there: the bound on the relative L1 error is d Σ|∇B(x_i)| / Σ B(x_i), with ∇B by central
//!   differences of the closed form, d = √2 h for square elements of side h.
//! - **energy balance**: in a closed scene the emitted power equals the absorbed power
//!   Σ_f ∫ (1 − ρ_f)(B − E_f)/ρ_f dA, to each method's stated tolerance (the table below).
//! - **threads**: 1 and 2 rayon threads (pools built explicitly) give bit-identical radiosity.
//! - **scale**: the scene scaled by 1e-4 and 1e4 (lengths in the parameters scaled alike) gives the same
//!   radiosity to 1e-9 relative: radiosity is an exitance, and every default length is relative.
//! - **box on/above floor, boxes touching walls**: closed boxes 1e-6 above a floor and flush against walls and
//!   floor, each holding a closed unlit interior (inward faces): no light reaches it (B = 0 exactly), and no
//!   radiosity anywhere is negative or non-finite.
//! - **sliver** (aspect ratio 1e4) and **fan** (a triangle fan with a face of relative area 5e-8) inside a
//!   furnace: still B = E/(1 − ρ) within 1 %.
//! - **emitter facing away** from every surface: exactly its own emission on it and zero elsewhere.
//! - **bright emitters**: two emitters 1e6 apart in a closed box: energy balance, B ≥ E on both, finite.
//! - **a final gather's cost**: its data is part of the bytes a method reports once it has answered, and its
//!   kernel evaluations are reported (`Solution::answer_kernel_evaluations`).
//!
//! Monte Carlo methods carry noise: a method whose test settings ask for `seeds > 1` is run with that many
//! seeds, the suite compares the mean of the runs and adds three standard errors of that mean (from the spread
//! of the runs) to the bound. Test-sized parameters, seeds and the stated energy balance come from each
//! method's registry entry ([`radlab_runner::methods::TestSettings`]), so a method registered later brings its
//! own. A method that cannot meet a case at test-sized budgets is listed in [`EXCEPTIONS`] with the measured
//! error and the reason; the suite checks that the exception still holds as stated (so a fixed method fails
//! here until its exception is removed), and that every listed exception names a trial of the suite.
//!
//! Each method × case is one named trial (`method :: case`, through libtest-mimic), run in parallel: `cargo
//! test -p radlab-runner --test conformance -- face-cluster` runs one method's cases, `-- "furnace cube"` one
//! case for every method. With `--nocapture` each trial prints its row of the method × case table (measured,
//! bound, time).

use std::fmt::Write as _;
use std::process::ExitCode;
use std::sync::Arc;

use libtest_mimic::{Arguments, Failed, Trial};

use radlab_kernels::form_factor::point_polygon;
use radlab_method::{EvalPoint, Solver, Step, evaluation_points};
use radlab_runner::methods::{MethodInfo, TestSettings, methods};
use radlab_scene::glam::{DVec3, dvec3};
use radlab_scene::{FaceId, Material, Rgb, Scene, SceneBuilder, builtin};
use radlab_testkit::{add_box, box_sides, grid, hollow_box, material, room, scaled};
use radlab_visibility::Accel;

/// Safety cap on steps per run (a method that has not converged by then fails the case, saying so).
const MAX_STEPS: usize = 200_000;
/// Evaluation points per scene (deterministic, area-stratified over the non-emitting faces).
const POINTS: usize = 96;

/// What an exception promises: the case still misses its bound (and stays finite), or at least stays finite.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Expect {
    /// The measured error still exceeds the bound; all values finite.
    Misses,
    /// Runs (with the overrides) and stays finite and non-negative; accuracy not claimed.
    Finite,
}

/// A method that cannot meet a case at test-sized budgets, with the measured error and the reason.
struct Exception {
    method: &'static str,
    case: &'static str,
    expect: Expect,
    /// Parameter overrides for the check run (e.g. a smaller budget when the full one is too slow for a test).
    overrides: &'static [(&'static str, &'static str)],
    reason: &'static str,
}

const EXCEPTIONS: &[Exception] = &[
    Exception {
        method: "mc-radiosity",
        case: "furnace cube ρ=0.999",
        expect: Expect::Finite,
        overrides: &[("particles_per_step", "100"), ("max_steps", "1")],
        // At the test-sized budget (4 × 20,000 particles) it passed: 4.4e-3 against a bound of 2.0e-2, in 79 s.
        reason: "random walks last 1/(1 − ρ) = 1000 bounces, so the test-sized budget takes over a minute in a \
                 debug build; checked at 100 particles for finite, non-negative output only",
    },
    Exception {
        method: "mc-radiosity",
        case: "furnace sphere ρ=0.999",
        expect: Expect::Finite,
        overrides: &[("particles_per_step", "100"), ("max_steps", "1")],
        // At the test-sized budget it passed: 4.8e-3 against a bound of 2.1e-2, in 64 s.
        reason: "random walks last 1000 bounces (as for the cube); checked at 100 particles for finite, \
                 non-negative output only",
    },
    Exception {
        method: "irradiance-cache",
        case: "furnace cube ρ=0.999",
        expect: Expect::Finite,
        overrides: &[("samples", "4")],
        // At the test-sized settings (4 runs, 64 directions a record) it passed: 1.45e-1 against a noise bound
        // of 4.28e-1, in 26 s of debug build (2026-12-05).
        reason: "each gather ray is continued by a path of 1/(1 − ρ) = 1000 bounces, so the test-sized budget \
                 takes half a minute in a debug build (radlab-irradiance-cache's own tests check furnaces at \
                 ρ = 0.5 and 0.9 against E/(1 − ρ) within 4 standard errors); checked at 4 directions a record \
                 for finite, non-negative output only",
    },
    Exception {
        method: "irradiance-cache",
        case: "furnace sphere ρ=0.999",
        expect: Expect::Finite,
        overrides: &[("samples", "4")],
        // At the test-sized settings it passed: 1.44e-1 against 4.27e-1, in 39 s (2026-12-05).
        reason: "paths last 1000 bounces (as for the cube); checked at 4 directions a record for finite, \
                 non-negative output only",
    },
    Exception {
        method: "bdpt",
        case: "furnace cube ρ=0.999",
        expect: Expect::Finite,
        overrides: &[("samples", "16")],
        // At 4 × 256 samples per point it passed, in 240 s of debug build (2026-12-05).
        reason: "eye subpaths last 1/(1 − ρ) = 1000 bounces and each eye vertex is joined to the light \
                 subpath's vertices by shadow rays, so the test-sized budget takes minutes in a debug build \
                 (radlab-bdpt's own tests check furnaces at ρ = 0.3 and 0.8 within 4.5 standard errors); \
                 checked at 16 samples per point for finite, non-negative output only",
    },
    Exception {
        method: "bdpt",
        case: "furnace sphere ρ=0.999",
        expect: Expect::Finite,
        overrides: &[("samples", "16")],
        reason: "subpaths last 1000 bounces (as for the cube); checked at 16 samples per point for finite, \
                 non-negative output only",
    },
    Exception {
        method: "radiosity-texture",
        case: "sliver (aspect 1e4) in a furnace",
        expect: Expect::Misses,
        overrides: &[],
        // Measured 9.0e-1 against a bound of 9.2e-2 (debug, 2026-12-05): B = E on the sliver in every run. Read by
        // a final gather over the same leaves (reconstruction = final-gather) it passed: 6.6e-3 against 4.9e-2.
        reason: "a histogram estimates a leaf from the landings in it: the sliver holds 1e-4 of the furnace's \
                 area, so of the test-sized 40,000 landings it expects about one per run, and a run with none \
                 reads B = E; the mean of 4 runs is E/(1 − ρ) only in expectation, with no spread to show it",
    },
    Exception {
        method: "radiosity-texture",
        case: "fan with a near-zero-area face in a furnace",
        expect: Expect::Misses,
        overrides: &[],
        // Measured 9.0e-1 against 6.3e-2 (debug, 2026-12-05); by a final gather it passed: 8.3e-3 against 3.9e-2.
        reason: "the fan's tiny triangle holds 5e-9 of the furnace's area and receives no landing at \
                 test-sized budgets, so it reads B = E (as for the sliver)",
    },
    Exception {
        method: "pathtrace",
        case: "furnace cube ρ=0.999",
        expect: Expect::Finite,
        overrides: &[("samples", "16")],
        // At 4 × 256 paths per point it passed: 8.5e-2 against a noise bound of 2.0e-1, in 45 s of debug build.
        reason: "paths last 1/(1 − ρ) = 1000 bounces, so the test-sized budget takes most of a minute in a \
                 debug build (radlab-pathtrace's own tests check this furnace within 4 standard errors); \
                 checked at 16 paths per point for finite, non-negative output only",
    },
    Exception {
        method: "pathtrace",
        case: "furnace sphere ρ=0.999",
        expect: Expect::Finite,
        overrides: &[("samples", "16")],
        // At 4 × 256 paths per point it passed: 8.4e-2 against 2.0e-1, in 80 s.
        reason: "paths last 1000 bounces (as for the cube); checked at 16 paths per point for finite, \
                 non-negative output only",
    },
];

fn exception(method: &str, case: &str) -> Option<&'static Exception> {
    EXCEPTIONS
        .iter()
        .find(|e| e.method == method && e.case == case)
}

// ---------------------------------------------------------------------------------------------------------
// Scenes.

/// A furnace cube of edge 1 (inward faces, 2 × 2 quads per side, h = 0.5) whose z = 0 side is replaced by
/// `floor` (a list of polygons covering the unit square).
fn furnace_with_floor(rho: f64, floor: &[Vec<DVec3>]) -> Scene {
    let mut b = SceneBuilder::new("furnace variant");
    let m = material(&mut b, "furnace", rho, 1.0);
    for (k, (o, u, v)) in box_sides(DVec3::ZERO, DVec3::ONE, false)
        .into_iter()
        .enumerate()
    {
        if k == 0 {
            for p in floor {
                b.add_polygon_points(p, m, "floor").expect("floor");
            }
        } else {
            grid(&mut b, o, u, v, 2, m);
        }
    }
    b.build().expect("scene")
}

// ---------------------------------------------------------------------------------------------------------
// Running a method.

/// Radiosity at `points` for each seed (1..=seeds), or why the run failed.
fn solve(
    m: &MethodInfo,
    scene: &Scene,
    accel: &Accel,
    params: &toml::Table,
    seeds: u64,
    points: &[(FaceId, DVec3)],
) -> Result<Vec<Vec<Rgb>>, String> {
    // The query points, handed to methods that answer at given points (path tracing).
    let eval: Vec<EvalPoint> = points
        .iter()
        .map(|&(face, point)| EvalPoint {
            face,
            point,
            normal: scene.faces[face].normal,
            weight: 1.0,
        })
        .collect();
    (1..=seeds)
        .map(|seed| {
            let mut s: Box<dyn Solver + '_> = (m.build)(scene, accel, params.clone(), seed, &eval)
                .map_err(|e| format!("build: {e}"))?;
            let mut converged = false;
            for _ in 0..MAX_STEPS {
                if s.step().map_err(|e| format!("step: {e}"))? == Step::Converged {
                    converged = true;
                    break;
                }
            }
            if !converged {
                return Err(format!("not converged after {MAX_STEPS} steps"));
            }
            let sol = s.solution();
            Ok(points
                .iter()
                .map(|&(f, p)| sol.radiosity_at(f, p))
                .collect())
        })
        .collect()
}

/// Mean over runs and the standard error of that mean per point (zero for one run).
fn mean_and_se(runs: &[Vec<Rgb>]) -> (Vec<Rgb>, Vec<Rgb>) {
    let k = runs.len() as f64;
    let n = runs[0].len();
    let mean: Vec<Rgb> = (0..n)
        .map(|i| runs.iter().map(|r| r[i]).sum::<Rgb>() / k)
        .collect();
    let se = (0..n)
        .map(|i| {
            if runs.len() < 2 {
                return Rgb::ZERO;
            }
            let var = runs
                .iter()
                .map(|r| (r[i] - mean[i]) * (r[i] - mean[i]))
                .sum::<Rgb>()
                / (k - 1.0);
            (var / k).map(f64::sqrt)
        })
        .collect();
    (mean, se)
}

/// The points of the scene's evaluation set, as (face, point).
fn eval_points(scene: &Scene) -> Vec<(FaceId, DVec3)> {
    evaluation_points(scene, POINTS, 1)
        .iter()
        .map(|p| (p.face, p.point))
        .collect()
}

/// An m × m grid of points (cell centres in the face's parameters) on face `f`, with the area each stands for.
fn face_grid(scene: &Scene, f: FaceId, m: usize) -> Vec<(FaceId, DVec3, f64)> {
    let poly = scene.polygon(f);
    let w = scene.faces[f].area / (m * m) as f64;
    let mut out = Vec::with_capacity(m * m);
    for j in 0..m {
        for i in 0..m {
            let (s, t) = ((i as f64 + 0.5) / m as f64, (j as f64 + 0.5) / m as f64);
            out.push((f, poly.point_at(s, t), w));
        }
    }
    out
}

// ---------------------------------------------------------------------------------------------------------
// Outcomes.

/// The result of one method on one case.
struct Outcome {
    /// The case's error measure (relative unless the case says otherwise).
    measured: f64,
    /// Its derived bound.
    bound: f64,
    /// Every value finite and non-negative.
    sane: bool,
    /// Why it could not run, if it could not.
    failure: Option<String>,
}

impl Outcome {
    fn pass(&self) -> bool {
        self.failure.is_none() && self.sane && self.measured <= self.bound
    }
    fn failed(why: String) -> Self {
        Self {
            measured: f64::NAN,
            bound: f64::NAN,
            sane: false,
            failure: Some(why),
        }
    }
}

fn sane(values: &[Rgb]) -> bool {
    values
        .iter()
        .all(|v| v.is_finite() && v.min_element() >= 0.0)
}

fn describe(o: &Outcome) -> String {
    if let Some(f) = &o.failure {
        return format!("FAIL: {f}");
    }
    let verdict = if o.pass() { "pass" } else { "FAIL" };
    let sanity = if o.sane {
        ""
    } else {
        ", negative or non-finite values"
    };
    format!("{verdict} {:.2e} / {:.2e}{sanity}", o.measured, o.bound)
}

// ---------------------------------------------------------------------------------------------------------
// Case evaluations.

/// Largest relative deviation from a uniform exact value over the points, against 1 % plus three standard
/// errors of the runs' mean.
fn uniform_case(
    m: &MethodInfo,
    scene: &Scene,
    exact: f64,
    params: &toml::Table,
    seeds: u64,
    extra_points: &[(FaceId, DVec3)],
) -> Outcome {
    let accel = Accel::new(scene);
    let mut points = eval_points(scene);
    points.extend_from_slice(extra_points);
    match solve(m, scene, &accel, params, seeds, &points) {
        Err(e) => Outcome::failed(e),
        Ok(runs) => {
            let (mean, se) = mean_and_se(&runs);
            let measured = mean
                .iter()
                .map(|b| (*b - Rgb::splat(exact)).abs().max_element() / exact)
                .fold(0.0, f64::max);
            let noise = se.iter().map(|s| s.max_element()).fold(0.0, f64::max) / exact;
            Outcome {
                measured,
                bound: 0.01 + 3.0 * noise,
                sane: runs.iter().all(|r| sane(r)),
                failure: None,
            }
        }
    }
}

/// Exact direct radiosity ρ E F_{dx→emitters} at a receiver point, and its gradient magnitude (central
/// differences in the receiver's plane).
fn direct(scene: &Scene, f: FaceId, x: DVec3) -> (f64, f64) {
    let n = scene.faces[f].normal;
    let rho = scene.reflectance(f).x;
    let field = |p: DVec3| -> f64 {
        scene
            .emitters()
            .into_iter()
            .map(|e| scene.emission(e).x * point_polygon(p, n, &scene.polygon(e)))
            .sum::<f64>()
            * rho
    };
    let d = 1e-5 * scene.diagonal();
    let t1 = n.any_orthonormal_vector();
    let t2 = n.cross(t1);
    let g1 = (field(x + d * t1) - field(x - d * t1)) / (2.0 * d);
    let g2 = (field(x + d * t2) - field(x - d * t2)) / (2.0 * d);
    (field(x), (g1 * g1 + g2 * g2).sqrt())
}

fn howell_case(m: &MethodInfo, scene: &Scene, h: f64, params: &toml::Table, seeds: u64) -> Outcome {
    let accel = Accel::new(scene);
    let points = eval_points(scene);
    match solve(m, scene, &accel, params, seeds, &points) {
        Err(e) => Outcome::failed(e),
        Ok(runs) => {
            let (mean, se) = mean_and_se(&runs);
            let (mut err, mut total, mut grad, mut noise) = (0.0, 0.0, 0.0, 0.0);
            for (k, &(f, x)) in points.iter().enumerate() {
                let (b, g) = direct(scene, f, x);
                err += (mean[k].x - b).abs();
                total += b;
                grad += g;
                noise += se[k].x;
            }
            let diameter = std::f64::consts::SQRT_2 * h;
            Outcome {
                measured: err / total,
                bound: (diameter * grad + 3.0 * noise) / total,
                sane: runs.iter().all(|r| sane(r)),
                failure: None,
            }
        }
    }
}

/// Relative energy imbalance |absorbed − emitted| / emitted (worst channel) on a closed scene whose faces are
/// all reflective, integrating over a 16 × 16 grid of cell centres per input face: exact for piecewise-constant
/// elements that tile each face in 2^k × 2^k for k ≤ 4 (the table keeps every method's elements that coarse).
///
/// Methods with a `reconstruction` parameter answer with their constant elements here, because every bound in
/// the settings table is derived from the element solution: a final gather's near field departs from the
/// element values on purpose (docs/methods.md, "Near field of the final gather"), so its answers need not sum
/// to the solution's balance.
fn balance_case(m: &MethodInfo, scene: &Scene, s: &TestSettings, params: &toml::Table) -> Outcome {
    let mut params = params.clone();
    if (m.params)().iter().any(|p| p.name == "reconstruction") {
        params.insert("reconstruction".into(), "constant".into());
    }
    let params = &params;
    let accel = Accel::new(scene);
    let mut grid_pts = Vec::new();
    for f in 0..scene.face_count() {
        grid_pts.extend(face_grid(scene, f, 16));
    }
    let points: Vec<(FaceId, DVec3)> = grid_pts.iter().map(|&(f, p, _)| (f, p)).collect();
    match solve(m, scene, &accel, params, s.seeds, &points) {
        Err(e) => Outcome::failed(e),
        Ok(runs) => {
            let phi = scene.emitted_power();
            let absorbed_of = |b: &[Rgb]| -> Rgb {
                grid_pts
                    .iter()
                    .zip(b)
                    .map(|(&(f, _, w), &b)| {
                        let rho = scene.reflectance(f);
                        w * (Rgb::ONE - rho) * (b - scene.emission(f)) / rho
                    })
                    .sum()
            };
            let per_run: Vec<Rgb> = runs.iter().map(|r| absorbed_of(r)).collect();
            let k = per_run.len() as f64;
            let mean = per_run.iter().copied().sum::<Rgb>() / k;
            let se = if per_run.len() > 1 {
                let var = per_run
                    .iter()
                    .map(|a| (*a - mean) * (*a - mean))
                    .sum::<Rgb>()
                    / (k - 1.0);
                (var / k).map(f64::sqrt)
            } else {
                Rgb::ZERO
            };
            let measured = ((mean - phi) / phi).abs().max_element();
            Outcome {
                measured,
                bound: s.balance + 3.0 * (se / phi).max_element(),
                sane: runs.iter().all(|r| sane(r)),
                failure: None,
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------------------
// The cases, and one trial per method × case.

/// What a case runs: the method, its test-sized settings and the parameters (with any exception's overrides).
type CaseFn = dyn Fn(&MethodInfo, &TestSettings, &toml::Table) -> Outcome + Send + Sync;

/// One case of the suite, run for every method.
struct Case {
    /// Its name, the second half of the trial's name (`method :: case`).
    name: String,
    /// The edge of the case's input faces, handed to [`TestSettings::params`].
    h: f64,
    /// Runs it.
    run: Arc<CaseFn>,
}

fn case(
    name: impl Into<String>,
    h: f64,
    run: impl Fn(&MethodInfo, &TestSettings, &toml::Table) -> Outcome + Send + Sync + 'static,
) -> Case {
    Case {
        name: name.into(),
        h,
        run: Arc::new(run),
    }
}

const FURNACE_RHOS: [f64; 5] = [0.0, 0.5, 0.9, 0.99, 0.999];

/// Furnaces: B = E/(1 − ρ), max relative error over the points.
fn furnace_cases(cases: &mut Vec<Case>) {
    for rho in FURNACE_RHOS {
        let exact = 1.0 / (1.0 - rho);
        let cube = Arc::new(
            builtin(&format!("furnace-cube?reflectance={rho}&tessellation=2")).expect("cube"),
        );
        cases.push(case(
            format!("furnace cube ρ={rho}"),
            0.5,
            move |m, s, p| uniform_case(m, &cube, exact, p, s.seeds, &[]),
        ));
        let sphere = Arc::new(
            builtin(&format!("furnace-sphere?reflectance={rho}&tessellation=2")).expect("sphere"),
        );
        let h = sphere.polygon(0).max_edge();
        cases.push(case(
            format!("furnace sphere ρ={rho}"),
            h,
            move |m, s, p| uniform_case(m, &sphere, exact, p, s.seeds, &[]),
        ));
    }
}

/// Howell's plates: relative L1 error against ρ E F_{dx→emitter}, bound d Σ|∇B| / Σ B (+ noise).
fn howell_cases(cases: &mut Vec<Case>) {
    let n = 8;
    let h = 1.0 / n as f64;
    for name in ["parallel", "perpendicular"] {
        let scene = Arc::new(
            builtin(&format!("{name}-squares?tessellation={n}")).expect("Howell's plates"),
        );
        cases.push(case(format!("{name} squares"), h, move |m, s, p| {
            howell_case(m, &scene, h, p, s.seeds)
        }));
    }
}

/// Closed convex room: |absorbed − emitted| / emitted against the method's stated tolerance (+ noise); two
/// emitters 1e6 apart.
fn balance_cases(cases: &mut Vec<Case>) {
    let plain = Arc::new(room("room", &|_| {}));
    // A second emitter 1e6 times dimmer than the light: the floor quad nearest the origin (face 0).
    let bright = {
        let mut b = SceneBuilder::new("room with a dim emitter");
        let dim = material(&mut b, "dim", 0.5, 1e-5);
        for f in 0..plain.face_count() {
            let mat = plain.material(f).clone();
            let id = if f == 0 {
                dim
            } else {
                b.add_material(Material {
                    name: format!("{}#{f}", mat.name),
                    ..mat
                })
                .expect("material")
            };
            b.add_polygon_points(plain.polygon(f).vertices(), id, "room")
                .expect("face");
        }
        Arc::new(b.build().expect("scene"))
    };
    assert!(bright.faces[0].normal.z > 0.5 && bright.emission(0).x == 1e-5);
    cases.push(case("energy balance", 0.5, move |m, s, p| {
        balance_case(m, &plain, s, p)
    }));
    let b = bright.clone();
    cases.push(case("emitters 1e6 apart: balance", 0.5, move |m, s, p| {
        balance_case(m, &b, s, p)
    }));
    // On each emitter B = E + ρ H ≥ E: the dim one must not lose its own emission under the bright one.
    cases.push(case(
        "emitters 1e6 apart: B ≥ E on the dim emitter",
        0.5,
        move |m, _, p| {
            let accel = Accel::new(&bright);
            let f = 0;
            let pts: Vec<_> = face_grid(&bright, f, 3)
                .into_iter()
                .map(|(f, x, _)| (f, x))
                .collect();
            match solve(m, &bright, &accel, p, 1, &pts) {
                Err(e) => Outcome::failed(e),
                Ok(runs) => {
                    let e = bright.emission(f).x;
                    // Zero when B ≥ E everywhere on it.
                    let shortfall = runs[0]
                        .iter()
                        .map(|b| (e - b.min_element()) / e)
                        .fold(0.0, f64::max);
                    Outcome {
                        measured: shortfall,
                        bound: 0.0,
                        sane: sane(&runs[0]),
                        failure: None,
                    }
                }
            }
        },
    ));
}

/// Determinism and scale: 1 vs 2 threads (bitwise differences), scene × 1e-4 and × 1e4 (max relative
/// difference, bound 1e-9).
fn thread_and_scale_cases(cases: &mut Vec<Case>) {
    let base = Arc::new(room("room with a block", &|b| {
        let m = material(b, "block", 0.5, 0.0);
        add_box(b, dvec3(0.3, 0.3, 0.0), dvec3(0.6, 0.5, 0.4), 1, m, true);
    }));
    let b = base.clone();
    cases.push(case("1 vs 2 threads", 0.5, move |m, _, p| {
        let accel = Accel::new(&b);
        let points = eval_points(&b);
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool");
            pool.install(|| solve(m, &b, &accel, p, 1, &points))
        };
        match (run(1), run(2)) {
            (Ok(x), Ok(y)) => {
                let differ = x[0]
                    .iter()
                    .zip(&y[0])
                    .filter(|(u, v)| {
                        u.to_array().map(f64::to_bits) != v.to_array().map(f64::to_bits)
                    })
                    .count();
                Outcome {
                    measured: differ as f64,
                    bound: 0.0,
                    sane: sane(&x[0]),
                    failure: None,
                }
            }
            (Err(e), _) | (_, Err(e)) => Outcome::failed(e),
        }
    }));
    cases.push(case("scale 1e-4 and 1e4", 0.5, move |m, _, p| {
        let accel = Accel::new(&base);
        let points = eval_points(&base);
        let reference = match solve(m, &base, &accel, p, 1, &points) {
            Ok(r) => r.into_iter().next().expect("one run"),
            Err(e) => return Outcome::failed(e),
        };
        let scale_b = reference
            .iter()
            .map(|b| b.max_element())
            .fold(0.0, f64::max);
        let mut worst: f64 = 0.0;
        let mut all_sane = sane(&reference);
        for k in [1e-4, 1e4] {
            let sc = scaled(&base, k);
            let accel = Accel::new(&sc);
            let pts: Vec<_> = points.iter().map(|&(f, x)| (f, x * k)).collect();
            // Lengths in the parameters (named `*_size` in every method) scale with the scene.
            let mut pk = p.clone();
            for (name, v) in pk.iter_mut() {
                if let (true, toml::Value::Float(x)) = (name.ends_with("_size"), v) {
                    *x *= k;
                }
            }
            match solve(m, &sc, &accel, &pk, 1, &pts) {
                Ok(run) => {
                    all_sane &= sane(&run[0]);
                    for (a, b) in run[0].iter().zip(&reference) {
                        worst = worst.max((*a - *b).abs().max_element() / scale_b);
                    }
                }
                Err(e) => return Outcome::failed(e),
            }
        }
        Outcome {
            measured: worst,
            bound: 1e-9,
            sane: all_sane,
            failure: None,
        }
    }));
}

/// Points over every face of `scene` whose material is `name` (3 × 3 per face).
fn points_on(scene: &Scene, name: &str) -> Vec<(FaceId, DVec3)> {
    (0..scene.face_count())
        .filter(|&f| scene.material(f).name == name)
        .flat_map(|f| face_grid(scene, f, 3))
        .map(|(f, x, _)| (f, x))
        .collect()
}

/// Closed unlit interiors: the largest radiosity found inside (must be exactly 0), plus sanity everywhere.
fn interior_case(m: &MethodInfo, scene: &Scene, params: &toml::Table, seeds: u64) -> Outcome {
    let accel = Accel::new(scene);
    let inside = points_on(scene, "interior");
    assert!(!inside.is_empty());
    let mut points = eval_points(scene);
    let n_eval = points.len();
    points.extend_from_slice(&inside);
    match solve(m, scene, &accel, params, seeds, &points) {
        Err(e) => Outcome::failed(e),
        Ok(runs) => {
            let mut measured: f64 = 0.0;
            for r in &runs {
                let lit = r[..n_eval]
                    .iter()
                    .map(|b| b.max_element())
                    .fold(0.0, f64::max);
                for b in &r[n_eval..] {
                    measured = measured.max(b.abs().max_element() / lit.max(1e-300));
                }
            }
            Outcome {
                measured,
                bound: 0.0,
                sane: runs.iter().all(|r| sane(r)),
                failure: None,
            }
        }
    }
}

/// Extremes: interiors (largest interior B / largest lit B, must be 0), furnaces with a sliver or a fan (max
/// relative error, 1 %), emitter facing away (max deviation from E on it and 0 elsewhere, relative to E).
fn extreme_cases(cases: &mut Vec<Case>) {
    let above = Arc::new(room("box 1e-6 above the floor", &|b| {
        hollow_box(b, dvec3(0.2, 0.2, 1e-6), dvec3(0.5, 0.5, 0.3));
    }));
    let touching = Arc::new(room("boxes touching walls", &|b| {
        // Flush against the x = 0 wall and the floor; and in the corner x = 1, y = 1 on the floor.
        hollow_box(b, dvec3(0.0, 0.3, 0.0), dvec3(0.25, 0.6, 0.3));
        hollow_box(b, dvec3(0.7, 0.7, 0.0), dvec3(1.0, 1.0, 0.5));
    }));
    let rho = 0.9;
    let sliver = Arc::new(furnace_with_floor(
        rho,
        &[
            vec![
                dvec3(0., 0., 0.),
                dvec3(1e-4, 0., 0.),
                dvec3(1e-4, 1., 0.),
                dvec3(0., 1., 0.),
            ],
            vec![
                dvec3(1e-4, 0., 0.),
                dvec3(1., 0., 0.),
                dvec3(1., 1., 0.),
                dvec3(1e-4, 1., 0.),
            ],
        ],
    ));
    assert_eq!(sliver.face_count(), 5 * 4 + 2, "the sliver must be kept");
    // A fan around the floor's centre over its boundary, with one extra boundary point 1e-7 from a corner: that
    // triangle's area is 2.5e-8 (5e-8 of its squared diameter), just above the scene's degenerate threshold.
    let c = dvec3(0.5, 0.5, 0.0);
    let ring = [
        dvec3(0., 0., 0.),
        dvec3(0., 1., 0.),
        dvec3(1., 1., 0.),
        dvec3(1., 1e-7, 0.),
        dvec3(1., 0., 0.),
    ];
    let fan: Vec<Vec<DVec3>> = (0..ring.len())
        .map(|k| vec![c, ring[(k + 1) % ring.len()], ring[k]])
        .collect();
    let fan_scene = Arc::new(furnace_with_floor(rho, &fan));
    assert_eq!(
        fan_scene.face_count(),
        5 * 4 + 5,
        "the fan must be kept whole"
    );
    // The floor's faces come first: the tiny triangle is (c, ring[4], ring[3]).
    let tiny = 3;
    let away = {
        let mut b = SceneBuilder::new("emitter facing away");
        let floor = material(&mut b, "floor", 0.5, 0.0);
        grid(
            &mut b,
            DVec3::ZERO,
            dvec3(1., 0., 0.),
            dvec3(0., 1., 0.),
            2,
            floor,
        );
        let light = material(&mut b, "light", 0.5, 3.0);
        // At z = 0.5 facing +z: its front sees nothing.
        grid(
            &mut b,
            dvec3(0.25, 0.25, 0.5),
            dvec3(0.5, 0., 0.),
            dvec3(0., 0.5, 0.),
            1,
            light,
        );
        Arc::new(b.build().expect("scene"))
    };
    cases.push(case(
        "closed box 1e-6 above the floor",
        0.5,
        move |m, s, p| interior_case(m, &above, p, s.seeds),
    ));
    cases.push(case("boxes touching walls", 0.5, move |m, s, p| {
        interior_case(m, &touching, p, s.seeds)
    }));
    let sliver_pt = [(0, dvec3(0.5e-4, 0.5, 0.0))];
    cases.push(case(
        "sliver (aspect 1e4) in a furnace",
        0.5,
        move |m, s, p| uniform_case(m, &sliver, 1.0 / (1.0 - rho), p, s.seeds, &sliver_pt),
    ));
    let tiny_pt = [(tiny, (c + ring[3] + ring[4]) / 3.0)];
    cases.push(case(
        "fan with a near-zero-area face in a furnace",
        0.5,
        move |m, s, p| uniform_case(m, &fan_scene, 1.0 / (1.0 - rho), p, s.seeds, &tiny_pt),
    ));
    cases.push(case("emitter facing away", 0.5, move |m, s, p| {
        let accel = Accel::new(&away);
        let mut pts = points_on(&away, "floor");
        let n_floor = pts.len();
        pts.extend(points_on(&away, "light"));
        match solve(m, &away, &accel, p, s.seeds, &pts) {
            Err(e) => Outcome::failed(e),
            Ok(runs) => {
                let e = 3.0;
                let mut worst: f64 = 0.0;
                for r in &runs {
                    for (k, b) in r.iter().enumerate() {
                        let exact = if k < n_floor { 0.0 } else { e };
                        worst = worst.max((*b - Rgb::splat(exact)).abs().max_element() / e);
                    }
                }
                Outcome {
                    measured: worst,
                    bound: 1e-12,
                    sane: runs.iter().all(|r| sane(r)),
                    failure: None,
                }
            }
        }
    }));
}

/// A final gather's work is counted the same way in every method: what a solution builds to answer (the
/// sources' values and bounds, the near field's sub-polygons) is part of the bytes its solver reports once it
/// has answered, and the point-to-polygon factors it evaluates are reported as answering kernel evaluations,
/// as the answering pass's rays and time are part of its cost. Run for every method with a `reconstruction`
/// parameter.
fn final_gather_work_is_counted(m: &MethodInfo) -> Result<(), Failed> {
    let scene = room("room with a block", &|b| {
        let mat = material(b, "block", 0.5, 0.0);
        add_box(b, dvec3(0.3, 0.3, 0.0), dvec3(0.6, 0.5, 0.4), 1, mat, true);
    });
    let accel = Accel::new(&scene);
    let points = eval_points(&scene);
    let mut p = (m.test.params)(0.5);
    p.insert("reconstruction".into(), "final-gather".into());
    let mut s = (m.build)(&scene, &accel, p, 1, &[]).map_err(|e| format!("build: {e}"))?;
    for _ in 0..MAX_STEPS {
        if s.step().map_err(|e| format!("step: {e}"))? != Step::Continue {
            break;
        }
    }
    let before = s.stats().bytes;
    if s.solution().answer_kernel_evaluations() != 0 {
        return Err("kernel evaluations reported before any answer".into());
    }
    for &(f, x) in &points {
        s.solution().radiosity_at(f, x);
    }
    let after = s.stats().bytes;
    if after <= before {
        return Err(
            format!("{before} bytes before answering by final gather, {after} after").into(),
        );
    }
    // At least one kernel per point (every point sees several elements of the room).
    let kernels = s.solution().answer_kernel_evaluations();
    if kernels < points.len() as u64 {
        return Err(format!(
            "{kernels} kernel evaluations answering {} points",
            points.len()
        )
        .into());
    }
    Ok(())
}

/// Runs one method on one case, applying the exception list: passes when the outcome meets its bound, or,
/// for a listed exception, when the exception still holds as stated.
fn run_case(method: &str, c: &Case, nocapture: bool) -> Result<(), Failed> {
    let m = methods()
        .into_iter()
        .find(|m| m.name == method)
        .expect("a registered method");
    let s = m.test;
    let params = (s.params)(c.h);
    let started = std::time::Instant::now();
    let (cell, failure) = match exception(method, &c.name) {
        None => {
            let o = (c.run)(&m, &s, &params);
            let failure = (!o.pass()).then(|| {
                format!(
                    "measured {:.3e}, bound {:.3e}, finite and non-negative {}{}",
                    o.measured,
                    o.bound,
                    o.sane,
                    o.failure
                        .as_deref()
                        .map(|f| format!(", {f}"))
                        .unwrap_or_default()
                )
            });
            (describe(&o), failure)
        }
        Some(x) => {
            let mut p = params.clone();
            for (k, v) in x.overrides {
                p.insert((*k).to_string(), radlab_method::params::parse_value(v));
            }
            let o = (c.run)(&m, &s, &p);
            let holds = match x.expect {
                Expect::Misses => o.failure.is_none() && o.sane && o.measured > o.bound,
                Expect::Finite => o.failure.is_none() && o.sane,
            };
            let failure = (!holds).then(|| {
                format!(
                    "the listed exception ({:?}: {}) no longer holds as stated: {} — update or remove it",
                    x.expect,
                    x.reason,
                    describe(&o)
                )
            });
            (
                format!("exception: {} — {}", describe(&o), x.reason),
                failure,
            )
        }
    };
    if nocapture {
        let mut line = String::new();
        let _ = write!(
            line,
            "| {method} | {} | {cell} | {:.1} s |",
            c.name,
            started.elapsed().as_secs_f64()
        );
        println!("{line}");
    }
    failure.map_or(Ok(()), |f| Err(f.into()))
}

fn main() -> ExitCode {
    let args = Arguments::from_args();
    let mut cases = Vec::new();
    furnace_cases(&mut cases);
    howell_cases(&mut cases);
    balance_cases(&mut cases);
    thread_and_scale_cases(&mut cases);
    extreme_cases(&mut cases);
    let cases: Vec<Arc<Case>> = cases.into_iter().map(Arc::new).collect();

    let mut trials = Vec::new();
    let mut gathering = 0;
    for m in methods() {
        for c in &cases {
            let (c, name, nocapture) = (c.clone(), m.name, args.nocapture);
            trials.push(Trial::test(format!("{name} :: {}", c.name), move || {
                run_case(name, &c, nocapture)
            }));
        }
        if (m.params)().iter().any(|l| l.name == "reconstruction") {
            gathering += 1;
            let name = m.name;
            trials.push(Trial::test(
                format!("{name} :: a final gather's work is counted"),
                move || {
                    let m = methods()
                        .into_iter()
                        .find(|m| m.name == name)
                        .expect("method");
                    final_gather_work_is_counted(&m)
                },
            ));
        }
    }
    // Every exception names a method and a case of the suite: one that matches no trial is stale.
    let case_names: Vec<String> = cases.iter().map(|c| c.name.clone()).collect();
    trials.push(Trial::test(
        "suite :: every listed exception is used",
        move || {
            let names: Vec<&str> = methods().iter().map(|m| m.name).collect();
            let stale: Vec<String> = EXCEPTIONS
                .iter()
                .filter(|x| !names.contains(&x.method) || !case_names.iter().any(|c| c == x.case))
                .map(|x| format!("{} :: {}", x.method, x.case))
                .collect();
            if stale.is_empty() {
                Ok(())
            } else {
                Err(format!(
                    "exceptions that match no trial (remove them): {}",
                    stale.join(", ")
                )
                .into())
            }
        },
    ));
    // Matrix, progressive, hierarchical, volume-cluster, face-cluster, mc-radiosity answer by final gather.
    trials.push(Trial::test(
        "suite :: six or more methods offer a final gather",
        move || {
            if gathering >= 6 {
                Ok(())
            } else {
                Err(format!("{gathering} methods answer by final gather").into())
            }
        },
    ));
    libtest_mimic::run(&args, trials).exit_code()
}

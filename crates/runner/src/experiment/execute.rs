//! Executing one run: build the method, step it to its stopping rule under the experiment's limits, evaluate
//! the solution at the evaluation points between steps (outside the timed region) against the reference, and
//! write `runs/<id>.trace.csv`, `images/<id>.exr` and, last, `runs/<id>.json` (its presence marks the run
//! complete). With isolation the run executes in a child process (`radlab run-one JOB.json`), so a crash, a
//! timeout or running out of memory is recorded as the run's outcome and the experiment goes on.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use radlab_method::{EvalPoint, MethodParams, Solver};
use radlab_scene::Rgb;
use radlab_visibility::Accel;
use serde::{Deserialize, Serialize};

use super::config::{Evaluation, LimitsConfig, OutputsConfig, ReferenceKind, RunSpec};
use super::metrics::{self, Errors};
use super::reference;
use crate::output::atomic::{write_bytes, write_csv_rows};
use crate::output::exr_image::write_exr;
use crate::solve_loop::{self, Limits};

/// Everything a run needs, serialisable for the child process.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Job {
    /// The run.
    pub spec: RunSpec,
    /// Digest of everything that determines the result (skip check).
    pub digest: String,
    /// The experiment's output directory.
    pub dir: PathBuf,
    /// Input faces of the scene.
    pub faces: u64,
    /// The cached reference file.
    pub reference_file: PathBuf,
    /// Which reference it is.
    pub reference_kind: ReferenceKind,
    /// The reference's noise floor.
    pub floor: Errors,
    /// Evaluation points.
    pub evaluation: Evaluation,
    /// Limits.
    pub limits: LimitsConfig,
    /// Outputs.
    pub outputs: OutputsConfig,
}

/// One row of `runs.csv`.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct RunResult {
    /// Run id.
    pub id: String,
    /// Config digest.
    pub digest: String,
    /// Expansion index.
    pub index: usize,
    /// Scene label.
    pub scene: String,
    /// Scaling family ("" for none).
    pub family: String,
    /// Input faces of the scene.
    pub faces: u64,
    /// Method name.
    pub method: String,
    /// Method label.
    pub label: String,
    /// All parameters, `k=v;...`.
    pub params: String,
    /// Swept parameters, `k=v;...`.
    pub sweep: String,
    /// Seed.
    pub seed: u64,
    /// converged, step-limit, time-limit, target-error, error, crash, timeout, out-of-memory.
    pub outcome: String,
    /// Error message for failed runs.
    pub message: String,
    /// Steps taken.
    pub steps: u64,
    /// Wall seconds in steps.
    pub wall_s: f64,
    /// Wall seconds building the solver before its first step (hierarchies built in advance: volume and face
    /// clusters), reported apart from the steps.
    #[serde(default)]
    pub setup_s: f64,
    /// CPU seconds in steps (all threads).
    pub cpu_s: f64,
    /// Evaluation points the run was measured (and, for path tracing, traced) at.
    #[serde(default)]
    pub points: u64,
    /// Wall seconds of answering at the evaluation points once, after the last step (a final gather's cost;
    /// near zero for constant and Gouraud reconstructions and for path tracing, which traces in its steps).
    #[serde(default)]
    pub answer_s: f64,
    /// Rays cast answering at the evaluation points once, after the last step.
    #[serde(default)]
    pub answer_rays: u64,
    /// Kernel evaluations spent answering at the evaluation points once, after the last step (a final
    /// gather's point-to-polygon factors; not in `form_factors`, which counts the steps).
    #[serde(default)]
    pub answer_form_factors: u64,
    /// Wall seconds of rendering the run's image (camera path tracing at the paths per point reached, for
    /// `pathtrace`; primary rays through the solution's reconstruction otherwise); 0 without images.
    #[serde(default)]
    pub image_s: f64,
    /// Peak resident memory of the run's process, bytes.
    pub peak_rss_bytes: u64,
    /// Elements.
    pub elements: u64,
    /// Links.
    pub links: u64,
    /// Form factors.
    pub form_factors: u64,
    /// Rays.
    pub rays: u64,
    /// Bytes the solver holds.
    pub bytes: u64,
    /// Final relative L1 error.
    #[serde(deserialize_with = "nan_if_null")]
    pub l1: f64,
    /// Final relative L2 error.
    #[serde(deserialize_with = "nan_if_null")]
    pub l2: f64,
    /// Final max relative error.
    #[serde(deserialize_with = "nan_if_null")]
    pub max: f64,
    /// Reference noise floor, L1.
    #[serde(deserialize_with = "nan_if_null")]
    pub floor_l1: f64,
    /// Reference noise floor, L2.
    #[serde(deserialize_with = "nan_if_null")]
    pub floor_l2: f64,
    /// Reference kind.
    pub reference: String,
    /// The method's own counters after the last step ([`radlab_method::Solver::counters`]), `name=value`
    /// joined by `;` (empty for methods without any).
    #[serde(default)]
    pub counters: String,
}

impl RunResult {
    /// Time to answer at the evaluation points: set-up, steps and one answering pass.
    pub fn time_to_answer(&self) -> f64 {
        self.setup_s + self.wall_s + self.answer_s
    }
}

/// One row of `trace.csv`.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct TraceRow {
    /// Run id.
    pub id: String,
    /// Scene label.
    pub scene: String,
    /// Method label.
    pub label: String,
    /// Swept parameters.
    pub sweep: String,
    /// Seed.
    pub seed: u64,
    /// Step number.
    pub step: u64,
    /// Wall seconds of the run's set-up (constructing the solver: hierarchy builds, preprocesses), counted in
    /// every time to answer. Filled from the run's result when the tables are written.
    #[serde(default)]
    pub setup_s: f64,
    /// Wall seconds of steps so far.
    pub wall_s: f64,
    /// CPU seconds of steps so far.
    pub cpu_s: f64,
    /// Wall seconds of answering at the evaluation points after this step (once, not summed over steps).
    #[serde(default)]
    pub answer_s: f64,
    /// Rays of answering at the evaluation points after this step.
    #[serde(default)]
    pub answer_rays: u64,
    /// Kernel evaluations of answering at the evaluation points after this step.
    #[serde(default)]
    pub answer_form_factors: u64,
    /// Elements.
    pub elements: u64,
    /// Links.
    pub links: u64,
    /// Form factors.
    pub form_factors: u64,
    /// Rays.
    pub rays: u64,
    /// Bytes held.
    pub bytes: u64,
    /// The method's own residual, if any.
    pub residual: Option<f64>,
    /// Relative L1 error.
    pub l1: f64,
    /// Relative L2 error.
    pub l2: f64,
    /// Max relative error.
    pub max: f64,
}

impl TraceRow {
    /// Time to answer at the evaluation points after this step: set-up, steps so far and one answering pass.
    pub fn time_to_answer(&self) -> f64 {
        self.setup_s + self.wall_s + self.answer_s
    }
}

/// JSON has no NaN: serde_json writes it as `null`, which reads back as NaN here (the error of a run that
/// failed before it could be evaluated).
fn nan_if_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// Paths of a run's files.
pub fn result_path(dir: &Path, id: &str) -> PathBuf {
    dir.join("runs").join(format!("{id}.json"))
}

/// Path of a run's trace.
pub fn trace_path(dir: &Path, id: &str) -> PathBuf {
    dir.join("runs").join(format!("{id}.trace.csv"))
}

/// Path of a run's last completed evaluation while it runs in a child process: what is kept of it if the child
/// is killed (its trace and points files are written with it).
pub fn partial_path(dir: &Path, id: &str) -> PathBuf {
    dir.join("runs").join(format!("{id}.partial.json"))
}

/// Path of a run's per-point answers (the final evaluation beside the reference).
pub fn points_path(dir: &Path, id: &str) -> PathBuf {
    dir.join("runs").join(format!("{id}.points.csv"))
}

/// One evaluation point of a run's final answer: where it is, the reference with its standard error, the
/// method's value and the point's error as the max column measures it.
/// `radlab compare` reads these rows back.
#[derive(serde::Serialize, serde::Deserialize)]
pub(crate) struct PointRow {
    pub(crate) point: usize,
    pub(crate) face: usize,
    pub(crate) x: f64,
    pub(crate) y: f64,
    pub(crate) z: f64,
    pub(crate) ref_r: f64,
    pub(crate) ref_g: f64,
    pub(crate) ref_b: f64,
    pub(crate) se_r: f64,
    pub(crate) se_g: f64,
    pub(crate) se_b: f64,
    pub(crate) r: f64,
    pub(crate) g: f64,
    pub(crate) b: f64,
    /// max over channels of |B − R| / max(|R|, floor), the max column's per-point term.
    pub(crate) rel_error: f64,
    /// max over channels of |B − R| / s (the reference's standard error; infinite where s = 0 and B ≠ R).
    pub(crate) z_score: f64,
}

/// Path of a run's image.
pub fn image_path(dir: &Path, id: &str) -> PathBuf {
    dir.join("images").join(format!("{id}.exr"))
}

fn base_result(job: &Job) -> RunResult {
    let s = &job.spec;
    RunResult {
        id: s.id(),
        digest: job.digest.clone(),
        index: s.index,
        scene: s.scene_label.clone(),
        family: s.family.clone(),
        faces: job.faces,
        method: s.method.clone(),
        label: s.label.clone(),
        params: s.params_string(),
        sweep: s.sweep.clone(),
        seed: s.seed,
        points: job.evaluation.points as u64,
        floor_l1: job.floor.l1,
        floor_l2: job.floor.l2,
        reference: format!("{:?}", job.reference_kind).to_lowercase(),
        l1: f64::NAN,
        l2: f64::NAN,
        max: f64::NAN,
        ..Default::default()
    }
}

/// Writes a run's result JSON (atomically).
pub fn write_result(dir: &Path, r: &RunResult) -> Result<()> {
    write_bytes(&result_path(dir, &r.id), |w| {
        Ok(serde_json::to_writer_pretty(w, r)?)
    })
}

/// Reads a run's result JSON.
pub fn read_result(path: &Path) -> Result<RunResult> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{}: cannot read", path.display()))?;
    serde_json::from_str(&text).with_context(|| format!("{}: malformed run result", path.display()))
}

/// Errors of the solver's solution at the points, with what answering took (wall time, rays, kernel
/// evaluations) and the memory held after it: answering is part of a method's cost (a final gather casts rays
/// at every query), charged once per evaluation.
fn evaluate(
    solver: &dyn Solver,
    accel: &Accel,
    points: &[EvalPoint],
    reference: &[Rgb],
    weights: &[f64],
) -> (Errors, Answering, Vec<Rgb>) {
    use rayon::prelude::*;
    let solution = solver.solution();
    let kernels0 = solution.answer_kernel_evaluations();
    let (t0, rays0) = (Instant::now(), accel.rays_cast());
    let values: Vec<Rgb> = points
        .par_iter()
        .map(|p| solution.radiosity_at(p.face, p.point))
        .collect();
    let answering = Answering {
        secs: t0.elapsed().as_secs_f64(),
        rays: accel.rays_cast().saturating_sub(rays0),
        kernels: solution
            .answer_kernel_evaluations()
            .saturating_sub(kernels0),
        bytes: solver.stats().bytes,
    };
    (
        metrics::errors(&values, reference, weights),
        answering,
        values,
    )
}

/// The cost of one answering pass at the evaluation points, and the memory the solver holds after it (what
/// answering built included: Gouraud vertices, a final gather's sources and near values).
#[derive(Clone, Copy, Debug, Default)]
struct Answering {
    secs: f64,
    rays: u64,
    kernels: u64,
    bytes: u64,
}

/// The solving time at which the next evaluation is due, after one at `wall` seconds of solving whose answering
/// took `answer_s`: once that time has grown by `growth` and, for `growth` > 1, by at least the answering time,
/// so that evaluating (a final gather at every point can take longer than the steps) takes no more of a run's
/// time than solving does. `growth` = 1 evaluates at every eligible step.
fn next_evaluation(wall: f64, growth: f64, answer_s: f64) -> f64 {
    if growth > 1.0 {
        (wall * growth).max(wall + answer_s)
    } else {
        wall
    }
}

/// Writes a run's final answers at the evaluation points beside the reference (`runs/<id>.points.csv`).
fn write_points(
    path: &Path,
    points: &[EvalPoint],
    reference: &[Rgb],
    std_error: &[Rgb],
    values: &[Rgb],
    weights: &[f64],
) -> Result<()> {
    let floor = metrics::max_error_floor(reference, weights);
    write_bytes(path, |w| {
        let mut out = csv::Writer::from_writer(w);
        for (i, (((p, r), s), v)) in points
            .iter()
            .zip(reference)
            .zip(std_error)
            .zip(values)
            .enumerate()
        {
            let d = (*v - *r).abs();
            let rel_error = (0..3)
                .map(|c| d[c] / r[c].abs().max(floor))
                .fold(0.0, f64::max);
            let z_score = (0..3)
                .map(|c| if d[c] == 0.0 { 0.0 } else { d[c] / s[c] })
                .fold(0.0, f64::max);
            out.serialize(PointRow {
                point: i,
                face: p.face,
                x: p.point.x,
                y: p.point.y,
                z: p.point.z,
                ref_r: r.x,
                ref_g: r.y,
                ref_b: r.z,
                se_r: s.x,
                se_g: s.y,
                se_b: s.z,
                r: v.x,
                g: v.y,
                b: v.z,
                rel_error,
                z_score,
            })?;
        }
        out.flush()?;
        Ok(())
    })
}

/// Runs a job in this process and writes its files. Failures of the method become the run's outcome.
pub fn execute(job: &Job) -> Result<RunResult> {
    let mut result = base_result(job);
    match execute_inner(job, &mut result) {
        Ok(()) => {}
        Err(e) => {
            result.outcome = "error".into();
            result.message = format!("{e:#}");
        }
    }
    result.peak_rss_bytes = solve_loop::peak_rss_bytes().unwrap_or(0);
    write_result(&job.dir, &result)?;
    let _ = std::fs::remove_file(partial_path(&job.dir, &result.id));
    Ok(result)
}

fn execute_inner(job: &Job, result: &mut RunResult) -> Result<()> {
    let spec = &job.spec;
    let scene = crate::scene_spec::load(&spec.scene)?;
    let accel = Accel::new(&scene);
    let points =
        radlab_method::evaluation_points(&scene, job.evaluation.points, job.evaluation.seed);
    let (reference, std_error) = reference::read_cache(&job.reference_file, points.len())?;
    let weights: Vec<f64> = points.iter().map(|p| p.weight).collect();
    let method = crate::methods::find(&spec.method)?;
    let setup = std::time::Instant::now();
    let mut solver = (method.build)(&scene, &accel, spec.params.clone(), spec.seed, &points)?;
    result.setup_s = setup.elapsed().as_secs_f64();
    let setup_s = result.setup_s;
    let limits = Limits {
        max_steps: job.limits.max_steps,
        time_limit: Duration::from_secs_f64(job.limits.time_limit),
    };
    let mut trace = Vec::new();
    let mut last_eval = Errors {
        l1: f64::NAN,
        l2: f64::NAN,
        max: f64::NAN,
    };
    let target = job.limits.target_error;
    let every = job.evaluation.every;
    let growth = job.evaluation.growth;
    let mut next_eval = 0.0;
    let mut last_answer = Answering::default();
    let mut last_values = Vec::new();
    // The after-step hook evaluates outside the solver's timed region, timing the answering separately;
    // reaching the target error ends the run.
    // In a child process every evaluation is also written as the run's partial result, with its trace and
    // points so far: a child killed for time (limits.kill_after) in a later step keeps what it measured.
    let mut partial = result.clone();
    let id = result.id.clone();
    let files = RunFiles {
        dir: &job.dir,
        id: &id,
        points: &points,
        reference: &reference,
        std_error: &std_error,
        weights: &weights,
    };
    let run = solve_loop::run(&mut *solver, limits, |s, rec| {
        let wall = rec.wall.as_secs_f64();
        if (rec.step % every == 0 && wall >= next_eval) || rec.step == 1 {
            let (e, answering, values) = evaluate(s, &accel, &points, &reference, &weights);
            last_eval = e;
            last_answer = answering;
            last_values = values;
            trace.push(row(spec, rec, setup_s, last_eval, last_answer));
            next_eval = next_evaluation(wall, growth, last_answer.secs);
            if job.limits.isolate {
                record(&mut partial, rec, last_eval, last_answer, s);
                partial.peak_rss_bytes = solve_loop::peak_rss_bytes().unwrap_or(0);
                files.write(&trace, &last_values)?;
                write_bytes(&partial_path(files.dir, files.id), |w| {
                    Ok(serde_json::to_writer_pretty(w, &partial)?)
                })?;
            }
            if target > 0.0 && last_eval.l1 <= target {
                anyhow::bail!(TargetReached);
            }
        }
        Ok(())
    });
    let (outcome, rec) = match run {
        Ok((o, rec)) => (o.as_str().to_string(), rec),
        Err(e) if e.is::<TargetReached>() => {
            let rec = solve_loop::StepRecord {
                step: trace.last().map_or(0, |t: &TraceRow| t.step),
                wall: Duration::from_secs_f64(trace.last().map_or(0.0, |t| t.wall_s)),
                cpu: Duration::from_secs_f64(trace.last().map_or(0.0, |t| t.cpu_s)),
                stats: solver.stats(),
            };
            ("target-error".to_string(), rec)
        }
        Err(e) => return Err(e),
    };
    if trace.last().is_none_or(|t| t.step != rec.step) {
        let (e, answering, values) = evaluate(&*solver, &accel, &points, &reference, &weights);
        last_eval = e;
        last_answer = answering;
        last_values = values;
        trace.push(row(spec, &rec, setup_s, last_eval, last_answer));
    }
    record(result, &rec, last_eval, last_answer, &*solver);
    result.outcome = outcome;
    files.write(&trace, &last_values)?;
    if job.outputs.images
        && let Some(camera) = super::images::camera_for(&scene, &job.outputs)
    {
        let t0 = Instant::now();
        let image = if spec.method == crate::pathtraced::NAME {
            // Path tracing's image costs paths per pixel: render it at the paths per point the run reached
            // (capped by outputs.pathtrace_image_spp).
            let params = radlab_pathtrace::PathTraceParams::from_table(spec.params.clone())?;
            let reached = (0..rec.step.saturating_sub(1))
                .fold(params.initial_samples.min(params.samples), |n, _| {
                    (2 * n).min(params.samples)
                });
            let render = radlab_pathtrace::RenderParams {
                samples_per_pixel: reached.min(job.outputs.pathtrace_image_spp).max(1),
                max_depth: params.max_depth,
                direct: params.direct,
            };
            radlab_pathtrace::render(&scene, &accel, &camera, &render, spec.seed, &|_, _| {}).0
        } else {
            radlab_answer::render_solution(
                &scene,
                &accel,
                &camera,
                solver.solution(),
                job.outputs.image_spp,
                spec.seed,
                &|_, _| {},
            )
        };
        result.image_s = t0.elapsed().as_secs_f64();
        write_exr(&image_path(&job.dir, &result.id), &image)?;
    }
    Ok(())
}

/// Fills a run's result from its last step and evaluation. Memory is read once the solution has answered,
/// so it holds what answering built, as its time and rays do.
fn record(
    result: &mut RunResult,
    rec: &solve_loop::StepRecord,
    e: Errors,
    answer: Answering,
    solver: &dyn Solver,
) {
    (
        result.answer_s,
        result.answer_rays,
        result.answer_form_factors,
        result.bytes,
    ) = (answer.secs, answer.rays, answer.kernels, answer.bytes);
    result.steps = rec.step;
    result.wall_s = rec.wall.as_secs_f64();
    result.cpu_s = rec.cpu.as_secs_f64();
    let st = rec.stats;
    (
        result.elements,
        result.links,
        result.form_factors,
        result.rays,
    ) = (st.elements, st.links, st.form_factors, st.rays);
    result.counters = solver
        .counters()
        .iter()
        .map(|(name, value)| format!("{name}={value}"))
        .collect::<Vec<_>>()
        .join(";");
    (result.l1, result.l2, result.max) = (e.l1, e.l2, e.max);
}

/// A run's trace and per-point files, and the fixed inputs of the second: its evaluation points, the reference
/// with its standard error and the points' weights.
struct RunFiles<'a> {
    dir: &'a Path,
    id: &'a str,
    points: &'a [EvalPoint],
    reference: &'a [Rgb],
    std_error: &'a [Rgb],
    weights: &'a [f64],
}

impl RunFiles<'_> {
    /// Writes the trace so far and the answers `values` at the points beside the reference (each atomically).
    fn write(&self, trace: &[TraceRow], values: &[Rgb]) -> Result<()> {
        write_csv_rows(&trace_path(self.dir, self.id), trace)?;
        write_points(
            &points_path(self.dir, self.id),
            self.points,
            self.reference,
            self.std_error,
            values,
            self.weights,
        )
    }
}

#[derive(Debug)]
struct TargetReached;
impl std::fmt::Display for TargetReached {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("target error reached")
    }
}
impl std::error::Error for TargetReached {}

/// A trace row: the step's record, with its answering pass (and the bytes held after it).
fn row(
    spec: &RunSpec,
    rec: &solve_loop::StepRecord,
    setup_s: f64,
    e: Errors,
    answer: Answering,
) -> TraceRow {
    let st = rec.stats;
    TraceRow {
        id: spec.id(),
        scene: spec.scene_label.clone(),
        label: spec.label.clone(),
        sweep: spec.sweep.clone(),
        seed: spec.seed,
        step: rec.step,
        setup_s,
        wall_s: rec.wall.as_secs_f64(),
        cpu_s: rec.cpu.as_secs_f64(),
        answer_s: answer.secs,
        answer_rays: answer.rays,
        answer_form_factors: answer.kernels,
        elements: st.elements,
        links: st.links,
        form_factors: st.form_factors,
        rays: st.rays,
        bytes: answer.bytes,
        residual: st.residual,
        l1: e.l1,
        l2: e.l2,
        max: e.max,
    }
}

/// Entry point of the child process: reads the job, watches memory, executes.
pub fn run_child(job_file: &Path) -> Result<()> {
    let text = std::fs::read_to_string(job_file)
        .with_context(|| format!("{}: cannot read job", job_file.display()))?;
    let job: Job = serde_json::from_str(&text)
        .with_context(|| format!("{}: malformed job", job_file.display()))?;
    if job.limits.memory_limit_mib > 0 {
        let limit = job.limits.memory_limit_mib * 1024 * 1024;
        let job2 = job.clone();
        std::thread::spawn(move || {
            loop {
                if current_rss_bytes().is_some_and(|rss| rss > limit) {
                    let mut r = base_result(&job2);
                    r.outcome = "out-of-memory".into();
                    r.message = format!(
                        "resident memory exceeded the limit of {} MiB",
                        job2.limits.memory_limit_mib
                    );
                    r.peak_rss_bytes = solve_loop::peak_rss_bytes().unwrap_or(0);
                    let _ = write_result(&job2.dir, &r);
                    std::process::exit(3);
                }
                std::thread::sleep(Duration::from_millis(20));
            }
        });
    }
    // Fault injection, for the tests of run isolation: RADLAB_FAULT=panic makes a child run panic.
    if std::env::var_os("RADLAB_FAULT").is_some_and(|v| v == "panic") {
        panic!("injected fault (RADLAB_FAULT=panic)");
    }
    execute(&job).map(|_| ())
}

/// Current resident set size (Linux `VmRSS`), bytes.
pub fn current_rss_bytes() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmRSS:"))?;
    Some(line.split_whitespace().nth(1)?.parse::<u64>().ok()? * 1024)
}

/// Runs a job in a child process, killing it after the kill timeout; records crashes and timeouts.
pub fn execute_isolated(job: &Job, threads: Option<usize>) -> Result<RunResult> {
    let id = job.spec.id();
    let job_file = job.dir.join("runs").join(format!("{id}.job.json"));
    write_bytes(&job_file, |w| Ok(serde_json::to_writer(w, job)?))?;
    let result_file = result_path(&job.dir, &id);
    let partial_file = partial_path(&job.dir, &id);
    for stale in [
        &result_file,
        &partial_file,
        &trace_path(&job.dir, &id),
        &points_path(&job.dir, &id),
    ] {
        let _ = std::fs::remove_file(stale);
    }
    let exe = std::env::current_exe()
        .context("cannot find the radlab executable to run a child process")?;
    let mut cmd = Command::new(exe);
    if let Some(n) = threads {
        cmd.arg("--threads").arg(n.to_string());
    }
    cmd.arg("run-one")
        .arg(&job_file)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    let mut child = cmd.spawn().context("cannot start a child radlab process")?;
    let mut stderr = child.stderr.take();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        if let Some(e) = stderr.as_mut() {
            let _ = e.read_to_string(&mut s);
        }
        s
    });
    let deadline = Instant::now() + Duration::from_secs_f64(job.limits.kill_after_secs());
    let status = loop {
        if let Some(st) = child.try_wait()? {
            break Some(st);
        }
        if Instant::now() >= deadline {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let err_text = reader.join().unwrap_or_default();
    let _ = std::fs::remove_file(&job_file);
    let written = read_result(&result_file);
    let partial = read_result(&partial_file).ok();
    let _ = std::fs::remove_file(&partial_file);
    if let (Some(st), Ok(r)) = (status, &written)
        && (st.success() || r.outcome == "out-of-memory")
    {
        return Ok(r.clone());
    }
    // A child that was killed or crashed after an evaluation keeps it (its trace and points are on disk).
    let mut r = partial.clone().unwrap_or_else(|| base_result(job));
    let kept = partial.map_or(String::new(), |p| {
        format!(
            "; the figures are those of step {} ({:.1} s of steps), its last evaluation",
            p.steps, p.wall_s
        )
    });
    // The panic message if there is one (the line after "panicked at"), otherwise the last lines of stderr.
    let lines: Vec<&str> = err_text.lines().collect();
    let tail = match lines.iter().position(|l| l.contains("panicked at")) {
        Some(i) => lines[i..(i + 2).min(lines.len())].join(" "),
        None => lines[lines.len().saturating_sub(3)..].join(" | "),
    };
    match status {
        None => {
            r.outcome = "timeout".into();
            r.message = format!(
                "killed after {:.0} s (limits.kill_after){kept}",
                job.limits.kill_after_secs()
            );
        }
        Some(st) => {
            r.outcome = "crash".into();
            r.message = match (st.success(), written) {
                (true, Err(e)) => {
                    format!("child exited with {st} but left no readable result: {e:#}")
                }
                _ => format!("child exited with {st}: {tail}{kept}"),
            };
        }
    }
    write_result(&job.dir, &r)?;
    Ok(r)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn evaluations_wait_for_as_much_solving_as_their_answering_took() {
        // Cheap answers: the solving time's growth alone decides.
        assert_eq!(next_evaluation(8.0, 1.25, 0.5), 10.0);
        // Costly answers (a 75 s pass after 8 s of steps): the next evaluation waits for 75 s more of solving.
        assert_eq!(next_evaluation(8.0, 1.25, 75.0), 83.0);
        // Growth 1 evaluates at every eligible step, however costly.
        assert_eq!(next_evaluation(8.0, 1.0, 75.0), 8.0);
    }

    #[test]
    fn jobs_reach_the_child_bit_for_bit() {
        // A log-range sweep value whose shortest decimal form needs a correctly rounded parser: the child must
        // run with exactly the parent's parameters (and so compute the same run id).
        let mut params = toml::Table::new();
        params.insert("epsilon".into(), toml::Value::Float(0.009999999999999995));
        params.insert(
            "alpha".into(),
            toml::Value::Float(f64::from_bits(0x3FB9_9999_9999_999A)),
        );
        let spec = RunSpec {
            index: 13,
            scene: "builtin:cornell".into(),
            scene_label: "cornell".into(),
            family: String::new(),
            method: "hierarchical".into(),
            label: "hierarchical".into(),
            params,
            sweep: String::new(),
            seed: 1,
        };
        let text = serde_json::to_string(&spec).expect("serialise");
        let back: RunSpec = serde_json::from_str(&text).expect("parse");
        assert_eq!(back, spec);
        assert_eq!(back.id(), spec.id());
    }
}

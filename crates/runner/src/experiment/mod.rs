//! `radlab run`, `radlab merge` and `radlab plot`: experiments from TOML configs
//! (documented key by key in experiments/README.md).
//!
//! `run` expands the config into runs, computes (or reads from `results/references/`) each scene's reference at
//! its evaluation points, executes every run not already complete with the same digest (each in a child
//! process unless `limits.isolate = false`), then rebuilds the tables, plots, images and report from the
//! per-run files. `--shard I/N` executes runs whose index ≡ I (mod N), I from 0; shards writing to different
//! directories are combined with `merge`.

pub mod config;
pub mod digest;
pub mod execute;
pub mod images;
pub use radlab_method::error_metric as metrics;
pub mod plots;
pub mod reference;
pub mod report;
pub mod tables;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::SystemTime;

use anyhow::{Context, Result, bail};
use radlab_visibility::Accel;

use crate::output::atomic::write_bytes;
use crate::output::exr_image::{read_exr, write_exr};
use crate::progress;
use config::{ExperimentConfig, RunSpec};
use execute::Job;

/// The default experiment.
pub const QUICKSTART: &str = "experiments/quickstart.toml";

/// Options of `radlab run`.
#[derive(Clone, Debug, clap::Args)]
pub struct RunArgs {
    /// The experiment config (default experiments/quickstart.toml).
    pub experiment: Option<PathBuf>,
    /// Output directory (default `results/<experiment name>`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Run only shard I of N (I from 0): runs whose index is I modulo N.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<String>,
    /// Redo runs already complete with the same config digest.
    #[arg(long)]
    pub force: bool,
}

/// Parses `I/N`.
pub fn parse_shard(s: &str) -> Result<(usize, usize)> {
    let err = || anyhow::anyhow!("--shard '{s}': expected I/N with 0 <= I < N, e.g. --shard 0/4");
    let (i, n) = s.split_once('/').ok_or_else(err)?;
    let (i, n): (usize, usize) = (
        i.trim().parse().map_err(|_| err())?,
        n.trim().parse().map_err(|_| err())?,
    );
    if n == 0 || i >= n {
        return Err(err());
    }
    Ok((i, n))
}

/// The runs of shard (i, n).
pub fn shard(runs: Vec<RunSpec>, (i, n): (usize, usize)) -> Vec<RunSpec> {
    runs.into_iter().filter(|r| r.index % n == i).collect()
}

fn references_dir(out: &Path) -> PathBuf {
    out.parent()
        .map_or_else(|| PathBuf::from("references"), |p| p.join("references"))
}

/// Digest of everything that determines a run's result, the scene's content (`scene_digest`) included: a
/// builtin or a mesh file that changes under the same name is run again.
pub fn job_digest(
    cfg: &ExperimentConfig,
    spec: &RunSpec,
    reference_kind: config::ReferenceKind,
    scene_digest: &str,
) -> String {
    let key = serde_json::json!({
        "spec": spec,
        "scene": scene_digest,
        "evaluation": cfg.evaluation,
        "reference": cfg.reference,
        "reference_kind": reference_kind,
        "limits": cfg.limits,
        "outputs": cfg.outputs,
        "version": env!("CARGO_PKG_VERSION"),
    });
    digest::hex(key.to_string().as_bytes())
}

/// Runs `radlab run`.
pub fn run(args: &RunArgs, threads: Option<usize>) -> Result<()> {
    let started = SystemTime::now();
    let path = args
        .experiment
        .clone()
        .unwrap_or_else(|| PathBuf::from(QUICKSTART));
    let cfg = ExperimentConfig::load(&path)?;
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("results").join(&cfg.name));
    let mut runs = cfg.runs()?;
    if let Some(s) = &args.shard {
        runs = shard(runs, parse_shard(s)?);
    }
    std::fs::create_dir_all(out.join("runs"))
        .with_context(|| format!("cannot create {}", out.display()))?;
    let config_text = toml::to_string(&cfg)?;
    write_bytes(&out.join("config.toml"), |w| {
        Ok(w.write_all(config_text.as_bytes())?)
    })?;
    let refs_dir = references_dir(&out);

    // References, once per scene.
    let mut jobs = Vec::new();
    for entry in &cfg.scenes {
        let label = entry.label();
        let mine: Vec<&RunSpec> = runs.iter().filter(|r| r.scene_label == label).collect();
        if mine.is_empty() {
            continue;
        }
        let scene = crate::scene_spec::load_and_warn(&entry.scene)
            .with_context(|| format!("scene '{label}'"))?;
        let scene_digest = digest::scene(&scene);
        let accel = Accel::new(&scene);
        let points =
            radlab_method::evaluation_points(&scene, cfg.evaluation.points, cfg.evaluation.seed);
        if points.is_empty() {
            bail!("scene '{label}' has no non-emitting surface to evaluate");
        }
        let kind = entry.reference.unwrap_or(cfg.reference.kind);
        let bar = progress::bar(points.len() as u64, &format!("reference {label}"));
        let r = reference::reference(
            &scene,
            &scene_digest,
            &accel,
            &points,
            &entry.reference_config(&cfg.reference),
            kind,
            &refs_dir,
            &|d, _| bar.set_position(d as u64),
        )?;
        bar.finish_and_clear();
        let weights: Vec<f64> = points.iter().map(|p| p.weight).collect();
        let floor = metrics::noise_floor(&r.values, &r.std_error, &weights);
        if r.seconds > 0.0 {
            eprintln!(
                "reference for {label}: {:?}, {:.1} s, noise floor L1 {:.2e}",
                r.kind, r.seconds, floor.l1
            );
        }
        if cfg.outputs.images
            && let Some(camera) = images::camera_for(&scene, &cfg.outputs)
        {
            let target = out.join("images").join(format!("reference-{label}.exr"));
            let cached = refs_dir.join(format!(
                "{}-image-{}.exr",
                label,
                &digest::hex(
                    format!(
                        "{}|{:?}|{}|{}",
                        scene_digest, camera, cfg.reference.image_spp, cfg.reference.seed
                    )
                    .as_bytes()
                )[..16]
            ));
            if !cached.exists() {
                let params = radlab_pathtrace::RenderParams {
                    samples_per_pixel: cfg.reference.image_spp,
                    ..Default::default()
                };
                let bar = progress::bar(
                    (camera.width * camera.height) as u64,
                    &format!("reference image {label}"),
                );
                let (img, _) = radlab_pathtrace::render(
                    &scene,
                    &accel,
                    &camera,
                    &params,
                    cfg.reference.seed,
                    &|d, _| bar.set_position(d as u64),
                );
                bar.finish_and_clear();
                write_exr(&cached, &img)?;
            }
            crate::output::atomic::write_via_temp(&target, |tmp| {
                std::fs::copy(&cached, tmp)
                    .map(|_| ())
                    .with_context(|| format!("cannot copy {}", cached.display()))
            })?;
        }
        for spec in mine {
            jobs.push(Job {
                spec: spec.clone(),
                digest: job_digest(&cfg, spec, r.kind, &scene_digest),
                dir: out.clone(),
                faces: scene.faces.len() as u64,
                reference_file: r.file.clone(),
                reference_kind: r.kind,
                floor,
                evaluation: cfg.evaluation.clone(),
                limits: cfg.limits.clone(),
                outputs: cfg.outputs.clone(),
            });
        }
    }

    // Runs.
    let bar = progress::bar(jobs.len() as u64, &cfg.name);
    let (mut done, mut skipped) = (0, 0);
    for job in &jobs {
        let id = job.spec.id();
        bar.set_message(id.clone());
        let existing = execute::read_result(&execute::result_path(&out, &id)).ok();
        if !args.force && existing.is_some_and(|r| r.digest == job.digest) {
            skipped += 1;
        } else {
            let r = if cfg.limits.isolate {
                execute::execute_isolated(job, threads)?
            } else {
                execute::execute(job)?
            };
            bar.suspend(|| {
                eprintln!(
                    "{:<48} {:<13} {:>9.3} s  L1 {:.3e}{}",
                    id,
                    r.outcome,
                    r.wall_s,
                    r.l1,
                    if r.message.is_empty() {
                        String::new()
                    } else {
                        format!("  ({})", r.message)
                    }
                )
            });
            done += 1;
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    finish(&out, &cfg)?;
    let meta = serde_json::json!({
        "experiment": cfg,
        "config_file": path,
        "shard": args.shard,
        "runs_executed": done,
        "runs_skipped": skipped,
        "started": humantime::format_rfc3339_seconds(started).to_string(),
        "finished": humantime::format_rfc3339_seconds(SystemTime::now()).to_string(),
        "environment": report::environment(),
    });
    write_bytes(&out.join("meta.json"), |w| {
        Ok(serde_json::to_writer_pretty(w, &meta)?)
    })?;
    println!(
        "{} runs executed, {skipped} skipped (already complete); results in {}",
        done,
        out.display()
    );
    println!("{}", out.join("report.md").display());
    Ok(())
}

/// Rebuilds tables, figures, difference images, contact sheets and the report from the per-run files of
/// `cfg`'s runs (all shards'). Files in `runs/` that no run of `cfg` writes (left by an earlier configuration
/// written to the same directory) are left in place but kept out of the tables, and counted on stderr.
pub fn finish(out: &Path, cfg: &ExperimentConfig) -> Result<()> {
    let ids: std::collections::HashSet<String> = cfg.runs()?.iter().map(RunSpec::id).collect();
    let (results, stale): (Vec<_>, Vec<_>) = tables::collect_results(out)?
        .into_iter()
        .partition(|r| ids.contains(&r.id));
    if !stale.is_empty() {
        eprintln!(
            "{}: {} run files in runs/ belong to no run of this experiment (an earlier configuration?); \
             left out of the tables and report",
            out.display(),
            stale.len()
        );
    }
    tables::write_tables(out, &results)?;
    redraw(out, &cfg.name, &cfg.description, cfg.outputs.plots)
}

/// Figures, images and report from `runs.csv`, `trace.csv` and the images directory.
pub fn redraw(out: &Path, name: &str, description: &str, plots_on: bool) -> Result<()> {
    let runs = tables::read_runs(&out.join("runs.csv"))?;
    let trace = tables::read_trace(&out.join("trace.csv"))?;
    let mut figures: BTreeMap<String, Vec<String>> = BTreeMap::new();
    let mut image_errors: BTreeMap<(String, String), f64> = BTreeMap::new();
    let mut scenes: Vec<String> = Vec::new();
    for r in &runs {
        if !scenes.contains(&r.scene) {
            scenes.push(r.scene.clone());
        }
    }
    for scene in &scenes {
        let figs = figures.entry(scene.clone()).or_default();
        if plots_on {
            for p in plots::scene_plots(out, scene, &runs, &trace)? {
                figs.push(relative(out, &p));
            }
        }
        // Images: the reference, and per method label its most accurate run.
        let ref_path = out.join("images").join(format!("reference-{scene}.exr"));
        if !ref_path.exists() {
            continue;
        }
        let reference = read_exr(&ref_path)?;
        let scale = images::exposure(&reference);
        let mut tiles = vec![(
            "reference".to_string(),
            "path traced".to_string(),
            reference.clone(),
        )];
        let mut labels: Vec<&str> = Vec::new();
        for r in runs.iter().filter(|r| &r.scene == scene) {
            if !labels.contains(&r.label.as_str()) {
                labels.push(&r.label);
            }
        }
        for label in labels {
            let best = runs
                .iter()
                .filter(|r| &r.scene == scene && r.label == label && r.l1.is_finite())
                .filter(|r| execute::image_path(out, &r.id).exists())
                .min_by(|a, b| a.l1.total_cmp(&b.l1));
            let Some(best) = best else { continue };
            let img = read_exr(&execute::image_path(out, &best.id))?;
            let diff = out.join("images").join(format!(
                "difference-{scene}-{}.png",
                config::label_from_spec(label)
            ));
            if let Ok(mean) = images::difference_png(&diff, &img, &reference) {
                image_errors.insert((scene.clone(), label.to_string()), mean);
                figs.push(relative(out, &diff));
                tiles.push((
                    label.to_string(),
                    format!(
                        "L1 {:.1e}, {}, img {:.0}%",
                        best.l1,
                        short_seconds(best.setup_s + best.wall_s + best.answer_s),
                        mean * 100.0
                    ),
                    img,
                ));
            }
        }
        let sheet = out
            .join("images")
            .join(format!("contact-sheet-{scene}.png"));
        images::contact_sheet(&sheet, &tiles, scale)?;
        figs.push(relative(out, &sheet));
    }
    if plots_on {
        let scaling = plots::scaling_plots(out, &runs)?;
        figures
            .entry(String::new())
            .or_default()
            .extend(scaling.iter().map(|p| relative(out, p)));
    }
    report::write_report(
        out,
        &report::markdown(name, description, &runs, &trace, &figures, &image_errors),
    )
}

fn relative(base: &Path, p: &Path) -> String {
    p.strip_prefix(base)
        .unwrap_or(p)
        .to_string_lossy()
        .into_owned()
}

/// Runs `radlab plot DIR`.
pub fn plot(dir: &Path) -> Result<()> {
    let cfg_path = dir.join("config.toml");
    let (name, description, plots_on) = match std::fs::read_to_string(&cfg_path)
        .ok()
        .and_then(|t| toml::from_str::<ExperimentConfig>(&t).ok())
    {
        Some(c) => (c.name, c.description, true),
        None => (
            dir.file_name()
                .map_or("experiment".into(), |n| n.to_string_lossy().into_owned()),
            String::new(),
            true,
        ),
    };
    if !dir.join("runs.csv").exists() {
        bail!(
            "{}: no runs.csv here; give the directory of an experiment's results",
            dir.display()
        );
    }
    redraw(dir, &name, &description, plots_on)?;
    println!("redrew figures and report in {}", dir.display());
    Ok(())
}

/// Runs `radlab merge OUT DIR...`: copies the per-run files and images of shard directories into OUT and
/// rebuilds its tables and report.
pub fn merge(out: &Path, dirs: &[PathBuf]) -> Result<()> {
    if dirs.is_empty() {
        bail!("merge: give the shard directories to merge");
    }
    let mut cfg: Option<ExperimentConfig> = None;
    for d in dirs {
        let text = std::fs::read_to_string(d.join("config.toml")).with_context(|| {
            format!(
                "{}: not an experiment result directory (no config.toml)",
                d.display()
            )
        })?;
        let c: ExperimentConfig =
            toml::from_str(&text).with_context(|| format!("{}/config.toml", d.display()))?;
        if let Some(prev) = &cfg
            && prev.name != c.name
        {
            bail!(
                "{}: experiment '{}' differs from '{}'",
                d.display(),
                c.name,
                prev.name
            );
        }
        for sub in ["runs", "images"] {
            let src = d.join(sub);
            if !src.exists() {
                continue;
            }
            std::fs::create_dir_all(out.join(sub))?;
            for e in std::fs::read_dir(&src)? {
                let p = e?.path();
                if let Some(n) = p.file_name()
                    && !n.to_string_lossy().starts_with('.')
                {
                    std::fs::copy(&p, out.join(sub).join(n))
                        .with_context(|| format!("cannot copy {}", p.display()))?;
                }
            }
        }
        cfg = Some(c);
    }
    let cfg = cfg.context("nothing to merge")?;
    let text = toml::to_string(&cfg)?;
    write_bytes(&out.join("config.toml"), |w| {
        Ok(w.write_all(text.as_bytes())?)
    })?;
    finish(out, &cfg)?;
    println!("merged {} directories into {}", dirs.len(), out.display());
    Ok(())
}

/// Seconds for an image's label: two decimals below 10 s ("0.77 s"), whole seconds above ("12 s", "340 s").
fn short_seconds(s: f64) -> String {
    if s < 10.0 {
        format!("{s:.2} s")
    } else {
        format!("{s:.0} s")
    }
}

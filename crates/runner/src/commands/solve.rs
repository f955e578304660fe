//! `radlab solve SCENE --method M [--set k=v ...] [--out DIR]`: one solve to the method's own stopping rule;
//! writes `faces.csv` (per-face mean radiosity), `radiosity.ply` (mesh with per-vertex radiosity) and, when the
//! scene has a camera, `image.exr` (radiance B/π through the camera), and prints a summary.

use std::path::PathBuf;
use std::time::Duration;

use anyhow::Result;
use radlab_method::{EvalPoint, Solution, Solver, params};
use radlab_scene::Scene;
use radlab_visibility::Accel;

use crate::output::{exr_image, faces_csv, ply_radiosity};
use crate::solve_loop::{self, Limits, Outcome, StepRecord};
use crate::{methods, progress, scene_spec};

/// Options shared by solve, probe and render.
#[derive(Clone, Debug, clap::Args)]
pub struct MethodArgs {
    /// The scene: a file (.toml, .obj, .ply, .off, .mgf) or builtin:NAME[?k=v&...] (see `radlab scenes`).
    pub scene: String,
    /// The method (see `radlab methods`).
    #[arg(long, short)]
    pub method: String,
    /// A method parameter, key=value (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Seed of every random choice.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Most solver steps before stopping.
    #[arg(long, default_value_t = 1_000_000)]
    pub max_steps: u64,
    /// Most seconds spent in solver steps before stopping.
    #[arg(long, default_value_t = 86_400.0)]
    pub time_limit: f64,
}

impl MethodArgs {
    /// The `--set` pairs as a TOML table.
    pub fn table(&self) -> Result<toml::Table> {
        let pairs: Result<Vec<_>, _> = self.set.iter().map(|s| params::split_pair(s)).collect();
        Ok(params::pairs_to_table(&pairs?)?)
    }

    /// The limits.
    pub fn limits(&self) -> Result<Limits> {
        if !(self.time_limit > 0.0 && self.time_limit.is_finite()) {
            anyhow::bail!("--time-limit must be a positive number of seconds");
        }
        Ok(Limits {
            max_steps: self.max_steps.max(1),
            time_limit: Duration::from_secs_f64(self.time_limit),
        })
    }
}

/// A scene loaded with its accelerator.
pub struct Loaded {
    /// The scene.
    pub scene: Scene,
    /// Its BVH.
    pub accel: Accel,
}

/// Loads the scene, reports its warnings on stderr, and builds the BVH.
pub fn load(spec: &str) -> Result<Loaded> {
    let scene = scene_spec::load_and_warn(spec)?;
    let accel = Accel::new(&scene);
    Ok(Loaded { scene, accel })
}

/// A finished solve: the solver after its last step, why it stopped, and the last step's record.
pub struct Solved<'a>(pub Box<dyn Solver + 'a>, pub Outcome, pub StepRecord);

impl Solved<'_> {
    /// The solution.
    pub fn solution(&self) -> &dyn Solution {
        self.0.solution()
    }
}

/// Builds the method and runs it to its stopping rule, with a spinner on a terminal. `points` are the points
/// that will be asked about (path tracing traces there; other methods ignore them).
pub fn solve<'a>(
    loaded: &'a Loaded,
    args: &MethodArgs,
    points: &[EvalPoint],
) -> Result<Solved<'a>> {
    let table = args.table()?;
    let method = methods::find(&args.method)?;
    let mut solver = (method.build)(&loaded.scene, &loaded.accel, table, args.seed, points)?;
    let bar = progress::spinner(&format!("{} on {}", args.method, loaded.scene.name));
    let (outcome, last) = solve_loop::run(&mut *solver, args.limits()?, |_, rec| {
        bar.set_message(format!(
            "step {} | {:.1} s | {} elements | {} rays",
            rec.step,
            rec.wall.as_secs_f64(),
            rec.stats.elements,
            rec.stats.rays
        ));
        bar.tick();
        Ok(())
    })?;
    bar.finish_and_clear();
    Ok(Solved(solver, outcome, last))
}

/// The radiance B/π of `solution` through `camera` (`render_solution`), with a progress bar on a terminal.
pub fn render_image(
    loaded: &Loaded,
    camera: &radlab_scene::Camera,
    solution: &dyn radlab_method::Solution,
    spp: u32,
    seed: u64,
) -> radlab_answer::Image {
    let bar = progress::bar(u64::from(camera.width * camera.height), "image");
    let image = radlab_answer::render_solution(
        &loaded.scene,
        &loaded.accel,
        camera,
        solution,
        spp,
        seed,
        &|done, _| bar.set_position(done as u64),
    );
    bar.finish_and_clear();
    image
}

/// Options of `radlab solve`.
#[derive(Clone, Debug, clap::Args)]
pub struct SolveArgs {
    #[command(flatten)]
    /// Scene, method and parameters.
    pub common: MethodArgs,
    /// Output directory (default results/solve/SCENE-METHOD).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Jittered samples per pixel of the EXR image.
    #[arg(long, default_value_t = 4)]
    pub spp: u32,
}

/// Runs `radlab solve`.
pub fn run(args: &SolveArgs) -> Result<()> {
    let a = &args.common;
    let loaded = load(&a.scene)?;
    let scene = &loaded.scene;
    let out = args.out.clone().unwrap_or_else(|| {
        let stem: String = scene
            .name
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '-' {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        PathBuf::from("results/solve").join(format!("{stem}-{}", a.method))
    });
    let solved = solve(&loaded, a, &[])?;
    let solution = solved.solution();
    // Answering every face and every mesh corner is long work where answers are final gathers.
    let bar = progress::bar(0, "faces.csv");
    let means = faces_csv::face_means(scene, solution, &bar);
    bar.finish_and_clear();
    faces_csv::write_faces_csv(&out.join("faces.csv"), scene, &means)?;
    let piece = if scene.faces.len() < 100_000 {
        0.5 * radlab_answer::default_element_size(scene)
    } else {
        f64::INFINITY
    };
    let bar = progress::bar(0, "radiosity.ply");
    ply_radiosity::write_ply(&out.join("radiosity.ply"), scene, solution, piece, &bar)?;
    bar.finish_and_clear();
    let mut written = vec!["faces.csv", "radiosity.ply"];
    if let Some(camera) = &scene.camera {
        let image = render_image(&loaded, camera, solution, args.spp, a.seed);
        exr_image::write_exr(&out.join("image.exr"), &image)?;
        written.push("image.exr");
    }
    let Solved(s, outcome, rec) = &solved;
    let st = s.stats();
    println!(
        "{} on {}: {} after {} steps, {:.3} s wall, {:.3} s CPU; {} elements, {} links, {} form factors, {} rays, {:.1} MiB held",
        a.method,
        scene.name,
        outcome.as_str(),
        rec.step,
        rec.wall.as_secs_f64(),
        rec.cpu.as_secs_f64(),
        st.elements,
        st.links,
        st.form_factors,
        st.rays,
        st.bytes as f64 / 1048576.0
    );
    println!("wrote {} in {}", written.join(", "), out.display());
    Ok(())
}

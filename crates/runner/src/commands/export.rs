//! `radlab export SCENE --to radiance|mitsuba --out DIR`: the scene for another renderer, the evaluation points,
//! and a script that asks that renderer for the radiosity at the points, so a radlab figure can be checked
//! against a renderer nobody here wrote.
//!
//! Both renderers are asked for the irradiance H at each point (the point lifted by 10⁻⁵ of the scene's
//! diagonal along its normal, so it does not hit its own face); for a Lambertian surface the radiosity is then
//! B = E + ρ H (Kajiya 1986, the rendering equation at a diffuse surface). The point files carry each point's
//! face, normal, ρ and E; the scripts write `x,y,z,r,g,b,se_r,se_g,se_b` (the columns of `radlab probe`) with
//! the standard error over independent repeats, which `radlab compare` reads.
//!
//! - **Radiance** (Ward 1994, "The RADIANCE lighting simulation and rendering system"): `scene.rad` with one
//!   `plastic` of zero specularity and roughness per material (a Lambertian reflector of reflectance ρ) and one
//!   `light` of radiance E/π per emitting material; faces as `polygon`s (right-hand rule, as radlab's). A
//!   Radiance `plastic` reflects from both sides, radlab's faces from their front only (a back absorbs), so
//!   each plastic is wrapped in a `mixfunc` that shows it where the ray meets the front (`Rdot` > 0) and a black
//!   `plastic` elsewhere: without it the back of an open surface (a table top, a height field) reflects in
//!   Radiance and not in radlab or Mitsuba. A Radiance `light` emits from its front only, as radlab's, but
//!   does not reflect, so an emitter's own reflectance is dropped (radlab keeps it; the difference is
//!   ρ_light H_light on the emitter, seen by the rest of the scene). `radiance-points.py` runs `oconv` and
//!   `rtrace -I` with pure Monte Carlo ambient sampling (`-aa 0`).
//! - **Mitsuba 3** (Jakob et al. 2022): `scene.xml` with one binary PLY per material (`mat_K.ply`, triangles),
//!   a `diffuse` BSDF of reflectance ρ, an `area` emitter of radiance E/π where E > 0, the `path` integrator
//!   with unlimited depth and the scene's camera as a `perspective` sensor (Mitsuba's `diffuse` reflects from
//!   the front only and its `area` emitter emits from the front only, as radlab's faces). `mitsuba-points.py`
//!   estimates H at each point per sample as the direct light by Mitsuba's emitter sampling at the point plus
//!   π L along a cosine-weighted direction, L the radiance Mitsuba's own path integrator returns there less the
//!   emission of the surface it meets (`--direct hemisphere`: H = π · mean(L) with emitters seen, noisier).
//!
//! Every file is written to a staging directory beside DIR and moved into DIR only when all are complete, so
//! a failed export leaves no partial files.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use radlab_method::{EvalPoint, evaluation_points};
use radlab_scene::Scene;

use crate::output::atomic;
use crate::scene_spec;

/// Which renderer to export for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Renderer {
    /// Radiance 6: `scene.rad` + `radiance-points.py` (oconv, rtrace -I).
    Radiance,
    /// Mitsuba 3: `scene.xml` + PLY per material + `mitsuba-points.py`.
    Mitsuba,
}

/// Options of `radlab export`.
#[derive(Clone, Debug, clap::Args)]
pub struct ExportArgs {
    /// The scene: builtin:NAME[?k=v...] or a .toml, .obj, .ply, .off or .mgf file.
    pub scene: String,
    /// The renderer to export for.
    #[arg(long = "to", value_enum)]
    pub to: Renderer,
    /// Output directory (created; files already in it with the same names are replaced).
    #[arg(long)]
    pub out: PathBuf,
    /// Number of evaluation points (area-stratified over the non-emitting faces, as in experiments).
    #[arg(long, default_value_t = 256)]
    pub points: usize,
    /// Seed of the evaluation points.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

/// Relative lift of a point along its normal before the other renderer traces from it.
pub const LIFT_REL: f64 = 1e-5;

/// One file of an export: its name in DIR and its bytes.
pub type ExportFile = (String, Vec<u8>);

/// Runs `radlab export`.
pub fn run(args: &ExportArgs) -> Result<()> {
    if args.points == 0 {
        bail!("--points 0: give at least one evaluation point");
    }
    let scene = scene_spec::load_and_warn(&args.scene)?;
    let points = evaluation_points(&scene, args.points, args.seed);
    let files = export_files(&scene, &points, args.to)?;
    write_all(&args.out, &files)?;
    let dropped = scene
        .materials
        .iter()
        .filter(|m| m.is_emitter() && m.reflectance.max_element() > 0.0)
        .count();
    if args.to == Renderer::Radiance && dropped > 0 {
        eprintln!(
            "note: {dropped} emitting material(s) also reflect; a Radiance `light` does not, so their reflectance \
             is dropped in scene.rad"
        );
    }
    println!(
        "wrote {} files to {} ({} faces, {} points); run: python3 {}/{}",
        files.len(),
        args.out.display(),
        scene.faces.len(),
        points.len(),
        args.out.display(),
        match args.to {
            Renderer::Radiance => RADIANCE_SCRIPT_NAME,
            Renderer::Mitsuba => MITSUBA_SCRIPT_NAME,
        }
    );
    Ok(())
}

/// The files of an export, in memory.
pub fn export_files(scene: &Scene, points: &[EvalPoint], to: Renderer) -> Result<Vec<ExportFile>> {
    let mut files = vec![("points.csv".to_string(), points_csv(scene, points)?)];
    match to {
        Renderer::Radiance => {
            files.push(("scene.rad".into(), radiance_scene(scene).into_bytes()));
            files.push((
                RADIANCE_SCRIPT_NAME.into(),
                RADIANCE_SCRIPT.as_bytes().to_vec(),
            ));
        }
        Renderer::Mitsuba => {
            files.push(("scene.xml".into(), mitsuba_xml(scene).into_bytes()));
            for (k, _) in scene.materials.iter().enumerate() {
                if let Some(ply) = material_ply(scene, k as u32) {
                    files.push((format!("mat_{k}.ply"), ply));
                }
            }
            files.push((
                MITSUBA_SCRIPT_NAME.into(),
                MITSUBA_SCRIPT.as_bytes().to_vec(),
            ));
        }
    }
    Ok(files)
}

/// Writes every file into a staging directory beside `out`, then moves them into `out`; on any error the
/// staging directory is removed and `out` is untouched.
pub fn write_all(out: &Path, files: &[ExportFile]) -> Result<()> {
    let name = out
        .file_name()
        .map_or_else(|| "export".into(), |n| n.to_string_lossy().into_owned());
    let staging = out.with_file_name(format!(".{name}.staging.{}", std::process::id()));
    let staged = (|| -> Result<()> {
        std::fs::create_dir_all(&staging)
            .with_context(|| format!("cannot create directory {}", staging.display()))?;
        for (file, bytes) in files {
            atomic::write_bytes(&staging.join(file), |w| Ok(w.write_all(bytes)?))?;
        }
        std::fs::create_dir_all(out)
            .with_context(|| format!("cannot create directory {}", out.display()))?;
        Ok(())
    })();
    if let Err(e) = staged {
        let _ = std::fs::remove_dir_all(&staging);
        return Err(e);
    }
    for (file, _) in files {
        std::fs::rename(staging.join(file), out.join(file))
            .with_context(|| format!("cannot move {file} into {}", out.display()))?;
    }
    let _ = std::fs::remove_dir_all(&staging);
    Ok(())
}

fn points_csv(scene: &Scene, points: &[EvalPoint]) -> Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record([
        "point", "face", "x", "y", "z", "nx", "ny", "nz", "rho_r", "rho_g", "rho_b", "e_r", "e_g",
        "e_b", "lift",
    ])?;
    let lift = LIFT_REL * scene.diagonal();
    for (i, p) in points.iter().enumerate() {
        let m = scene.material(p.face);
        let mut row = vec![i.to_string(), p.face.to_string()];
        row.extend(
            [
                p.point.x,
                p.point.y,
                p.point.z,
                p.normal.x,
                p.normal.y,
                p.normal.z,
                m.reflectance.x,
                m.reflectance.y,
                m.reflectance.z,
                m.emission.x,
                m.emission.y,
                m.emission.z,
                lift,
            ]
            .iter()
            .map(|v| v.to_string()),
        );
        w.write_record(&row)?;
    }
    Ok(w.into_inner()?)
}

/// The black material a Radiance face shows from behind.
const BACK: &str = "radlab_back";

/// A Radiance scene description: materials, then one polygon per face.
pub fn radiance_scene(scene: &Scene) -> String {
    let mut s = format!(
        "# {} exported by radlab: {} faces. Lambertian `plastic` (specularity 0, roughness 0) of reflectance rho,\n\
         # one-sided as radlab's faces: a `mixfunc` shows it where the ray meets the front (Rdot > 0) and black\n\
         # `radlab_back` elsewhere; emitters as `light` of radiance E/pi (a Radiance light does not reflect).\n\
         \nvoid plastic {BACK}\n0\n0\n5 0 0 0 0 0\n",
        scene.name,
        scene.faces.len()
    );
    let inv_pi = std::f64::consts::FRAC_1_PI;
    for (k, m) in scene.materials.iter().enumerate() {
        let _ = writeln!(s, "\n# material {k}: {}", m.name);
        if m.is_emitter() {
            let l = m.emission * inv_pi;
            let _ = writeln!(s, "void light mat_{k}\n0\n0\n3 {} {} {}", l.x, l.y, l.z);
        } else {
            let r = m.reflectance;
            let _ = writeln!(
                s,
                "void plastic mat_{k}_front\n0\n0\n5 {} {} {} 0 0\n\n\
                 void mixfunc mat_{k}\n4 mat_{k}_front {BACK} if(Rdot,1,0) .\n0\n0",
                r.x, r.y, r.z
            );
        }
    }
    s.push('\n');
    for (f, face) in scene.faces.iter().enumerate() {
        let v = face.vertex_indices();
        let _ = write!(
            s,
            "mat_{} polygon f{f}\n0\n0\n{}",
            face.material,
            3 * v.len()
        );
        for &i in v {
            let p = scene.vertices[i as usize];
            let _ = write!(s, " {} {} {}", p.x, p.y, p.z);
        }
        s.push('\n');
    }
    s
}

/// A Mitsuba 3 scene: the path integrator, the camera (if any), one PLY shape per material.
pub fn mitsuba_xml(scene: &Scene) -> String {
    let mut s = String::from("<scene version=\"3.0.0\">\n");
    let _ = writeln!(
        s,
        "    <!-- {} exported by radlab: {} faces; diffuse BSDFs of reflectance rho, area emitters of radiance E/pi -->",
        scene.name,
        scene.faces.len()
    );
    s.push_str("    <integrator type=\"path\">\n        <integer name=\"max_depth\" value=\"-1\"/>\n    </integrator>\n");
    if let Some(c) = &scene.camera {
        let _ = write!(
            s,
            "    <sensor type=\"perspective\">\n        <string name=\"fov_axis\" value=\"y\"/>\n        \
             <float name=\"fov\" value=\"{}\"/>\n        <transform name=\"to_world\">\n            \
             <lookat origin=\"{}, {}, {}\" target=\"{}, {}, {}\" up=\"{}, {}, {}\"/>\n        </transform>\n        \
             <sampler type=\"independent\">\n            <integer name=\"sample_count\" value=\"64\"/>\n        </sampler>\n        \
             <film type=\"hdrfilm\">\n            <integer name=\"width\" value=\"{}\"/>\n            \
             <integer name=\"height\" value=\"{}\"/>\n            <rfilter type=\"box\"/>\n        </film>\n    </sensor>\n",
            c.fov_y_deg,
            c.eye.x,
            c.eye.y,
            c.eye.z,
            c.target.x,
            c.target.y,
            c.target.z,
            c.up.x,
            c.up.y,
            c.up.z,
            c.width,
            c.height
        );
    }
    let inv_pi = std::f64::consts::FRAC_1_PI;
    for (k, m) in scene.materials.iter().enumerate() {
        if !scene.faces.iter().any(|f| f.material as usize == k) {
            continue;
        }
        let r = m.reflectance;
        let _ = write!(
            s,
            "    <!-- material {k}: {} -->\n    <shape type=\"ply\" id=\"mat_{k}\">\n        \
             <string name=\"filename\" value=\"mat_{k}.ply\"/>\n        <boolean name=\"face_normals\" value=\"true\"/>\n        \
             <bsdf type=\"diffuse\">\n            <rgb name=\"reflectance\" value=\"{}, {}, {}\"/>\n        </bsdf>\n",
            xml_escape(&m.name),
            r.x,
            r.y,
            r.z
        );
        if m.is_emitter() {
            let l = m.emission * inv_pi;
            let _ = write!(
                s,
                "        <emitter type=\"area\">\n            <rgb name=\"radiance\" value=\"{}, {}, {}\"/>\n        </emitter>\n",
                l.x, l.y, l.z
            );
        }
        s.push_str("    </shape>\n");
    }
    s.push_str("</scene>\n");
    s
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace("--", "- -")
}

/// A binary little-endian PLY of the faces of material `k` (quads split into two triangles along 0–2, exact
/// for radlab's planar convex quads), or `None` if no face uses it.
pub fn material_ply(scene: &Scene, k: u32) -> Option<Vec<u8>> {
    let faces: Vec<_> = scene.faces.iter().filter(|f| f.material == k).collect();
    if faces.is_empty() {
        return None;
    }
    let mut verts: Vec<f32> = Vec::new();
    let mut tris: Vec<[u32; 3]> = Vec::new();
    for f in faces {
        let base = (verts.len() / 3) as u32;
        for &i in f.vertex_indices() {
            let p = scene.vertices[i as usize];
            verts.extend([p.x as f32, p.y as f32, p.z as f32]);
        }
        tris.push([base, base + 1, base + 2]);
        if f.vertex_count() == 4 {
            tris.push([base, base + 2, base + 3]);
        }
    }
    let mut out = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\nproperty float y\n\
         property float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        verts.len() / 3,
        tris.len()
    )
    .into_bytes();
    for v in verts {
        out.extend(v.to_le_bytes());
    }
    for t in tris {
        out.push(3);
        for i in t {
            out.extend((i as i32).to_le_bytes());
        }
    }
    Some(out)
}

/// File name of the Radiance script.
pub const RADIANCE_SCRIPT_NAME: &str = "radiance-points.py";
/// File name of the Mitsuba script.
pub const MITSUBA_SCRIPT_NAME: &str = "mitsuba-points.py";

const RADIANCE_SCRIPT: &str = include_str!("export_radiance_points.py");
const MITSUBA_SCRIPT: &str = include_str!("export_mitsuba_points.py");

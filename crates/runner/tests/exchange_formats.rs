//! Exchange formats end to end: an MGF furnace solved by matrix radiosity gives B = E/(1 − ρ); the Cornell box
//! as MGF gives builtin:cornell's matrix radiosity face by face; `radlab export` writes complete Radiance and
//! Mitsuba scenes whose numbers are the scene's (polygons, E/π, triangles), and nothing on failure. The
//! cross-checks against the renderers themselves need Radiance or Mitsuba installed and are documented in
//! scenes/README.md; they are not run here (CI has neither).

mod support;
use support::{radlab, repo, text};

fn csv_rows(bytes: &[u8]) -> (Vec<String>, Vec<Vec<String>>) {
    let mut r = csv::Reader::from_reader(bytes);
    let h = r
        .headers()
        .expect("header")
        .iter()
        .map(str::to_string)
        .collect();
    let rows = r
        .records()
        .map(|x| x.expect("row").iter().map(str::to_string).collect())
        .collect();
    (h, rows)
}

#[test]
fn mgf_furnace_solves_to_e_over_one_minus_rho() {
    // A closed box (a prism facing in), rd 0.8 neutral, ed 179 lm/m² neutral: ρ = 0.8 in every channel,
    // E = M·(1, 1, 1) = (1.2049, 0.9484, 0.9091) W/m², so B = 5 E.
    let tmp = tempfile::tempdir().expect("tmp");
    let scene = tmp.path().join("furnace.mgf");
    std::fs::write(
        &scene,
        "m f =\n rd .8\n ed 179\nv a =\n p 0 0 0\nv b =\n p 0 1 0\nv c =\n p 1 1 0\nv d =\n p 1 0 0\n\
         xf -s 2\nprism a b c d -1\nxf\n",
    )
    .expect("write");
    let points = tmp.path().join("p.csv");
    std::fs::write(
        &points,
        "x,y,z\n1,1,0\n0.5,1.5,-2\n0,0.3,-1.2\n2,1.9,-0.1\n",
    )
    .expect("points");
    let o = radlab(
        tmp.path(),
        &[
            "probe",
            scene.to_str().expect("utf8"),
            "--method",
            "matrix",
            "--points",
            points.to_str().expect("utf8"),
        ],
    );
    assert!(o.status.success(), "{}", text(&o));
    let (_, rows) = csv_rows(&o.stdout);
    assert_eq!(rows.len(), 4);
    let e = [1.2049, 0.9484, 0.9091];
    for r in rows {
        for c in 0..3 {
            let b: f64 = r[3 + c].parse().expect("number");
            // E to the 4 digits of the sRGB matrix; the solve to its own tolerance.
            assert!((b / (5.0 * e[c]) - 1.0).abs() < 1e-3, "{r:?}");
        }
    }
}

#[test]
fn cornell_mgf_has_builtin_cornells_matrix_radiosity() {
    let tmp = tempfile::tempdir().expect("tmp");
    let mut faces = Vec::new();
    for (name, scene) in [
        ("builtin", "builtin:cornell?width=8&height=8".to_string()),
        (
            "mgf",
            repo()
                .join("scenes/cornell.mgf")
                .to_string_lossy()
                .into_owned(),
        ),
    ] {
        let out = tmp.path().join(name);
        let o = radlab(
            tmp.path(),
            &[
                "solve",
                &scene,
                "--method",
                "matrix",
                "--set",
                "visibility=centre",
                "--set",
                "element_size=150",
                "--out",
                out.to_str().expect("utf8"),
            ],
        );
        assert!(o.status.success(), "{}", text(&o));
        faces.push(csv_rows(&std::fs::read(out.join("faces.csv")).expect("faces.csv")).1);
    }
    assert_eq!(faces[0].len(), faces[1].len());
    for (a, b) in faces[0].iter().zip(&faces[1]) {
        for c in [2, 9, 10, 11] {
            let (x, y): (f64, f64) = (a[c].parse().expect("n"), b[c].parse().expect("n"));
            assert!(
                (x - y).abs() <= 1e-9 * x.abs().max(1e-12),
                "face {}: {x} against {y}",
                a[0]
            );
        }
    }
}

#[test]
fn export_writes_complete_radiance_and_mitsuba_scenes() {
    let tmp = tempfile::tempdir().expect("tmp");
    let scene = radlab_formats::load_scene("builtin:cornell").expect("cornell");
    let rad = tmp.path().join("rad");
    let o = radlab(
        tmp.path(),
        &[
            "export",
            "builtin:cornell",
            "--to",
            "radiance",
            "--out",
            rad.to_str().expect("utf8"),
            "--points",
            "50",
        ],
    );
    assert!(o.status.success(), "{}", text(&o));
    let r = std::fs::read_to_string(rad.join("scene.rad")).expect("scene.rad");
    assert_eq!(r.matches(" polygon f").count(), scene.faces.len());
    // Three reflecting materials, each one-sided: its plastic where a ray meets the front, black behind.
    assert_eq!(r.matches("void plastic").count(), 4);
    assert!(r.contains("void plastic radlab_back\n0\n0\n5 0 0 0 0 0\n"));
    for k in [0, 1, 2] {
        assert!(
            r.contains(&format!(
                "void mixfunc mat_{k}\n4 mat_{k}_front radlab_back if(Rdot,1,0) .\n0\n0\n"
            )),
            "mat_{k}"
        );
    }
    // The light: radiance E/π per channel.
    let e = radlab_scene::builtin::cornell_light_exitance() / std::f64::consts::PI;
    assert!(r.contains(&format!(
        "void light mat_3\n0\n0\n3 {} {} {}",
        e.x, e.y, e.z
    )));
    let (h, rows) = csv_rows(&std::fs::read(rad.join("points.csv")).expect("points"));
    assert_eq!(rows.len(), 50);
    assert_eq!(&h[..8], ["point", "face", "x", "y", "z", "nx", "ny", "nz"]);
    assert!(rad.join("radiance-points.py").exists());

    let mi = tmp.path().join("mi");
    let o = radlab(
        tmp.path(),
        &[
            "export",
            "builtin:cornell",
            "--to",
            "mitsuba",
            "--out",
            mi.to_str().expect("utf8"),
        ],
    );
    assert!(o.status.success(), "{}", text(&o));
    let xml = std::fs::read_to_string(mi.join("scene.xml")).expect("scene.xml");
    assert_eq!(xml.matches("<shape type=\"ply\"").count(), 4);
    assert_eq!(xml.matches("<emitter type=\"area\">").count(), 1);
    assert!(xml.contains("<lookat origin=\"278, 273, -800\""));
    // Each PLY holds its material's faces as triangles (quads split in two).
    for k in 0..4u32 {
        let ply = std::fs::read(mi.join(format!("mat_{k}.ply"))).expect("ply");
        let head = String::from_utf8_lossy(&ply[..200.min(ply.len())]).into_owned();
        let tris: usize = scene
            .faces
            .iter()
            .filter(|f| f.material == k)
            .map(|f| f.vertex_count() - 2)
            .sum();
        assert!(
            head.contains(&format!("element face {tris}\n")),
            "mat_{k}: {head}"
        );
    }
    let leftovers: Vec<_> = std::fs::read_dir(tmp.path())
        .expect("dir")
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().starts_with('.'))
        .collect();
    assert!(leftovers.is_empty(), "staging left behind: {leftovers:?}");

    // An output path below a regular file cannot be created: an error, and nothing written.
    let blocker = tmp.path().join("blocker");
    std::fs::write(&blocker, "x").expect("write");
    let o = radlab(
        tmp.path(),
        &[
            "export",
            "builtin:cornell",
            "--to",
            "radiance",
            "--out",
            blocker.join("out").to_str().expect("utf8"),
        ],
    );
    assert!(!o.status.success());
    assert!(text(&o).contains("cannot create directory"), "{}", text(&o));
    let left: Vec<_> = std::fs::read_dir(tmp.path())
        .expect("dir")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    assert!(
        left.iter()
            .all(|n| ["rad", "mi", "blocker"].contains(&n.as_str())),
        "{left:?}"
    );
}

/// Whether `python3 -c CODE` runs and exits 0 (a renderer's Python package is installed and works).
fn python_runs(code: &str) -> bool {
    std::process::Command::new("python3")
        .args(["-c", code])
        .output()
        .is_ok_and(|o| o.status.success())
}

/// Rows of a points CSV by column name: x,y,z,r,g,b and se_r,se_g,se_b.
fn answers(bytes: &[u8]) -> Vec<[f64; 9]> {
    let (h, rows) = csv_rows(bytes);
    let col = |name: &str| h.iter().position(|c| c == name).expect(name);
    let cols = ["x", "y", "z", "r", "g", "b", "se_r", "se_g", "se_b"].map(col);
    rows.iter()
        .map(|r| cols.map(|c| r[c].parse::<f64>().expect("number")))
        .collect()
}

/// The other renderer's answers at the exported points against radlab's path tracer at the same points: the
/// mean over points and channels of z² = (B − R)² / (s_B² + s_R²), which is 1 for independent unbiased answers,
/// and the z-score of their summed signed difference.
/// On the Cornell box with a light that does not reflect (Radiance's `light` cannot), both renderers model
/// radlab's scene exactly, so anything well above 1 is a disagreement (scenes/README.md, "The cross-check").
fn cross_check(renderer: &str, script: &str, script_args: &[&str]) -> (f64, f64) {
    let tmp = tempfile::tempdir().expect("tmp");
    let scene = tmp.path().join("cornell-dark-light.mgf");
    let mgf = std::fs::read_to_string(repo().join("scenes/cornell.mgf")).expect("cornell.mgf");
    assert!(mgf.contains("rd 0.78"));
    std::fs::write(&scene, mgf.replace("rd 0.78", "rd 0")).expect("write");
    let dir = tmp.path().join(renderer);
    let scene = scene.to_str().expect("utf8");
    let args = [
        "export",
        scene,
        "--to",
        renderer,
        "--out",
        dir.to_str().expect("utf8"),
        "--points",
        "64",
    ];
    let o = radlab(tmp.path(), &args);
    assert!(o.status.success(), "{}", text(&o));
    let out = dir.join("answers.csv");
    let o = std::process::Command::new("python3")
        .arg(dir.join(script))
        .args(script_args)
        .args(["--out", out.to_str().expect("utf8")])
        .output()
        .expect("python3 runs");
    assert!(o.status.success(), "{}", text(&o));
    let theirs = answers(&std::fs::read(&out).expect("answers"));
    let points = dir.join("points.csv");
    let probe = [
        "probe",
        scene,
        "--method",
        "pathtrace",
        "--set",
        "samples=65536",
        "--points",
        points.to_str().expect("utf8"),
    ];
    let o = radlab(tmp.path(), &probe);
    assert!(o.status.success(), "{}", text(&o));
    let ours = answers(&o.stdout);
    assert_eq!(theirs.len(), 64);
    assert_eq!(ours.len(), 64);
    let mut z2 = Vec::new();
    // The signed difference of channel sums over all points, and its variance taking each point's channels
    // as fully correlated (they come from the same paths): the one bound that sees a bias smaller than a
    // point's noise.
    let (mut signed, mut signed_var) = (0.0, 0.0);
    for (t, r) in theirs.iter().zip(&ours) {
        signed += (t[3] + t[4] + t[5]) - (r[3] + r[4] + r[5]);
        signed_var += (t[6] + t[7] + t[8]).powi(2) + (r[6] + r[7] + r[8]).powi(2);
        assert!(
            (t[0] - r[0]).abs() + (t[1] - r[1]).abs() + (t[2] - r[2]).abs() < 1e-6,
            "same points"
        );
        for c in 3..6 {
            let var = t[c + 3].powi(2) + r[c + 3].powi(2);
            if var == 0.0 {
                // A point no light reaches (under a block): both must say 0, exactly.
                assert_eq!((t[c], r[c]), (0.0, 0.0), "an exact answer must agree");
                continue;
            }
            z2.push((t[c] - r[c]).powi(2) / var);
        }
    }
    let mean = z2.iter().sum::<f64>() / z2.len() as f64;
    let z = signed / signed_var.sqrt();
    eprintln!(
        "{renderer}: mean z² {mean:.2} over {} values, signed z {z:.2}",
        z2.len()
    );
    (mean, z)
}

/// Radiance (Ward 1994) agrees with radlab's path tracer point by point. Runs where Radiance is installed
/// (`rtrace` on PATH, or `pip install pyradiance`); elsewhere (CI) it says so and checks nothing.
#[test]
fn radiance_agrees_with_the_path_tracer_where_installed() {
    let on_path = std::process::Command::new("rtrace")
        .arg("-version")
        .output()
        .is_ok();
    if !on_path && !python_runs("import pyradiance") {
        eprintln!("skipped: Radiance is not installed (rtrace, or `pip install pyradiance`)");
        return;
    }
    let (z2, z) = cross_check("radiance", "radiance-points.py", &["--repeats", "32"]);
    // 64 points: the mean of z² has a standard deviation of about 0.2 where the answers agree.
    assert!(z2 < 2.0, "Radiance against radlab: mean z² {z2}");
    assert!(
        z.abs() < 4.0,
        "Radiance against radlab: signed difference at {z} standard errors"
    );
}

/// Mitsuba 3 (Jakob et al. 2022) agrees with radlab's path tracer point by point. Runs where Mitsuba's
/// `llvm_ad_rgb` variant loads (`pip install mitsuba` and an LLVM it accepts: scenes/README.md); elsewhere it
/// says so and checks nothing.
#[test]
fn mitsuba_agrees_with_the_path_tracer_where_installed() {
    if !python_runs("import mitsuba as mi; mi.set_variant('llvm_ad_rgb')") {
        eprintln!("skipped: Mitsuba 3 (variant llvm_ad_rgb) is not installed");
        return;
    }
    let (z2, z) = cross_check("mitsuba", "mitsuba-points.py", &["--spp", "65536"]);
    assert!(z2 < 2.0, "Mitsuba against radlab: mean z² {z2}");
    assert!(
        z.abs() < 4.0,
        "Mitsuba against radlab: signed difference at {z} standard errors"
    );
}

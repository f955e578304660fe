//! Scene input end to end: every error path of the TOML, OBJ/MTL, PLY and OFF readers names the file and the
//! line or field; geometry read or generated is checked against closed forms (closed surfaces have zero total
//! vector area; box 6s², sphere 4πr²), the published Cornell box numbers, and spectral-to-RGB values computed
//! by an independent tool (colour-science 0.4.7, 1 nm CIE 1931 tables).

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use radlab_formats::load_scene;
use radlab_formats::{LoadNotes, MAX_COLOUR_REFLECTANCE, load_scene_with_notes};
use radlab_scene::glam::{DVec3, dvec3};
use radlab_scene::{FaceId, Scene, SceneError, builtin};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes")
}

fn load(p: &Path) -> Result<Scene, SceneError> {
    load_scene(p.to_str().expect("utf-8 path"))
}

fn load_noted(p: &Path) -> Result<(Scene, LoadNotes), SceneError> {
    load_scene_with_notes(p.to_str().expect("utf-8 path"))
}

/// Writes `files` (name, content) into a fresh directory.
fn temp_files(files: &[(&str, &[u8])]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("temp dir");
    for (name, content) in files {
        std::fs::write(dir.path().join(name), content).expect("write fixture");
    }
    dir
}

/// Loads a scene made of the given files, starting from the first.
fn load_files(files: &[(&str, &[u8])]) -> Result<Scene, SceneError> {
    let dir = temp_files(files);
    load(&dir.path().join(files[0].0))
}

fn error_of(r: Result<Scene, SceneError>) -> (SceneError, String) {
    let e = r.expect_err("an error was expected");
    let s = e.to_string();
    (e, s)
}

/// The line of a parse error (panics on other kinds).
fn line_of(e: &SceneError) -> usize {
    match e {
        SceneError::Parse { line, .. } => *line,
        other => panic!("expected a parse error with a line, got {other:?}"),
    }
}

fn vector_area(s: &Scene, faces: impl IntoIterator<Item = FaceId>) -> DVec3 {
    faces.into_iter().map(|f| s.polygon(f).vector_area()).sum()
}

/// Checks `faces` form a closed, consistently oriented surface over shared vertices: every directed edge
/// (a, b) is matched by exactly one (b, a).
fn assert_watertight(s: &Scene, faces: impl IntoIterator<Item = FaceId>) {
    // Per undirected edge (low, high): (uses, uses low→high minus uses high→low).
    let mut edges = std::collections::BTreeMap::<(u32, u32), (i32, i32)>::new();
    for f in faces {
        let v = s.faces[f].vertex_indices();
        for k in 0..v.len() {
            let (a, b) = (v[k], v[(k + 1) % v.len()]);
            let e = edges.entry((a.min(b), a.max(b))).or_default();
            e.0 += 1;
            e.1 += if a < b { 1 } else { -1 };
        }
    }
    for (&(a, b), &(uses, _)) in &edges {
        assert_eq!(uses, 2, "edge {a}-{b} is used {uses} times, not twice");
    }
    for (&(a, b), &(_, balance)) in &edges {
        assert_eq!(
            balance, 0,
            "edge {a}-{b} is not used once in each direction"
        );
    }
}

fn faces_with(s: &Scene, material: &str) -> Vec<FaceId> {
    (0..s.face_count())
        .filter(|&f| s.material(f).name == material)
        .collect()
}

// ---------------------------------------------------------------- TOML: geometry

const BOX_TOML: &str = r#"
[materials.grey]
reflectance = 0.5

[[objects]]
type = "box"
min = [1, 2, 3]
max = [3, 4, 5]
subdivisions = 3
material = "grey"
"#;

#[test]
fn toml_box_is_closed_with_area_six_s_squared_and_faces_outward_or_inward() {
    let s = load_files(&[("box.toml", BOX_TOML.as_bytes())]).expect("box loads");
    assert_eq!(s.face_count(), 6 * 9);
    assert!(vector_area(&s, 0..s.face_count()).length() < 1e-12);
    // Closed and connected: shared vertices, Euler characteristic V − E + F = 2 with E = 2F.
    assert_watertight(&s, 0..s.face_count());
    assert_eq!(s.vertices.len(), 6 * 9 + 2);
    assert!((s.total_area() - 6.0 * 2.0 * 2.0).abs() < 1e-12);
    let c = dvec3(2.0, 3.0, 4.0);
    assert!(s.faces.iter().all(|f| f.normal.dot(f.centroid - c) > 0.0));

    let inward = BOX_TOML.replace("subdivisions = 3", "subdivisions = 1\ninward = true");
    let s = load_files(&[("room.toml", inward.as_bytes())]).expect("room loads");
    assert_eq!(s.face_count(), 6);
    assert!(s.faces.iter().all(|f| f.normal.dot(c - f.centroid) > 0.0));
}

fn sphere_toml(n: usize, inward: bool) -> String {
    format!(
        "[materials.grey]\nreflectance = 0.5\n\n[[objects]]\ntype = \"sphere\"\ncenter = [1, -2, 0.5]\n\
         radius = 2\nsubdivisions = {n}\ninward = {inward}\nmaterial = \"grey\"\n"
    )
}

#[test]
fn toml_sphere_is_closed_and_its_area_tends_to_four_pi_r_squared() {
    let c = dvec3(1.0, -2.0, 0.5);
    let exact = 4.0 * PI * 4.0;
    let mut errors = Vec::new();
    for n in [4, 8, 16] {
        let s = load_files(&[("s.toml", sphere_toml(n, false).as_bytes())]).expect("sphere loads");
        assert_eq!(s.face_count(), 12 * n * n);
        assert!(
            vector_area(&s, 0..s.face_count()).length() < 1e-9,
            "not closed"
        );
        assert_watertight(&s, 0..s.face_count());
        assert_eq!(s.vertices.len(), 6 * n * n + 2);
        assert!(s.faces.iter().all(|f| f.normal.dot(f.centroid - c) > 0.0));
        for v in &s.vertices {
            assert!(((*v - c).length() - 2.0).abs() < 1e-12);
        }
        // An inscribed polyhedron: area below 4πr², converging as 1/n².
        let e = (exact - s.total_area()) / exact;
        assert!(e > 0.0);
        errors.push(e);
    }
    assert!(errors[2] < 0.005, "{errors:?}");
    for k in 0..2 {
        let ratio = errors[k] / errors[k + 1];
        assert!((3.0..5.0).contains(&ratio), "not O(1/n²): {errors:?}");
    }
    let s = load_files(&[("s.toml", sphere_toml(3, true).as_bytes())]).expect("inward sphere");
    assert!(s.faces.iter().all(|f| f.normal.dot(c - f.centroid) > 0.0));
}

#[test]
fn toml_scene_with_every_object_type_loads() {
    let (s, notes) = load_noted(&data("all_objects.toml")).expect("loads");
    assert_eq!(s.name, "all-objects");
    let cam = s.camera.as_ref().expect("camera");
    assert_eq!((cam.width, cam.height), (64, 48));
    assert_eq!(cam.up, DVec3::Y);
    // The OBJ's own materials come along (cube.obj has one face without material).
    assert_eq!(notes.default_material_faces, 1);
    assert!(
        s.materials
            .iter()
            .any(|m| m.emission == dvec3(10.0, 20.0, 30.0))
    );
    let lamp = faces_with(&s, "lamp");
    assert_eq!(lamp.len(), 1);
    assert!(s.faces[lamp[0]].normal.y < -0.999, "lamp faces down");
    assert_eq!(s.emission(lamp[0]), dvec3(20.0, 20.0, 15.0));
    // The pentagon was fanned into three triangles (counted).
    assert_eq!(s.warnings.polygons_triangulated, 1);
    // Room: 6 sides × 2 × 2; sphere 12·16; heightfields 2·2·2 and 2·4·4; tetra 4; cube 6; lamp 1; pentagon 3.
    assert_eq!(s.face_count(), 24 + 192 + 8 + 32 + 4 + 6 + 1 + 3);
}

#[test]
fn transforms_scale_then_rotate_then_translate_and_mirrors_keep_the_facing() {
    let toml = r#"
[materials.grey]
reflectance = 0.5

[[objects]]
type = "quad"
points = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
material = "grey"
transform = { scale = 2, rotate = { axis = [0, 0, 1], angle = 90 }, translate = [10, 0, 0] }
"#;
    let s = load_files(&[("t.toml", toml.as_bytes())]).expect("loads");
    // (1,0,0) → (2,0,0) → rotated 90° about z → (0,2,0) → (10,2,0); (1,1,0) → (2,2,0) → (−2,2,0) → (8,2,0).
    let expect = [
        dvec3(10.0, 0.0, 0.0),
        dvec3(10.0, 2.0, 0.0),
        dvec3(8.0, 2.0, 0.0),
        dvec3(8.0, 0.0, 0.0),
    ];
    for (v, e) in s.vertices.iter().zip(expect) {
        assert!((*v - e).length() < 1e-12, "{v} vs {e}");
    }
    assert!(s.faces[0].normal.z > 0.999);

    let mirrored = toml.replace(
        "scale = 2, rotate = { axis = [0, 0, 1], angle = 90 }, translate = [10, 0, 0]",
        "scale = [-1, 1, 1]",
    );
    let s = load_files(&[("m.toml", mirrored.as_bytes())]).expect("loads");
    assert!(s.vertices.iter().any(|v| v.x == -1.0));
    assert!(
        s.faces[0].normal.z > 0.999,
        "a mirror keeps the facing side"
    );

    // A mesh placed by a transform: tetra.off's apex (0,0,1) → ×0.5 → 90° about y: (x, z) ↦ (z, −x) →
    // (0.5, 0, 0) → + (0, 1, 1) = (0.5, 1, 1).
    let s = load(&data("all_objects.toml")).expect("loads");
    assert!(
        s.vertices
            .iter()
            .any(|v| (*v - dvec3(0.5, 1.0, 1.0)).length() < 1e-12)
    );
}

#[test]
fn degenerate_faces_are_counted_and_dropped() {
    let toml = r#"
[materials.grey]
reflectance = 0.5

[[objects]]
type = "polygon"
points = [[0, 0, 0], [1, 0, 0], [2, 0, 0]]
material = "grey"

[[objects]]
type = "polygon"
points = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
material = "grey"
"#;
    let s = load_files(&[("d.toml", toml.as_bytes())]).expect("loads");
    assert_eq!(s.face_count(), 1);
    assert_eq!(s.warnings.degenerate_faces, 1);

    let off = "OFF\n4 3 0\n0 0 0\n1 0 0\n0 1 0\n2 0 0\n3 0 1 2\n3 0 1 3\n3 1 1 2\n";
    let s = load_files(&[("d.off", off.as_bytes())]).expect("loads");
    assert_eq!(s.face_count(), 1);
    assert_eq!(s.warnings.degenerate_faces, 2);
}

// ---------------------------------------------------------------- TOML: errors

/// Loads `toml` as `bad.toml` and returns the error text, checking it names the file and `line`.
fn toml_error(toml: &str, line: usize) -> String {
    let (e, s) = error_of(load_files(&[("bad.toml", toml.as_bytes())]));
    assert!(s.contains("bad.toml"), "file not named: {s}");
    assert_eq!(line_of(&e), line, "{s}");
    s
}

#[test]
fn malformed_toml_names_the_line() {
    toml_error(
        "[materials.grey]\nreflectance = 0.5\nemission = [1, 2,, 3]\n",
        3,
    );
    toml_error("[materials.grey]\nreflectance = \n", 2);
    toml_error("name = \"room\n[materials.grey]\n", 1);
    // An unclosed array runs on until toml meets something that cannot continue it.
    toml_error(
        "[materials.grey]\nreflectance = 0.5\nemission = [1, 2\n\n[[objects]]\n",
        5,
    );
}

#[test]
fn unknown_keys_are_named_with_their_line() {
    let s = toml_error("[materials.grey]\nreflectance = 0.5\ncolour = 1\n", 3);
    assert!(s.contains("colour"), "{s}");
    let s = toml_error("titel = \"x\"\n", 1);
    assert!(s.contains("titel"), "{s}");
    // A key that exists, but not for this object type.
    let s = toml_error(
        "[materials.grey]\nreflectance = 0.5\n\n[[objects]]\ntype = \"box\"\nmin = [0, 0, 0]\n\
         max = [1, 1, 1]\nradius = 2\nmaterial = \"grey\"\n",
        4,
    );
    assert!(s.contains("'radius'") && s.contains("box"), "{s}");
    let s = toml_error(
        "[materials.grey]\nreflectance = 0.5\n\n[[objects]]\ntype = \"cone\"\nmaterial = \"grey\"\n",
        4,
    );
    assert!(s.contains("cone") && s.contains("sphere"), "{s}");
    let s = toml_error(
        "[materials.grey]\nreflectance = 0.5\n\n[[objects]]\ntype = \"quad\"\n\
         points = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]\nmaterial = \"gray\"\n",
        4,
    );
    assert!(s.contains("'gray'") && s.contains("grey"), "{s}");
    let s = toml_error(
        "[materials.grey]\nreflectance = 0.5\n\n[camera]\neye = [0, 0, 0]\ntarget = [0, 0, 1]\nfov = 40\nzoom = 2\n",
        8,
    );
    assert!(s.contains("zoom"), "{s}");
}

#[test]
fn non_finite_coordinates_are_rejected_naming_the_key() {
    let s = toml_error(
        "[materials.grey]\nreflectance = 0.5\n\n[[objects]]\ntype = \"box\"\nmin = [nan, 0, 0]\n\
         max = [1, 1, 1]\nmaterial = \"grey\"\n",
        4,
    );
    assert!(s.contains("'min'") && s.contains("finite"), "{s}");
    let s = toml_error(
        "[materials.grey]\nreflectance = 0.5\n\n[[objects]]\ntype = \"quad\"\n\
         points = [[0, 0, 0], [inf, 0, 0], [1, 1, 0], [0, 1, 0]]\nmaterial = \"grey\"\n",
        4,
    );
    assert!(s.contains("'points'"), "{s}");
    let s = toml_error(
        "[materials.grey]\nreflectance = 0.5\n\n[camera]\neye = [0, nan, 0]\ntarget = [0, 0, 1]\nfov = 40\n",
        4,
    );
    assert!(s.contains("camera"), "{s}");
    let s = toml_error(
        "[materials.grey]\nreflectance = 0.5\n\n[[objects]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\n\
         radius = inf\nmaterial = \"grey\"\n",
        4,
    );
    assert!(s.contains("radius"), "{s}");
}

#[test]
fn reflectance_one_and_negative_emission_are_rejected_naming_the_field() {
    let s = toml_error("# a comment\n[materials.mirror]\nreflectance = 1.0\n", 3);
    assert!(s.contains("mirror") && s.contains("reflectance"), "{s}");
    let s = toml_error("[materials.paint]\nreflectance = [0.5, 1.2, 0.5]\n", 2);
    assert!(s.contains("reflectance"), "{s}");
    let s = toml_error(
        "[materials.lamp]\nreflectance = 0\n\nemission = [1, -1, 1]\n",
        4,
    );
    assert!(s.contains("lamp") && s.contains("emission"), "{s}");
    let s = toml_error("[materials.x]\nreflectance = [0.5, 0.5]\n", 2);
    assert!(s.contains("three"), "{s}");
    let s = toml_error(
        "[materials.grey]\nreflectance = 0.5\n[camera]\neye = [0, 0, 0]\ntarget = [0, 0, 1]\nfov = 0\n",
        3,
    );
    assert!(s.contains("fov"), "{s}");
}

#[test]
fn a_missing_mesh_file_is_named_with_the_scene_line() {
    let s = toml_error(
        "[materials.grey]\nreflectance = 0.5\n\n[[objects]]\ntype = \"mesh\"\nfile = \"meshes/bunny.off\"\n",
        4,
    );
    assert!(
        s.contains("meshes/bunny.off") && s.contains("not found"),
        "{s}"
    );
}

// ---------------------------------------------------------------- OBJ / MTL

#[test]
fn obj_mtl_materials_are_read() {
    let (s, notes) = load_noted(&data("cube.obj")).expect("cube loads");
    assert_eq!(s.name, "cube");
    assert_eq!(s.face_count(), 6);
    assert!(s.faces.iter().all(|f| f.vertex_count() == 4), "quads kept");
    assert!(vector_area(&s, 0..6).length() < 1e-12);
    let c = DVec3::splat(0.5);
    assert!(s.faces.iter().all(|f| f.normal.dot(f.centroid - c) > 0.0));
    assert_eq!(notes.default_material_faces, 1);
    let white = faces_with(&s, "white");
    assert_eq!(white.len(), 4);
    assert_eq!(s.reflectance(white[0]), dvec3(0.7, 0.6, 0.5));
    let lamp = faces_with(&s, "lamp");
    assert_eq!(lamp.len(), 1);
    assert_eq!(s.emission(lamp[0]), dvec3(10.0, 20.0, 30.0));
    assert_eq!(s.reflectance(lamp[0]), DVec3::ZERO, "Kd 0 is grey 0");
    let grey = faces_with(&s, "default-grey");
    assert_eq!(grey.len(), 1);
    assert_eq!(s.reflectance(grey[0]), DVec3::splat(0.5));
    assert!(s.faces[lamp[0]].normal.z > 0.999);
}

/// Writes a scene as OBJ + MTL (one material per face group) with full precision.
fn write_obj(s: &Scene) -> (String, String) {
    let mut obj = String::from("mtllib scene.mtl\n");
    let mut mtl = String::new();
    for m in &s.materials {
        let (r, e) = (m.reflectance, m.emission);
        mtl += &format!(
            "newmtl {}\nKd {:e} {:e} {:e}\nKe {:e} {:e} {:e}\n",
            m.name, r.x, r.y, r.z, e.x, e.y, e.z
        );
    }
    for v in &s.vertices {
        obj += &format!("v {:e} {:e} {:e}\n", v.x, v.y, v.z);
    }
    for f in &s.faces {
        obj += &format!("usemtl {}\nf", s.materials[f.material as usize].name);
        for &i in f.vertex_indices() {
            obj += &format!(" {}", i + 1);
        }
        obj += "\n";
    }
    (obj, mtl)
}

#[test]
fn obj_mtl_round_trip_keeps_faces_and_materials() {
    let original = builtin("cornell?tessellation=2").expect("cornell");
    let (obj, mtl) = write_obj(&original);
    let back = load_files(&[("scene.obj", obj.as_bytes()), ("scene.mtl", mtl.as_bytes())])
        .expect("round trip loads");
    assert_eq!(back.face_count(), original.face_count());
    for f in 0..original.face_count() {
        let (a, b) = (original.polygon(f), back.polygon(f));
        assert_eq!(a.len(), b.len(), "face {f} arity");
        // OBJ positions are read back in double precision.
        for (p, q) in a.vertices().iter().zip(b.vertices()) {
            assert!((*p - *q).length() < 1e-9, "face {f}: {p} vs {q}");
        }
        let (ma, mb) = (original.material(f), back.material(f));
        assert_eq!(ma.name, mb.name);
        assert!((ma.reflectance - mb.reflectance).abs().max_element() < 1e-6);
        assert!(
            (ma.emission - mb.emission).abs().max_element()
                < 1e-5 * ma.emission.max_element().max(1.0)
        );
    }
}

#[test]
fn obj_nan_vertex_names_its_line() {
    let (e, s) = error_of(load(&data("nan_vertex.obj")));
    assert_eq!(line_of(&e), 4, "{s}");
    assert!(s.contains("nan_vertex.obj") && s.contains("finite"), "{s}");
    let (e, s) = error_of(load_files(&[(
        "inf.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1e999 0\nf 1 2 3\n",
    )]));
    assert_eq!(line_of(&e), 3, "{s}");
}

#[test]
fn truncated_obj_names_the_line() {
    let cube = std::fs::read_to_string(data("cube.obj")).expect("fixture");
    let mtl = std::fs::read(data("cube.mtl")).expect("fixture");
    // Cut in the middle of the last face.
    let cut = &cube[..cube.rfind("7 8").expect("last face")];
    let last_line = cut.lines().count();
    let (e, s) = error_of(load_files(&[
        ("cut.obj", cut.as_bytes()),
        ("cube.mtl", &mtl),
    ]));
    assert_eq!(line_of(&e), last_line, "{s}");
    assert!(s.contains("cut.obj") && s.contains("cut short"), "{s}");
    // Cut in the middle of a vertex.
    let cut = &cube[..cube.find("v 1 1 0").expect("vertex") + 5];
    let last_line = cut.lines().count();
    let (e, s) = error_of(load_files(&[
        ("cut.obj", cut.as_bytes()),
        ("cube.mtl", &mtl),
    ]));
    assert_eq!(line_of(&e), last_line, "{s}");
    // A face pointing past the vertices.
    let (e, s) = error_of(load_files(&[(
        "idx.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n",
    )]));
    assert_eq!(line_of(&e), 5, "{s}");
}

#[test]
fn mtl_problems_name_the_mtl_file_material_and_line() {
    let obj = b"mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl mirror\nf 1 2 3\n";
    let (e, s) = error_of(load_files(&[
        ("a.obj", obj),
        ("m.mtl", b"newmtl mirror\nKd 1 1 1\n"),
    ]));
    assert_eq!(line_of(&e), 2, "{s}");
    assert!(
        s.contains("m.mtl") && s.contains("mirror") && s.contains("Kd"),
        "{s}"
    );
    let (e, s) = error_of(load_files(&[
        ("a.obj", obj),
        ("m.mtl", b"newmtl mirror\nKd 0.5 0.5 0.5\n\nKe 1 -2 1\n"),
    ]));
    assert_eq!(line_of(&e), 4, "{s}");
    assert!(s.contains("Ke"), "{s}");
    let (_, s) = error_of(load_files(&[("a.obj", obj)]));
    assert!(s.contains("m.mtl"), "missing MTL not named: {s}");
    let (e, s) = error_of(load_files(&[
        ("a.obj", obj),
        ("m.mtl", b"newmtl glass\nKd 0.5 0.5 0.5\n"),
    ]));
    assert_eq!(line_of(&e), 5, "{s}");
    assert!(s.contains("mirror") && s.contains("glass"), "{s}");
}

// ---------------------------------------------------------------- PLY

/// The tetrahedron of tetra_ascii.ply.
const TETRA_V: [([f32; 3], [u8; 3]); 4] = [
    ([0.0, 0.0, 0.0], [255, 0, 0]),
    ([1.0, 0.0, 0.0], [0, 255, 0]),
    ([0.0, 1.0, 0.0], [0, 0, 255]),
    ([0.0, 0.0, 1.0], [255, 255, 255]),
];
const TETRA_F: [[i32; 3]; 4] = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];

fn binary_ply(big_endian: bool) -> Vec<u8> {
    let format = if big_endian {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let mut out = format!(
        "ply\nformat {format} 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\nelement face 4\n\
         property list uchar int vertex_indices\nend_header\n"
    )
    .into_bytes();
    for (p, c) in TETRA_V {
        for x in p {
            out.extend(if big_endian {
                x.to_be_bytes()
            } else {
                x.to_le_bytes()
            });
        }
        out.extend(c);
    }
    for f in TETRA_F {
        out.push(3);
        for i in f {
            out.extend(if big_endian {
                i.to_be_bytes()
            } else {
                i.to_le_bytes()
            });
        }
    }
    out
}

fn same_scene(a: &Scene, b: &Scene) {
    assert_eq!(a.vertices, b.vertices);
    assert_eq!(a.face_count(), b.face_count());
    for f in 0..a.face_count() {
        assert_eq!(a.faces[f].indices, b.faces[f].indices);
        assert_eq!(a.material(f).reflectance, b.material(f).reflectance);
    }
}

#[test]
fn ascii_and_binary_ply_give_identical_scenes() {
    let (ascii, notes) = load_noted(&data("tetra_ascii.ply")).expect("ascii loads");
    let le = load_files(&[("le.ply", &binary_ply(false))]).expect("little endian loads");
    let be = load_files(&[("be.ply", &binary_ply(true))]).expect("big endian loads");
    same_scene(&ascii, &le);
    same_scene(&ascii, &be);
    assert_eq!(ascii.face_count(), 4);
    assert!(vector_area(&ascii, 0..4).length() < 1e-12);
    let c = DVec3::splat(0.25);
    assert!(
        ascii
            .faces
            .iter()
            .all(|f| f.normal.dot(f.centroid - c) > 0.0)
    );
    // Face 0 (vertices 0, 2, 1): mean of red, blue, green = 1/3 each. Face 3 (1, 2, 3): (1, 2, 2)/3 → the
    // green and blue channels 2/3; face 1 (0, 1, 3): (2, 2, 1)/3.
    let third = 1.0 / 3.0;
    assert!(
        (ascii.reflectance(0) - DVec3::splat(third))
            .abs()
            .max_element()
            < 1e-12
    );
    assert!(
        (ascii.reflectance(1) - dvec3(2.0, 2.0, 1.0) * third)
            .abs()
            .max_element()
            < 1e-12
    );
    assert!(
        (ascii.reflectance(3) - dvec3(1.0, 2.0, 2.0) * third)
            .abs()
            .max_element()
            < 1e-12
    );
    assert!(notes.is_empty(), "{notes:?}");
    // White vertices everywhere: 1.0 is clamped to the documented maximum and counted.
    let white = std::fs::read_to_string(data("tetra_ascii.ply"))
        .expect("fixture")
        .replace("255 0 0\n", "255 255 255\n")
        .replace("0 255 0\n", "255 255 255\n")
        .replace("0 0 255\n", "255 255 255\n");
    let dir = temp_files(&[("white.ply", white.as_bytes())]);
    let (s, notes) = load_noted(&dir.path().join("white.ply")).expect("loads");
    assert_eq!(s.reflectance(0), DVec3::splat(MAX_COLOUR_REFLECTANCE));
    assert_eq!(notes.clamped_colour_faces, 4);
}

#[test]
fn truncated_ply_is_a_clear_error() {
    let ascii = std::fs::read_to_string(data("tetra_ascii.ply")).expect("fixture");
    let cut = &ascii[..ascii.find("3 0 3 2").expect("face")];
    let (e, s) = error_of(load_files(&[("cut.ply", cut.as_bytes())]));
    assert!(s.contains("cut.ply") && s.contains("cut short"), "{s}");
    assert!(line_of(&e) >= 17, "{s}");
    for big in [false, true] {
        let bin = binary_ply(big);
        let (_, s) = error_of(load_files(&[("cut.ply", &bin[..bin.len() - 7])]));
        assert!(s.contains("cut short") && s.contains("face"), "{s}");
        let header_end = bin
            .windows(11)
            .position(|w| w == b"end_header\n")
            .expect("header")
            + 11;
        let (_, s) = error_of(load_files(&[("cut.ply", &bin[..header_end + 20])]));
        assert!(s.contains("cut short") && s.contains("vertex"), "{s}");
    }
    let (_, s) = error_of(load_files(&[("cut.ply", &ascii.as_bytes()[..40])]));
    assert!(s.contains("cut.ply") && s.contains("header"), "{s}");
}

#[test]
fn ply_bad_values_name_the_line() {
    let ascii = std::fs::read_to_string(data("tetra_ascii.ply")).expect("fixture");
    let nan = ascii.replace("0 1 0 0 0 255", "0 nan 0 0 0 255");
    let (e, s) = error_of(load_files(&[("nan.ply", nan.as_bytes())]));
    assert_eq!(line_of(&e), 16, "{s}");
    assert!(s.contains("vertex"), "{s}");
    // Binary files can hold a NaN: named by its vertex number.
    let mut bin = binary_ply(false);
    let at = bin
        .windows(11)
        .position(|w| w == b"end_header\n")
        .expect("header")
        + 11
        + 2 * 15
        + 4;
    bin[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    let (_, s) = error_of(load_files(&[("nan.ply", &bin)]));
    assert!(s.contains("vertex 2") && s.contains("finite"), "{s}");
    let bad = ascii.replace("3 1 2 3", "3 1 2 4");
    let (e, s) = error_of(load_files(&[("idx.ply", bad.as_bytes())]));
    assert_eq!(line_of(&e), 21, "{s}");
    assert!(s.contains("out of range"), "{s}");
}

// ---------------------------------------------------------------- OFF

#[test]
fn off_tetrahedron_reads_with_its_face_colour() {
    let (s, notes) = load_noted(&data("tetra.off")).expect("loads");
    assert_eq!(s.face_count(), 4);
    assert_watertight(&s, 0..4);
    assert!(vector_area(&s, 0..4).length() < 1e-12);
    let c = DVec3::splat(0.25);
    assert!(s.faces.iter().all(|f| f.normal.dot(f.centroid - c) > 0.0));
    assert_eq!(s.reflectance(0), DVec3::splat(0.5));
    assert_eq!(
        s.reflectance(3),
        dvec3(MAX_COLOUR_REFLECTANCE, 128.0 / 255.0, 0.0)
    );
    assert_eq!(notes.default_material_faces, 3);
    assert_eq!(notes.clamped_colour_faces, 1);
}

#[test]
fn off_errors_name_the_line() {
    let text = std::fs::read_to_string(data("tetra.off")).expect("fixture");
    let cut = &text[..text.find("3 0 3 2").expect("face")];
    let (e, s) = error_of(load_files(&[("cut.off", cut.as_bytes())]));
    assert!(s.contains("cut short") && s.contains("face 3 of 4"), "{s}");
    assert_eq!(line_of(&e), cut.lines().count(), "{s}");
    let (e, s) = error_of(load_files(&[(
        "nan.off",
        text.replace("0 1 0\n", "0 NaN 0\n").as_bytes(),
    )]));
    assert_eq!(line_of(&e), 6, "{s}");
    let (e, s) = error_of(load_files(&[(
        "idx.off",
        text.replace("3 0 1 3", "3 0 1 4").as_bytes(),
    )]));
    assert_eq!(line_of(&e), 9, "{s}");
    assert!(s.contains("out of range"), "{s}");
    let (e, s) = error_of(load_files(&[(
        "short.off",
        text.replace("3 0 1 3", "3 0 1").as_bytes(),
    )]));
    assert_eq!(line_of(&e), 9, "{s}");
    let (e, s) = error_of(load_files(&[("hdr.off", b"PLY\n3 1 0\n")]));
    assert_eq!(line_of(&e), 1, "{s}");
    assert!(s.contains("OFF"), "{s}");
}

// ---------------------------------------------------------------- specs

#[test]
fn unknown_extension_builtin_and_parameter_are_errors_listing_the_choices() {
    let e = load_scene("room.blend").expect_err("error").to_string();
    assert!(e.contains(".blend") || e.contains("'blend'"), "{e}");
    assert!(e.contains(".toml") && e.contains(".obj") && e.contains(".ply") && e.contains(".off"));
    let e = load_scene("builtin:cornel").expect_err("error").to_string();
    assert!(e.contains("cornell") && e.contains("bumpy-sphere"), "{e}");
    let e = load_scene("builtin:cornell?lights=2")
        .expect_err("error")
        .to_string();
    assert!(e.contains("lights") && e.contains("light"), "{e}");
    let e = load_scene("builtin:terrain?faces=10")
        .expect_err("error")
        .to_string();
    assert!(e.contains("faces"), "{e}");
    let e = load_scene("builtin:furnace-sphere?reflectance=1")
        .expect_err("error")
        .to_string();
    assert!(e.contains("reflectance"), "{e}");
    let (_, s) = error_of(load(&data("no-such-file.obj")));
    assert!(s.contains("no-such-file.obj"), "{s}");
}

// ---------------------------------------------------------------- builtins

#[test]
fn cornell_box_matches_the_published_data() {
    let s = load_scene("builtin:cornell").expect("cornell");
    // Floor: a trapezoid with parallel sides 552.8 (z = 0) and 549.6 (z = 559.2), height 559.2.
    let floor: f64 = (0..s.face_count())
        .filter(|&f| s.faces[f].centroid.y.abs() < 1e-9)
        .map(|f| s.faces[f].area)
        .sum();
    assert!(
        (floor - 0.5 * (552.8 + 549.6) * 559.2).abs() < 1e-6,
        "{floor}"
    );
    let lights = s.emitters();
    let light: f64 = lights.iter().map(|&f| s.faces[f].area).sum();
    assert!((light - 130.0 * 105.0).abs() < 1e-9, "{light}");
    assert!(lights.iter().all(|&f| s.faces[f].normal.y < -0.999999));
    // Ceiling + light = the published 556.0 × 559.2 ceiling.
    let ceiling: f64 = (0..s.face_count())
        .filter(|&f| (s.faces[f].centroid.y - 548.8).abs() < 1e-9)
        .map(|f| s.faces[f].area)
        .sum();
    assert!((ceiling - 556.0 * 559.2).abs() < 1e-6, "{ceiling}");
    // Room faces look into the box, block faces out of their block. Faces come in the published order:
    // floor, light, ceiling (4), back, right, left (2), short block (5), tall block (5).
    let inside = dvec3(278.0, 274.4, 279.6);
    let short_c = dvec3(185.5, 82.5, 169.0);
    let tall_c = dvec3(368.5, 165.0, 351.25);
    for (f, face) in s.faces.iter().enumerate() {
        let c = face.centroid;
        let d = match f {
            0..10 => inside - c,
            10..15 => c - short_c,
            _ => c - tall_c,
        };
        assert!(
            face.normal.dot(d) > 0.0,
            "face {f} at {c} faces {}",
            face.normal
        );
    }
    // 6 room sides (ceiling as 4 quads, left wall as 2 triangles) + light + 2 × 5 block faces.
    assert_eq!(s.face_count(), 1 + 1 + 4 + 1 + 1 + 2 + 10);
    let cam = s.camera.as_ref().expect("camera");
    assert_eq!(cam.eye, dvec3(278.0, 273.0, -800.0));
    assert!(((cam.target - cam.eye).normalize() - DVec3::Z).length() < 1e-12);
    let fov = 2.0 * (12.5f64 / 35.0).atan() * 180.0 / PI;
    assert!((cam.fov_y_deg - fov).abs() < 1e-9 && (fov - 39.3077).abs() < 1e-3);
    assert_eq!((cam.width, cam.height), (256, 256));
    // Tessellation keeps areas and splits every piece into n².
    let t = load_scene("builtin:cornell?tessellation=3&width=64&height=32").expect("cornell");
    assert_eq!(t.face_count(), 9 * s.face_count());
    assert!((t.total_area() - s.total_area()).abs() < 1e-6 * s.total_area());
    assert_eq!(
        t.camera.as_ref().map(|c| (c.width, c.height)),
        Some((64, 32))
    );
}

#[test]
fn cornell_colours_match_an_independent_spectral_integration() {
    // colour-science 0.4.7: sd_to_XYZ(ρ·S, CIE 1931 2° at 1 nm, k = 1/106.856895), XYZ → sRGB (IEC matrix),
    // ratio to the light's RGB; light radiance RGB likewise.
    let [white, green, red] = radlab_scene::builtin::cornell_reflectances();
    let refs = [
        (white, dvec3(0.738615, 0.735408, 0.750600)),
        (green, dvec3(0.118687, 0.383054, 0.023703)),
        (red, dvec3(0.451354, 0.035633, 0.011566)),
    ];
    for (got, want) in refs {
        assert!((got - want).abs().max_element() < 1.5e-3, "{got} vs {want}");
    }
    let e = radlab_scene::builtin::cornell_light_exitance();
    let want = PI * dvec3(20.791526, 10.848415, 2.770333);
    assert!(
        ((e - want) / want).abs().max_element() < 5e-3,
        "{e} vs {want}"
    );
    let s = load_scene("builtin:cornell?light=2").expect("cornell");
    let l = s.emitters()[0];
    assert!((s.emission(l) - 2.0 * e).abs().max_element() < 1e-12);
    assert_eq!(s.reflectance(faces_with(&s, "red")[0]), red);
    // The red wall is on the left of the image: camera right is −x, so red is at large x.
    assert!(s.faces[faces_with(&s, "red")[0]].centroid.x > 500.0);
    assert!(s.faces[faces_with(&s, "green")[0]].centroid.x < 1.0);
}

#[test]
fn furnace_sphere_is_closed_and_faces_its_centre() {
    let s = load_scene("builtin:furnace-sphere?tessellation=5&radius=3&reflectance=0.9&emission=2")
        .expect("furnace sphere");
    assert_eq!(s.face_count(), 12 * 25);
    assert!(vector_area(&s, 0..s.face_count()).length() < 1e-9);
    assert_watertight(&s, 0..s.face_count());
    assert!(s.faces.iter().all(|f| f.normal.dot(-f.centroid) > 0.0));
    assert!(s.materials.len() == 1 && s.materials[0].reflectance == DVec3::splat(0.9));
    let ratio = s.total_area() / (4.0 * PI * 9.0);
    assert!(ratio < 1.0 && ratio > 0.95, "{ratio}");
}

#[test]
fn detailed_families_hit_their_face_counts() {
    for k in [100, 137, 1000, 20_000] {
        for family in ["bumpy-sphere", "terrain", "polygon-soup"] {
            let s = load_scene(&format!("builtin:{family}?faces={k}")).expect("builds");
            let got = s.face_count() as f64;
            assert!((got / k as f64 - 1.0).abs() <= 0.1, "{family} k={k}: {got}");
        }
    }
}

#[test]
fn polygon_soup_is_unconnected_inside_the_room_facing_every_way_and_seeded() {
    let s = load_scene("builtin:polygon-soup?faces=4010").expect("builds");
    let soup = faces_with(&s, "soup");
    assert_eq!(soup.len(), 4000);
    // No two triangles share a vertex index: a soup, not a mesh.
    let mut seen = std::collections::HashSet::new();
    for &f in &soup {
        for &i in s.faces[f].indices.iter().filter(|&&i| i != u32::MAX) {
            assert!(seen.insert(i), "vertex {i} shared");
        }
    }
    // Inside the room, above the floor, below 1.2 + the largest circumradius (1.5 × 0.04).
    for &f in &soup {
        for v in s.polygon(f).vertices() {
            assert!(
                v.x.abs() < 2.0 && v.z.abs() < 2.0 && v.y > 0.0 && v.y < 1.26,
                "{v}"
            );
        }
    }
    // Facing directions uniform on the sphere: the mean unit normal of n of them has standard deviation
    // 1/sqrt(3 n) per axis (0.009 here); the mean of n_y^2 is 1/3 with standard deviation about 0.0047.
    let n = soup.len() as f64;
    let mean: DVec3 = soup.iter().map(|&f| s.faces[f].normal).sum::<DVec3>() / n;
    assert!(mean.abs().max_element() < 0.04, "{mean}");
    let y2 = soup
        .iter()
        .map(|&f| s.faces[f].normal.y.powi(2))
        .sum::<f64>()
        / n;
    assert!((y2 - 1.0 / 3.0).abs() < 0.02, "{y2}");
    // Same seed, same soup; another seed, another.
    let again = load_scene("builtin:polygon-soup?faces=4010").expect("builds");
    assert_eq!(s.vertices, again.vertices);
    let other = load_scene("builtin:polygon-soup?faces=4010&seed=2").expect("builds");
    assert_ne!(s.vertices, other.vertices);
}

#[test]
fn bumpy_sphere_is_closed_outward_above_the_floor_and_seeded() {
    let s = load_scene("builtin:bumpy-sphere?faces=3000&bumpiness=0.3").expect("builds");
    let sphere = faces_with(&s, "sphere");
    assert!(sphere.len() > 2500);
    let total: f64 = sphere.iter().map(|&f| s.faces[f].area).sum();
    assert!(vector_area(&s, sphere.iter().copied()).length() < 1e-9 * total);
    assert_watertight(&s, sphere.iter().copied());
    let centre = sphere
        .iter()
        .map(|&f| s.faces[f].centroid * s.faces[f].area)
        .sum::<DVec3>()
        / total;
    assert!(
        sphere
            .iter()
            .all(|&f| s.faces[f].normal.dot(s.faces[f].centroid - centre) > 0.0)
    );
    let lowest = sphere
        .iter()
        .flat_map(|&f| s.polygon(f).vertices().to_vec())
        .map(|v| v.y)
        .fold(f64::INFINITY, f64::min);
    assert!(lowest > 0.0, "sphere touches the floor: {lowest}");
    // The bumps make the radius vary.
    let radii: Vec<f64> = sphere
        .iter()
        .map(|&f| (s.faces[f].centroid - centre).length())
        .collect();
    let (lo, hi) = radii
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &r| (a.min(r), b.max(r)));
    assert!(hi / lo > 1.1, "{lo} {hi}");
    // Room: light faces down, walls face in.
    let light = s.emitters();
    assert_eq!(light.len(), 1);
    assert!(s.faces[light[0]].normal.y < -0.999);
    let room_c = dvec3(0.0, 1.5, 0.0);
    for f in faces_with(&s, "walls") {
        assert!(s.faces[f].normal.dot(room_c - s.faces[f].centroid) > 0.0);
    }
    let again = load_scene("builtin:bumpy-sphere?faces=3000&bumpiness=0.3").expect("builds");
    assert_eq!(s.vertices, again.vertices);
    let other = load_scene("builtin:bumpy-sphere?faces=3000&bumpiness=0.3&seed=2").expect("builds");
    assert_ne!(s.vertices, other.vertices);
}

#[test]
fn terrain_faces_up_under_a_light_facing_down() {
    let s = load_scene("builtin:terrain?faces=2000&relief=2").expect("builds");
    let ground = faces_with(&s, "ground");
    assert!(ground.iter().all(|&f| s.faces[f].normal.y > 0.0));
    let light = s.emitters();
    assert_eq!(light.len(), 1);
    assert!(s.faces[light[0]].normal.y < -0.999);
    let top = s.vertices.iter().map(|v| v.y).fold(f64::MIN, f64::max);
    assert!(s.faces[light[0]].centroid.y >= top);
    let again = load_scene("builtin:terrain?faces=2000&relief=2").expect("builds");
    assert_eq!(s.vertices, again.vertices);
    let other = load_scene("builtin:terrain?faces=2000&relief=2&seed=9").expect("builds");
    assert_ne!(s.vertices, other.vertices);
}

// ---------------------------------------------------------------- scenes/

#[test]
fn every_example_scene_loads() {
    let mut count = 0;
    for entry in std::fs::read_dir(scenes_dir()).expect("scenes/") {
        let path = entry.expect("entry").path();
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
        if ["toml", "obj", "ply", "off"].contains(&ext) {
            let s = load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            assert!(s.face_count() > 0);
            count += 1;
        }
    }
    assert!(count >= 3, "only {count} example scenes");
}

#[test]
fn the_obj_furnace_cube_is_closed_inward_and_uniform() {
    let s = load(&scenes_dir().join("furnace-cube.obj")).expect("loads");
    assert!(vector_area(&s, 0..s.face_count()).length() < 1e-9);
    assert_watertight(&s, 0..s.face_count());
    let c = s.faces.iter().map(|f| f.centroid * f.area).sum::<DVec3>() / s.total_area();
    assert!(s.faces.iter().all(|f| f.normal.dot(c - f.centroid) > 0.0));
    for f in 0..s.face_count() {
        assert_eq!(s.reflectance(f), DVec3::splat(0.999));
        assert_eq!(s.emission(f), DVec3::ONE);
    }
}

#[test]
fn the_readme_example_is_room_toml_and_every_builtin_is_documented() {
    let readme = std::fs::read_to_string(scenes_dir().join("README.md")).expect("README");
    let room = std::fs::read_to_string(scenes_dir().join("room.toml")).expect("room.toml");
    let block = readme
        .split("```toml\n")
        .nth(1)
        .and_then(|rest| rest.split("```").next())
        .expect("a toml block in the README");
    assert_eq!(
        block, room,
        "scenes/README.md's example differs from room.toml"
    );
    for info in radlab_scene::builtin::builtins() {
        assert!(
            readme.contains(&format!("| `{}` |", info.name)),
            "{} is not in scenes/README.md",
            info.name
        );
    }
}

#[test]
#[should_panic(expected = "not twice")]
fn the_watertightness_check_catches_an_open_surface() {
    let s = load_scene("builtin:parallel-squares").expect("builds");
    assert_watertight(&s, 0..s.face_count());
}

/// A unit square in two `g` groups (two triangles each), with its top-right corner repeated as an extra `v`
/// line: tobj re-indexes vertices per group, and the loader welds equal positions back into one index, so
/// the faces on both sides of the group boundary share their edge.
#[test]
fn obj_groups_keep_connectivity_by_welding_equal_positions() {
    let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\nv 1 1 -0\n\
               g left\nf 1 2 3\nf 1 3 4\ng right\nf 2 5 6\nf 2 6 7\n";
    let s = load_files(&[("groups.obj", obj.as_bytes())]).expect("loads");
    assert_eq!(s.face_count(), 4);
    // 6 distinct positions (−0 welds with +0), so the right group's two triangles meet the left one's.
    assert_eq!(s.vertices.len(), 6);
    let adj = s.edge_adjacency();
    // A 2 × 1 strip of four triangles: 9 edges, 6 on the boundary, 3 shared by exactly two faces.
    assert_eq!(adj.edge_count(), 9);
    assert_eq!(adj.boundary_edge_count(), 6);
    assert_eq!(adj.non_manifold_edge_count(), 0);
    let pairs: Vec<(FaceId, FaceId)> = adj.manifold_pairs().map(|(_, a, b)| (a, b)).collect();
    assert_eq!(pairs.len(), 3);
    // The edge between the groups, x = 1, joins a face of each group.
    let across = adj
        .edges()
        .find(|e| e.vertices.iter().all(|&v| s.vertices[v as usize].x == 1.0))
        .expect("the shared edge x = 1");
    assert_eq!(across.faces.len(), 2);
    assert!(across.faces[0] < 2 && across.faces[1] >= 2, "{across:?}");
}

#[test]
fn closed_scenes_are_told_from_open_ones() {
    for (spec, closed) in [
        ("furnace-cube?tessellation=3", true),
        ("furnace-sphere?tessellation=2", true),
        ("cornell", false),
        ("perpendicular-squares", false),
        ("terrain?faces=200", false),
    ] {
        let s = radlab_scene::builtin(spec).expect("scene");
        assert_eq!(s.is_closed(), closed, "{spec}");
    }
}

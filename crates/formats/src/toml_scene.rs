//! radlab's TOML scene description (the format is documented with a complete example in `scenes/README.md`):
//! `[materials.NAME]` tables (reflectance ρ ∈ [0, 1) and emission E as radiant exitance in W/m², each grey or
//! [r, g, b]), an optional `[camera]`, and `[[objects]]` of type `polygon`, `quad`, `box`, `sphere`,
//! `heightfield` (alias `terrain`) or `mesh` (an OBJ, PLY or OFF file relative to the TOML file), each with an
//! optional `transform` (scale, then rotate about an axis by degrees, then translate).
//!
//! Unknown keys anywhere are errors naming the key; every error names the file and the line (from the span
//! toml gives, or the line where the offending table starts).

use std::collections::BTreeMap;
use std::fmt;
use std::path::Path;

use glam::DVec3;
use serde::Deserialize;
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use toml::Spanned;

use crate::transform::Transform;
use crate::{LoadNotes, add_mesh, line_at, merge_notes, parse_error, read_bytes, read_mesh};
use radlab_scene::builtin::primitives::{
    Fractal, add_box, add_cube_sphere, add_height_field, add_subdivided, fractal_heights,
};
use radlab_scene::{Camera, Material, Scene, SceneBuilder, SceneError};

/// A grey value or an `[x, y, z]` triple (colours, per-axis scales).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Triple(DVec3);

impl<'de> Deserialize<'de> for Triple {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Triple;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number or an array of three numbers [r, g, b]")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Triple, E> {
                Ok(Triple(DVec3::splat(v)))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Triple, E> {
                Ok(Triple(DVec3::splat(v as f64)))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Triple, E> {
                Ok(Triple(DVec3::splat(v as f64)))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Triple, A::Error> {
                let mut c = [0.0; 3];
                for (k, slot) in c.iter_mut().enumerate() {
                    *slot = seq
                        .next_element::<f64>()?
                        .ok_or_else(|| de::Error::invalid_length(k, &self))?;
                }
                if seq.next_element::<f64>()?.is_some() {
                    return Err(de::Error::invalid_length(4, &self));
                }
                Ok(Triple(DVec3::from(c)))
            }
        }
        d.deserialize_any(V)
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneDef {
    name: Option<String>,
    #[serde(default)]
    materials: BTreeMap<String, Spanned<MaterialDef>>,
    camera: Option<Spanned<CameraDef>>,
    #[serde(default)]
    objects: Vec<Spanned<ObjectDef>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialDef {
    reflectance: Spanned<Triple>,
    emission: Option<Spanned<Triple>>,
}

fn default_up() -> [f64; 3] {
    [0.0, 1.0, 0.0]
}

fn default_pixels() -> u32 {
    256
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraDef {
    eye: [f64; 3],
    target: [f64; 3],
    #[serde(default = "default_up")]
    up: [f64; 3],
    fov: f64,
    #[serde(default = "default_pixels")]
    width: u32,
    #[serde(default = "default_pixels")]
    height: u32,
}

fn default_roughness() -> f64 {
    0.5
}

fn default_amplitude() -> f64 {
    1.0
}

fn default_octaves() -> usize {
    6
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FractalDef {
    cells: [usize; 2],
    #[serde(default = "default_amplitude")]
    amplitude: f64,
    #[serde(default = "default_roughness")]
    roughness: f64,
    #[serde(default = "default_octaves")]
    octaves: usize,
    seed: u64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RotateDef {
    axis: [f64; 3],
    angle: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TransformDef {
    scale: Option<Triple>,
    rotate: Option<RotateDef>,
    translate: Option<[f64; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectDef {
    #[serde(rename = "type")]
    kind: String,
    material: Option<String>,
    points: Option<Vec<[f64; 3]>>,
    min: Option<[f64; 3]>,
    max: Option<[f64; 3]>,
    inward: Option<bool>,
    center: Option<[f64; 3]>,
    radius: Option<f64>,
    subdivisions: Option<usize>,
    corner: Option<[f64; 3]>,
    size: Option<[f64; 2]>,
    heights: Option<Vec<Vec<f64>>>,
    fractal: Option<FractalDef>,
    flip: Option<bool>,
    file: Option<String>,
    transform: Option<TransformDef>,
}

/// Generates one object's faces into a builder, with the given material index.
type Generator = Box<dyn FnOnce(&mut SceneBuilder, u32) -> Result<usize, SceneError>>;

/// Object types and the keys each accepts (besides `type`).
const OBJECT_KEYS: [(&str, &[&str]); 7] = [
    (
        "polygon",
        &["material", "points", "subdivisions", "transform"],
    ),
    ("quad", &["material", "points", "subdivisions", "transform"]),
    (
        "box",
        &[
            "material",
            "min",
            "max",
            "inward",
            "subdivisions",
            "transform",
        ],
    ),
    (
        "sphere",
        &[
            "material",
            "center",
            "radius",
            "subdivisions",
            "inward",
            "transform",
        ],
    ),
    (
        "heightfield",
        &[
            "material",
            "corner",
            "size",
            "heights",
            "fractal",
            "flip",
            "transform",
        ],
    ),
    (
        "terrain",
        &[
            "material",
            "corner",
            "size",
            "heights",
            "fractal",
            "flip",
            "transform",
        ],
    ),
    ("mesh", &["material", "file", "transform"]),
];

/// Largest `subdivisions` accepted (a sphere of 12 × 1024² ≈ 12.6 million triangles).
pub const MAX_SUBDIVISIONS: usize = 1024;

/// Default subdivisions of a sphere (cells per cube-face edge: 12 n² = 768 triangles).
pub const DEFAULT_SPHERE_SUBDIVISIONS: usize = 8;

impl ObjectDef {
    fn present_keys(&self) -> Vec<&'static str> {
        let mut k = Vec::new();
        let mut add = |name: &'static str, present: bool| {
            if present {
                k.push(name);
            }
        };
        add("material", self.material.is_some());
        add("points", self.points.is_some());
        add("min", self.min.is_some());
        add("max", self.max.is_some());
        add("inward", self.inward.is_some());
        add("center", self.center.is_some());
        add("radius", self.radius.is_some());
        add("subdivisions", self.subdivisions.is_some());
        add("corner", self.corner.is_some());
        add("size", self.size.is_some());
        add("heights", self.heights.is_some());
        add("fractal", self.fractal.is_some());
        add("flip", self.flip.is_some());
        add("file", self.file.is_some());
        add("transform", self.transform.is_some());
        k
    }
}

/// Where errors point: the file and its text.
struct Source<'a> {
    path: &'a Path,
    text: &'a str,
}

impl Source<'_> {
    fn line(&self, offset: usize) -> usize {
        line_at(self.text.as_bytes(), offset)
    }

    fn error(&self, offset: usize, message: impl Into<String>) -> SceneError {
        parse_error(self.path, self.line(offset), message)
    }
}

/// Loads a TOML scene.
pub fn load_toml_scene(path: &Path) -> Result<(Scene, LoadNotes), SceneError> {
    let bytes = read_bytes(path)?;
    let text = String::from_utf8(bytes).map_err(|e| {
        let line = line_at(e.as_bytes(), e.utf8_error().valid_up_to());
        parse_error(path, line, "the file is not valid UTF-8 text")
    })?;
    parse_toml_scene(&text, path)
}

/// Parses TOML scene text; `path` names the file in errors and anchors relative mesh paths.
pub fn parse_toml_scene(text: &str, path: &Path) -> Result<(Scene, LoadNotes), SceneError> {
    let src = Source { path, text };
    let def: SceneDef = toml::from_str(text).map_err(|e| {
        let line = e.span().map_or(0, |s| src.line(s.start));
        parse_error(path, line, e.message().trim().to_string())
    })?;
    let name = def.name.clone().unwrap_or_else(|| {
        path.file_stem()
            .map_or_else(|| "scene".to_string(), |s| s.to_string_lossy().into_owned())
    });
    let mut b = SceneBuilder::new(&name);
    let mut notes = LoadNotes::default();

    // Materials, in file order.
    let mut mats: Vec<(&String, &Spanned<MaterialDef>)> = def.materials.iter().collect();
    mats.sort_by_key(|(_, m)| m.span().start);
    let mut materials: BTreeMap<String, (u32, Material)> = BTreeMap::new();
    for (mname, m) in mats {
        let rho = m.get_ref().reflectance.get_ref().0;
        let (e, e_at) = match &m.get_ref().emission {
            Some(e) => (e.get_ref().0, e.span().start),
            None => (DVec3::ZERO, m.span().start),
        };
        let material = Material::new(mname, rho, e).map_err(|err| {
            let at = match &err {
                SceneError::Invalid { field, .. } if field.ends_with("emission") => e_at,
                _ => m.get_ref().reflectance.span().start,
            };
            src.error(at, strip_invalid(err))
        })?;
        let idx = b.add_material(material.clone())?;
        materials.insert(mname.clone(), (idx, material));
    }

    if let Some(c) = &def.camera {
        let cd = c.get_ref();
        let camera = Camera {
            eye: DVec3::from(cd.eye),
            target: DVec3::from(cd.target),
            up: DVec3::from(cd.up),
            fov_y_deg: cd.fov,
            width: cd.width,
            height: cd.height,
        };
        camera.validate().map_err(|e| {
            let text = strip_invalid(e);
            let text = text.strip_prefix("camera.").unwrap_or(&text);
            src.error(c.span().start, format!("[camera] {text}"))
        })?;
        b.set_camera(camera);
    }

    for (i, obj) in def.objects.iter().enumerate() {
        add_object(&src, &mut b, &materials, i, obj, &mut notes)?;
    }
    if b.face_count() == 0 {
        return Err(parse_error(
            path,
            0,
            "the scene has no usable faces: add [[objects]] (see scenes/README.md)",
        ));
    }
    Ok((b.build()?, notes))
}

/// "field: message" of a validation error, for re-wrapping with a file and line.
fn strip_invalid(e: SceneError) -> String {
    match e {
        SceneError::Invalid { field, message } => format!("{field}: {message}"),
        other => other.to_string(),
    }
}

fn add_object(
    src: &Source,
    b: &mut SceneBuilder,
    materials: &BTreeMap<String, (u32, Material)>,
    i: usize,
    obj: &Spanned<ObjectDef>,
    notes: &mut LoadNotes,
) -> Result<(), SceneError> {
    let at = obj.span().start;
    let o = obj.get_ref();
    let kind = o.kind.as_str();
    let label = format!("objects[{i}] ({kind})");
    let fail = |msg: String| src.error(at, format!("{label}: {msg}"));
    let Some((_, allowed)) = OBJECT_KEYS.iter().find(|(k, _)| *k == kind) else {
        let types: Vec<&str> = OBJECT_KEYS.iter().map(|(k, _)| *k).collect();
        return Err(src.error(
            at,
            format!(
                "objects[{i}]: unknown type '{kind}'; types are: {}",
                types.join(", ")
            ),
        ));
    };
    for key in o.present_keys() {
        if !allowed.contains(&key) {
            return Err(fail(format!(
                "key '{key}' does not apply to a {kind}; its keys are: type, {}",
                allowed.join(", ")
            )));
        }
    }
    let transform = match &o.transform {
        None => Transform::default(),
        Some(t) => {
            let mut tr = Transform::default();
            if let Some(s) = t.scale {
                tr.scale = s.0;
            }
            if let Some(r) = &t.rotate {
                tr.axis = DVec3::from(r.axis);
                tr.angle_deg = r.angle;
            }
            if let Some(p) = t.translate {
                tr.translate = DVec3::from(p);
            }
            tr.validate().map_err(|m| fail(format!("transform: {m}")))?;
            tr
        }
    };
    let what = format!("{}:{} {label}", src.path.display(), src.line(at));

    if kind == "mesh" {
        let Some(file) = &o.file else {
            return Err(fail(
                "missing key 'file' (an .obj, .ply or .off path, relative to this scene file)"
                    .into(),
            ));
        };
        let resolved = src.path.parent().unwrap_or(Path::new("")).join(file);
        if !resolved.is_file() {
            return Err(fail(format!(
                "mesh file '{file}' not found (looked for {}; paths are relative to the scene file's folder)",
                resolved.display()
            )));
        }
        let mesh = read_mesh(&resolved)?;
        let material = match &o.material {
            Some(m) => Some(material_of(materials, m).map_err(&fail)?.0),
            None => None,
        };
        let mut mesh_notes = mesh.notes.clone();
        if material.is_some() {
            mesh_notes.default_material_faces = 0;
        }
        add_mesh(b, &mesh, &transform, material, &what)?;
        merge_notes(notes, &mesh_notes);
        return Ok(());
    }

    let Some(mname) = &o.material else {
        return Err(fail(
            "missing key 'material' (every object names a material defined under [materials])"
                .into(),
        ));
    };
    let (mi, material) = material_of(materials, mname).map_err(&fail)?;
    let finite3 = |key: &str, v: [f64; 3]| -> Result<DVec3, SceneError> {
        let p = DVec3::from(v);
        if p.is_finite() {
            Ok(p)
        } else {
            Err(fail(format!(
                "'{key}' = [{}, {}, {}] must be finite numbers",
                p.x, p.y, p.z
            )))
        }
    };
    let required = |key: &str, v: Option<[f64; 3]>| -> Result<DVec3, SceneError> {
        let v = v.ok_or_else(|| fail(format!("missing key '{key}'")))?;
        finite3(key, v)
    };
    let n = o.subdivisions.unwrap_or(1);
    if o.subdivisions.is_some() && !(1..=MAX_SUBDIVISIONS).contains(&n) {
        return Err(fail(format!(
            "subdivisions = {n} must be in 1..={MAX_SUBDIVISIONS}"
        )));
    }

    let generate: Generator = match kind {
        "polygon" | "quad" => {
            let pts = o
                .points
                .as_ref()
                .ok_or_else(|| fail("missing key 'points'".into()))?;
            let mut p = Vec::with_capacity(pts.len());
            for &v in pts {
                p.push(finite3("points", v)?);
            }
            if kind == "quad" && p.len() != 4 {
                return Err(fail(format!(
                    "a quad has 4 points (corners in order), found {}",
                    p.len()
                )));
            }
            if p.len() < 3 {
                return Err(fail(format!(
                    "a polygon needs at least 3 points, found {}",
                    p.len()
                )));
            }
            if n > 1 && p.len() > 4 {
                return Err(fail(
                    "subdivisions apply to triangles and quads only".into(),
                ));
            }
            let w = what.clone();
            Box::new(move |b, m| add_subdivided(b, &p, n, m, &w))
        }
        "box" => {
            let lo = required("min", o.min)?;
            let hi = required("max", o.max)?;
            if !(lo.x < hi.x && lo.y < hi.y && lo.z < hi.z) {
                return Err(fail(format!(
                    "'min' {lo} must be below 'max' {hi} in every axis"
                )));
            }
            let inward = o.inward.unwrap_or(false);
            let w = what.clone();
            Box::new(move |b, m| add_box(b, lo, hi, n, inward, m, &w))
        }
        "sphere" => {
            let c = required("center", o.center)?;
            let r = o
                .radius
                .ok_or_else(|| fail("missing key 'radius'".into()))?;
            if !(r.is_finite() && r > 0.0) {
                return Err(fail(format!("radius = {r} must be a finite number > 0")));
            }
            let n = o.subdivisions.unwrap_or(DEFAULT_SPHERE_SUBDIVISIONS);
            let inward = o.inward.unwrap_or(false);
            let w = what.clone();
            Box::new(move |b, m| add_cube_sphere(b, c, r, [n; 3], inward, m, &|_| 1.0, &w))
        }
        _ => {
            // heightfield / terrain
            let corner = match o.corner {
                Some(v) => finite3("corner", v)?,
                None => DVec3::ZERO,
            };
            let size = o
                .size
                .ok_or_else(|| fail("missing key 'size' = [size_x, size_z]".into()))?;
            if !size.iter().all(|s| s.is_finite() && *s > 0.0) {
                return Err(fail(format!(
                    "size = [{}, {}] must be finite numbers > 0",
                    size[0], size[1]
                )));
            }
            let (nx, nz, h) = match (&o.heights, &o.fractal) {
                (Some(_), Some(_)) => {
                    return Err(fail("give either 'heights' or 'fractal', not both".into()));
                }
                (None, None) => {
                    return Err(fail(
                        "give 'heights' (rows of numbers) or 'fractal' = { cells = [nx, nz], seed = ... }"
                            .into(),
                    ));
                }
                (Some(rows), None) => {
                    let nz = rows.len().saturating_sub(1);
                    let nx = rows.first().map_or(0, |r| r.len().saturating_sub(1));
                    if nx < 1 || nz < 1 {
                        return Err(fail(
                            "'heights' needs at least 2 rows of at least 2 values".into(),
                        ));
                    }
                    let mut h = Vec::with_capacity((nx + 1) * (nz + 1));
                    for (r, row) in rows.iter().enumerate() {
                        if row.len() != nx + 1 {
                            return Err(fail(format!(
                                "'heights' row {r} has {} values, row 0 has {}; rows must be equally long",
                                row.len(),
                                nx + 1
                            )));
                        }
                        if let Some(v) = row.iter().find(|v| !v.is_finite()) {
                            return Err(fail(format!(
                                "'heights' row {r} holds {v}; heights must be finite"
                            )));
                        }
                        h.extend_from_slice(row);
                    }
                    (nx, nz, h)
                }
                (None, Some(f)) => {
                    let [nx, nz] = f.cells;
                    if !(1..=4096).contains(&nx) || !(1..=4096).contains(&nz) {
                        return Err(fail(format!(
                            "fractal cells = [{nx}, {nz}] must each be in 1..=4096"
                        )));
                    }
                    if !(f.amplitude.is_finite() && f.amplitude >= 0.0) {
                        return Err(fail(
                            "fractal amplitude must be a finite number >= 0".into(),
                        ));
                    }
                    if !(0.0..=1.0).contains(&f.roughness) {
                        return Err(fail("fractal roughness must be in [0, 1]".into()));
                    }
                    if !(1..=16).contains(&f.octaves) {
                        return Err(fail("fractal octaves must be in 1..=16".into()));
                    }
                    let h = fractal_heights(
                        nx,
                        nz,
                        &Fractal {
                            amplitude: f.amplitude,
                            roughness: f.roughness,
                            octaves: f.octaves,
                            seed: f.seed,
                        },
                    );
                    (nx, nz, h)
                }
            };
            let flip = o.flip.unwrap_or(false);
            let w = what.clone();
            Box::new(move |b, m| {
                add_height_field(b, corner, (size[0], size[1]), nx, nz, &h, flip, m, &w)
            })
        }
    };
    place(b, mi, material, &transform, &what, generate)?;
    Ok(())
}

fn material_of<'m>(
    materials: &'m BTreeMap<String, (u32, Material)>,
    name: &str,
) -> Result<(u32, &'m Material), String> {
    materials.get(name).map(|(i, m)| (*i, m)).ok_or_else(|| {
        let known: Vec<&str> = materials.keys().map(String::as_str).collect();
        format!(
            "material '{name}' is not defined; defined materials: {}",
            if known.is_empty() {
                "none (add a [materials.NAME] table)".to_string()
            } else {
                known.join(", ")
            }
        )
    })
}

/// Generates an object with `generate` and adds it to `b` through `t` (directly when `t` is the identity).
fn place(
    b: &mut SceneBuilder,
    material_index: u32,
    material: &Material,
    t: &Transform,
    what: &str,
    generate: Generator,
) -> Result<usize, SceneError> {
    if t.is_identity() {
        return generate(b, material_index);
    }
    let mut tmp = SceneBuilder::new(what);
    let m = tmp.add_material(material.clone())?;
    generate(&mut tmp, m)?;
    {
        let w = tmp.warnings_mut().clone();
        let main = b.warnings_mut();
        main.degenerate_faces += w.degenerate_faces;
        main.nonplanar_faces += w.nonplanar_faces;
        main.polygons_triangulated += w.polygons_triangulated;
    }
    if tmp.face_count() == 0 {
        return Ok(0);
    }
    let s = tmp.build()?;
    let base = b.vertex_count() as u32;
    let apply = t.applier();
    for &v in &s.vertices {
        b.add_vertex(apply(v), what)?;
    }
    let flip = t.reverses_orientation();
    let mut added = 0;
    let mut idx: Vec<u32> = Vec::with_capacity(4);
    for f in &s.faces {
        idx.clear();
        idx.extend(f.vertex_indices().iter().map(|&i| base + i));
        if flip {
            idx.reverse();
        }
        added += b.add_polygon(&idx, material_index, what)?;
    }
    Ok(added)
}

//! # radlab-formats
//!
//! Scene input: `load_scene` turns a scene spec into a validated [`Scene`]. A spec is `builtin:NAME[?k=v&...]`
//! (see [`radlab_scene::builtin()`]) or a path whose extension picks the format:
//!
//! | extension | format | reader |
//! |---|---|---|
//! | `.toml` | radlab scene description (materials, camera, objects; documented in `scenes/README.md`) | [`toml_scene`] |
//! | `.obj` | Wavefront OBJ with MTL materials (`Kd` → reflectance, `Ke` → emission as exitance, W/m²) | [`obj_mtl`] (tobj) |
//! | `.ply` | PLY, ASCII or binary either endianness; vertex or face colours → reflectance | [`ply_mesh`] (ply-rs-bw) |
//! | `.off` | Object File Format (the CGAL demo meshes) | [`off_mesh`] |
//! | `.mgf` | Materials and Geometry Format (the radiosity literature's scenes; includes, transforms, primitives) | [`mgf`] |
//!
//! Every error names the file and, where the format has lines, the line; nothing is half-built. Problems that
//! are not errors are counted: degenerate faces in [`radlab_scene::SceneWarnings`], the rest in [`LoadNotes`].

pub mod mgf;
pub mod obj_mtl;
pub mod off_mesh;
pub mod ply_mesh;
pub mod toml_scene;
pub mod transform;

use std::path::Path;

use glam::DVec3;

pub use transform::Transform;

use radlab_scene::{Material, Scene, SceneBuilder, SceneError};

/// Reflectance given to faces whose file assigns them no material (grey, per channel).
pub const DEFAULT_REFLECTANCE: f64 = 0.5;

/// Largest reflectance a colour (PLY, OFF) turns into: colours are clamped to [0, 0.99] per channel, so white
/// (255, 255, 255) becomes 0.99. Give materials explicitly (TOML `material` override) for other values.
pub const MAX_COLOUR_REFLECTANCE: f64 = 0.99;

/// Name of the material given to faces without one.
pub const DEFAULT_MATERIAL_NAME: &str = "default-grey";

/// Counted notes from loading that are not errors (the scene crate never prints; the runner reports them).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LoadNotes {
    /// Faces that had no material in their file and got [`DEFAULT_REFLECTANCE`] grey.
    pub default_material_faces: usize,
    /// MTL materials without `Kd`, given [`DEFAULT_REFLECTANCE`] grey.
    pub materials_without_kd: usize,
    /// Faces whose colour-derived reflectance was clamped to [0, [`MAX_COLOUR_REFLECTANCE`]].
    pub clamped_colour_faces: usize,
    /// OBJ point (`p`) and line (`l`) elements skipped: they are not surfaces.
    pub skipped_points_and_lines: usize,
    /// Entities read but not supported (MGF's specular and transmitting materials, for instance): one
    /// message each, naming the file and line of its first occurrence.
    pub unsupported: Vec<String>,
}

impl LoadNotes {
    /// Whether nothing was noted.
    pub fn is_empty(&self) -> bool {
        *self == Self::default()
    }

    fn add(&mut self, o: &LoadNotes) {
        self.default_material_faces += o.default_material_faces;
        self.materials_without_kd += o.materials_without_kd;
        self.clamped_colour_faces += o.clamped_colour_faces;
        self.skipped_points_and_lines += o.skipped_points_and_lines;
        for u in &o.unsupported {
            if !self.unsupported.contains(u) {
                self.unsupported.push(u.clone());
            }
        }
    }
}

/// The file extensions `load_scene` accepts.
pub const SCENE_EXTENSIONS: [&str; 5] = ["toml", "obj", "ply", "off", "mgf"];

/// Loads a scene from `builtin:NAME[?k=v&...]` or a `.toml`, `.obj`, `.ply`, `.off` or `.mgf` file.
pub fn load_scene(spec: &str) -> Result<Scene, SceneError> {
    load_scene_with_notes(spec).map(|(s, _)| s)
}

/// Like [`load_scene`], also returning the counted [`LoadNotes`].
pub fn load_scene_with_notes(spec: &str) -> Result<(Scene, LoadNotes), SceneError> {
    if let Some(rest) = spec.strip_prefix("builtin:") {
        return radlab_scene::builtin::builtin(rest).map(|s| (s, LoadNotes::default()));
    }
    let path = Path::new(spec);
    let ext = extension(path);
    match ext.as_str() {
        "toml" => toml_scene::load_toml_scene(path),
        "mgf" => mgf::load_mgf(path),
        "obj" | "ply" | "off" => {
            let mesh = read_mesh(path)?;
            let name = path
                .file_stem()
                .map_or_else(|| spec.to_string(), |s| s.to_string_lossy().into_owned());
            let mut b = SceneBuilder::new(&name);
            add_mesh(&mut b, &mesh, &Transform::default(), None, spec)?;
            Ok((b.build()?, mesh.notes))
        }
        _ => Err(SceneError::Invalid {
            field: spec.to_string(),
            message: format!(
                "unknown scene file extension '{}'; give a .toml, .obj, .ply, .off or .mgf file, or builtin:NAME \
                 (see `radlab scenes`)",
                if ext.is_empty() { "(none)" } else { &ext }
            ),
        }),
    }
}

fn extension(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

/// A polygon mesh read from a file, before it joins a scene.
#[derive(Clone, Debug, Default)]
pub struct PolygonMesh {
    /// Vertex positions (finite).
    pub positions: Vec<DVec3>,
    /// Vertex indices of all polygons, concatenated.
    pub indices: Vec<u32>,
    /// Polygon p is `indices[starts[p]..starts[p + 1]]`; `starts` has one more entry than there are polygons.
    pub starts: Vec<usize>,
    /// Material of each polygon, an index into `materials`.
    pub material_of: Vec<u32>,
    /// The mesh's materials.
    pub materials: Vec<Material>,
    /// Counted notes.
    pub notes: LoadNotes,
}

impl PolygonMesh {
    /// An empty mesh.
    pub fn new() -> Self {
        Self {
            starts: vec![0],
            ..Self::default()
        }
    }

    /// Number of polygons.
    pub fn polygon_count(&self) -> usize {
        self.starts.len().saturating_sub(1)
    }

    /// The vertex indices of polygon `p`.
    pub fn polygon(&self, p: usize) -> &[u32] {
        &self.indices[self.starts[p]..self.starts[p + 1]]
    }

    /// Appends a polygon (indices already checked against `positions`).
    pub fn push_polygon(&mut self, idx: &[u32], material: u32) {
        self.indices.extend_from_slice(idx);
        self.starts.push(self.indices.len());
        self.material_of.push(material);
    }

    /// Index of the default grey material, adding it on first use.
    pub fn default_material(&mut self) -> u32 {
        if let Some(i) = self
            .materials
            .iter()
            .position(|m| m.name == DEFAULT_MATERIAL_NAME)
        {
            return i as u32;
        }
        self.materials.push(Material {
            name: DEFAULT_MATERIAL_NAME.to_string(),
            reflectance: DVec3::splat(DEFAULT_REFLECTANCE),
            emission: DVec3::ZERO,
        });
        (self.materials.len() - 1) as u32
    }
}

/// Reads an OBJ, PLY or OFF mesh, by extension.
pub fn read_mesh(path: &Path) -> Result<PolygonMesh, SceneError> {
    match extension(path).as_str() {
        "obj" => obj_mtl::read_obj(path),
        "ply" => ply_mesh::read_ply(path),
        "off" => off_mesh::read_off(path),
        other => Err(SceneError::Invalid {
            field: path.display().to_string(),
            message: format!(
                "unknown mesh file extension '{other}'; meshes are .obj (with .mtl), .ply or .off files"
            ),
        }),
    }
}

/// Adds a mesh to a builder: positions through `transform` (winding reversed when it mirrors), every polygon
/// with `material` when given, otherwise with the mesh's own materials (added to the builder, named
/// `<what>/<name>` unless `what` is empty). Returns the number of faces added.
pub fn add_mesh(
    b: &mut SceneBuilder,
    mesh: &PolygonMesh,
    transform: &Transform,
    material: Option<u32>,
    what: &str,
) -> Result<usize, SceneError> {
    let mats: Vec<u32> = match material {
        Some(_) => Vec::new(),
        None => {
            let mut v = Vec::with_capacity(mesh.materials.len());
            for m in &mesh.materials {
                let mut m = m.clone();
                if b.material_index(&m.name).is_some() {
                    m.name = format!("{what}/{}", m.name);
                }
                v.push(b.add_material(m)?);
            }
            v
        }
    };
    let base = b.vertex_count() as u32;
    let place = transform.applier();
    for &p in &mesh.positions {
        b.add_vertex(place(p), what)?;
    }
    let flip = transform.reverses_orientation();
    let mut added = 0;
    let mut idx: Vec<u32> = Vec::with_capacity(8);
    for p in 0..mesh.polygon_count() {
        idx.clear();
        idx.extend(mesh.polygon(p).iter().map(|&i| base + i));
        if flip {
            idx.reverse();
        }
        let m = match material {
            Some(m) => m,
            None => mats
                .get(mesh.material_of[p] as usize)
                .copied()
                .ok_or_else(|| SceneError::Invalid {
                    field: what.to_string(),
                    message: format!("polygon {p} refers to a material that does not exist"),
                })?,
        };
        added += b.add_polygon(&idx, m, what)?;
    }
    Ok(added)
}

/// Reads a whole file, naming it in the error.
pub(crate) fn read_bytes(path: &Path) -> Result<Vec<u8>, SceneError> {
    std::fs::read(path).map_err(|source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// The 1-based line holding byte `offset` of `text`.
pub(crate) fn line_at(text: &[u8], offset: usize) -> usize {
    let end = offset.min(text.len());
    text[..end].iter().filter(|&&c| c == b'\n').count() + 1
}

/// A parse error at a file's line.
pub(crate) fn parse_error(path: &Path, line: usize, message: impl Into<String>) -> SceneError {
    SceneError::Parse {
        path: path.to_path_buf(),
        line,
        message: message.into(),
    }
}

/// A reflectance from a colour in [0, 1] per channel: clamped to [0, MAX_COLOUR_REFLECTANCE]; `clamped`
/// tells whether any channel moved.
pub(crate) fn colour_reflectance(c: DVec3) -> (DVec3, bool) {
    let r = c.clamp(DVec3::ZERO, DVec3::splat(MAX_COLOUR_REFLECTANCE));
    (r, r != c)
}

/// Turns per-face colours into deduplicated materials named `<prefix> rgb(r, g, b)`.
pub(crate) struct ColourMaterials {
    map: std::collections::HashMap<[u64; 3], u32>,
    prefix: String,
}

impl ColourMaterials {
    pub(crate) fn new(prefix: &str) -> Self {
        Self {
            map: std::collections::HashMap::new(),
            prefix: prefix.to_string(),
        }
    }

    /// The material index for colour `c` (channels in [0, 1] nominally), clamping and counting in `mesh.notes`.
    pub(crate) fn material(&mut self, mesh: &mut PolygonMesh, c: DVec3) -> u32 {
        let (rho, clamped) = colour_reflectance(c);
        if clamped {
            mesh.notes.clamped_colour_faces += 1;
        }
        let key = rho.to_array().map(f64::to_bits);
        if let Some(&m) = self.map.get(&key) {
            return m;
        }
        mesh.materials.push(Material {
            name: format!(
                "{} rgb({:.4}, {:.4}, {:.4})",
                self.prefix, rho.x, rho.y, rho.z
            ),
            reflectance: rho,
            emission: DVec3::ZERO,
        });
        let m = (mesh.materials.len() - 1) as u32;
        self.map.insert(key, m);
        m
    }
}

/// Adds notes of a sub-load to a total.
pub(crate) fn merge_notes(total: &mut LoadNotes, part: &LoadNotes) {
    total.add(part);
}

//! Wavefront OBJ meshes with MTL materials, read with tobj (polygons kept as they are: no triangulation).
//!
//! Materials: `Kd r g b` → reflectance ρ (each channel in [0, 1); `Kd 1 1 1` is an error: use 0.999), `Ke r g b`
//! → emission as radiant exitance E in W/m² (E = π × radiance; not a radiance), other statements ignored.
//! A single value (`Kd 0.5`) means grey. A material without `Kd` gets the default grey (counted); faces
//! after no `usemtl` get the default grey material (counted). `usemtl` of a name no MTL file defines is an
//! error, as are point (`p`) and line (`l`) elements only when they come from `f` lines with fewer than three
//! vertices (a file cut short); real `p`/`l` elements are skipped and counted.
//!
//! tobj reports no line numbers, so this reader counts the lines tobj has consumed when it fails, and scans
//! the file itself to name the line of a non-finite vertex or an out-of-range face index. Positions and
//! colours are read by tobj in double precision (its `use_f64` feature).
//!
//! tobj re-indexes vertices per `o`/`g` group and per `usemtl` run; this reader welds exactly equal positions
//! across the whole file (−0.0 and +0.0 alike), so a mesh split into groups keeps its connectivity: faces of
//! different groups that share an edge share its two vertex indices in the [`radlab_scene::Scene`].

use std::cell::RefCell;
use std::collections::HashMap;
use std::io::{BufRead, Read};
use std::path::Path;

use glam::DVec3;

use crate::{PolygonMesh, line_at, parse_error, read_bytes};
use radlab_scene::{Material, SceneError};

/// A `BufRead` over bytes that knows how far it has been read, so a parser's failure can be given a line.
struct CountingReader<'a> {
    data: &'a [u8],
    pos: usize,
}

impl<'a> CountingReader<'a> {
    fn new(data: &'a [u8]) -> Self {
        Self { data, pos: 0 }
    }

    /// The line of the last byte consumed (the line a line-by-line parser was working on).
    fn line(&self) -> usize {
        line_at(self.data, self.pos.saturating_sub(1))
    }
}

impl Read for CountingReader<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let rest = &self.data[self.pos..];
        let n = rest.len().min(buf.len());
        buf[..n].copy_from_slice(&rest[..n]);
        self.pos += n;
        Ok(n)
    }
}

impl BufRead for CountingReader<'_> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        Ok(&self.data[self.pos..])
    }

    fn consume(&mut self, amt: usize) {
        self.pos = (self.pos + amt).min(self.data.len());
    }
}

/// Lines of an MTL file's statements, per material, for error messages.
#[derive(Default)]
struct MtlLines {
    kd: Option<usize>,
    ke: Option<usize>,
}

/// Reads, checks and parses one MTL file: returns tobj's result, or the first problem (file and line).
fn load_mtl_checked(path: &Path) -> Result<tobj::MTLLoadResult, SceneError> {
    let bytes = read_bytes(path)?;
    let text = String::from_utf8_lossy(&bytes);
    // Normalise `Kd 0.5` to `Kd 0.5 0.5 0.5` (tobj wants three values), line for line, and note where each
    // material's Kd and Ke are.
    let mut normalised = String::with_capacity(text.len() + 64);
    let mut lines: Vec<(String, MtlLines)> = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let n = i + 1;
        let mut toks = line.split_whitespace();
        let key = toks.next().unwrap_or("");
        let vals: Vec<&str> = toks.collect();
        match key {
            "newmtl" => {
                let name = line.trim_start()[6..].trim().to_string();
                lines.push((name, MtlLines::default()));
                normalised.push_str(line);
            }
            "Ka" | "Kd" | "Ks" | "Ke" | "Tf" => {
                if vals
                    .first()
                    .is_some_and(|v| *v == "spectral" || *v == "xyz")
                {
                    return Err(parse_error(
                        path,
                        n,
                        format!(
                            "'{key} {}' is not supported; give three numbers r g b",
                            vals[0]
                        ),
                    ));
                }
                if let Some((_, l)) = lines.last_mut() {
                    match key {
                        "Kd" => l.kd = Some(n),
                        "Ke" => l.ke = Some(n),
                        _ => {}
                    }
                }
                match vals.len() {
                    1 => normalised.push_str(&format!("{key} {0} {0} {0}", vals[0])),
                    3 => normalised.push_str(line),
                    k => {
                        return Err(parse_error(
                            path,
                            n,
                            format!(
                                "'{key}' needs three numbers r g b (or one for grey), found {k}"
                            ),
                        ));
                    }
                }
            }
            _ => normalised.push_str(line),
        }
        normalised.push('\n');
    }
    let mut reader = CountingReader::new(normalised.as_bytes());
    let result = tobj::load_mtl_buf(&mut reader);
    let (materials, map) = match result {
        Ok(r) => r,
        Err(e) => {
            return Err(parse_error(
                path,
                reader.line(),
                format!("cannot read this material statement: {e}"),
            ));
        }
    };
    for m in &materials {
        let at = lines
            .iter()
            .rev()
            .find(|(name, _)| *name == m.name)
            .map(|(_, l)| l);
        if let Some(kd) = m.diffuse {
            let rho = DVec3::new(kd[0], kd[1], kd[2]);
            if !rho.to_array().iter().all(|c| (0.0..1.0).contains(c)) {
                return Err(parse_error(
                    path,
                    at.and_then(|l| l.kd).unwrap_or(0),
                    format!(
                        "material '{}': Kd {} {} {} is outside [0, 1); a diffuse reflectance must be at \
                         least 0 and below 1 (use 0.999 for a near-perfect reflector)",
                        m.name, rho.x, rho.y, rho.z
                    ),
                ));
            }
        }
        if let Some(ke) = m.emissive {
            let e = DVec3::new(ke[0], ke[1], ke[2]);
            if !e.to_array().iter().all(|c| c.is_finite() && *c >= 0.0) {
                return Err(parse_error(
                    path,
                    at.and_then(|l| l.ke).unwrap_or(0),
                    format!(
                        "material '{}': Ke {} {} {} must be finite and >= 0 (emission is radiant exitance, \
                         W/m²)",
                        m.name, e.x, e.y, e.z
                    ),
                ));
            }
        }
    }
    Ok(Ok((materials, map)))
}

/// Reads an OBJ file and the MTL files it names (relative to its folder).
pub fn read_obj(path: &Path) -> Result<PolygonMesh, SceneError> {
    let bytes = read_bytes(path)?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mtl_failure: RefCell<Option<SceneError>> = RefCell::new(None);
    let loader = |mtl: &Path| -> tobj::MTLLoadResult {
        let full = dir.join(mtl);
        match load_mtl_checked(&full) {
            Ok(r) => r,
            Err(e) => {
                let mut slot = mtl_failure.borrow_mut();
                if slot.is_none() {
                    *slot = Some(e);
                }
                Err(tobj::LoadError::OpenFileFailed)
            }
        }
    };
    // tobj's defaults are all off: polygons as they are (no triangulation), separate index streams, points
    // and lines kept (so they can be counted).
    let options = tobj::LoadOptions::default();
    let mut reader = CountingReader::new(&bytes);
    let result = tobj::load_obj_buf(&mut reader, &options, loader);
    if let Some(e) = mtl_failure.into_inner() {
        return Err(match e {
            SceneError::Io { path: mtl, source } => {
                let line = statements(&bytes)
                    .find(|(_, key, _)| *key == "mtllib")
                    .map_or(0, |(l, _, _)| l);
                parse_error(
                    path,
                    line,
                    format!(
                        "cannot read the material library {} named by 'mtllib' (paths are relative to the \
                         OBJ file's folder): {source}",
                        mtl.display()
                    ),
                )
            }
            other => other,
        });
    }
    let (models, materials) = match result {
        Ok(r) => r,
        Err(e) => return Err(obj_error(path, &bytes, e, reader.line())),
    };
    let materials = materials
        .map_err(|e| parse_error(path, 0, format!("cannot read its material library: {e}")))?;
    check_usemtl(path, &bytes, &materials)?;

    let mut mesh = PolygonMesh::new();
    for m in &materials {
        let rho = match m.diffuse {
            Some(kd) => DVec3::new(kd[0], kd[1], kd[2]),
            None => {
                mesh.notes.materials_without_kd += 1;
                DVec3::splat(super::DEFAULT_REFLECTANCE)
            }
        };
        let e = m
            .emissive
            .map_or(DVec3::ZERO, |ke| DVec3::new(ke[0], ke[1], ke[2]));
        let name = if m.name.is_empty() {
            "unnamed"
        } else {
            &m.name
        };
        mesh.materials.push(Material::new(name, rho, e)?);
    }
    let mut short_faces = 0usize;
    // tobj gives each `o`/`g` group (and each `usemtl` run) its own vertex array, so a vertex shared across
    // groups arrives once per group. Welding exactly equal positions over the whole file gives them one index
    // again, so faces on both sides of a group boundary share their edge (mesh connectivity survives).
    let mut welded: HashMap<[u64; 3], u32> = HashMap::new();
    let mut local: Vec<u32> = Vec::new();
    for model in &models {
        let m = &model.mesh;
        local.clear();
        for p in m.positions.chunks_exact(3) {
            let v = DVec3::new(p[0], p[1], p[2]);
            if !v.is_finite() {
                return Err(non_finite_vertex(path, &bytes));
            }
            // + 0.0 turns −0.0 into +0.0, so the two zeros weld.
            let key = (v + DVec3::ZERO).to_array().map(f64::to_bits);
            let next = mesh.positions.len() as u32;
            let id = *welded.entry(key).or_insert(next);
            if id == next {
                mesh.positions.push(v);
            }
            local.push(id);
        }
        let material = match m.material_id {
            Some(id) if id < mesh.materials.len() => id as u32,
            _ => mesh.default_material(),
        };
        let mut at = 0usize;
        let nfaces = if m.face_arities.is_empty() {
            m.indices.len() / 3
        } else {
            m.face_arities.len()
        };
        let mut idx: Vec<u32> = Vec::with_capacity(8);
        for f in 0..nfaces {
            let arity = m.face_arities.get(f).map_or(3, |&a| a as usize);
            let Some(face) = m.indices.get(at..at + arity) else {
                return Err(parse_error(
                    path,
                    0,
                    "the face list is inconsistent (is the file cut short?)",
                ));
            };
            at += arity;
            if arity < 3 {
                short_faces += 1;
                continue;
            }
            if m.material_id.is_none() {
                mesh.notes.default_material_faces += 1;
            }
            idx.clear();
            for &i in face {
                let Some(&v) = local.get(i as usize) else {
                    return Err(parse_error(
                        path,
                        0,
                        "a face refers to a vertex its group does not have (is the file cut short?)",
                    ));
                };
                idx.push(v);
            }
            mesh.push_polygon(&idx, material);
        }
    }
    if short_faces > 0 {
        if let Some(line) = first_short_face_line(&bytes) {
            return Err(parse_error(
                path,
                line,
                "this face has fewer than 3 vertices; a face needs at least 3 (is the file cut short?)",
            ));
        }
        mesh.notes.skipped_points_and_lines += short_faces;
    }
    if mesh.polygon_count() == 0 {
        return Err(parse_error(
            path,
            0,
            "the file has no faces ('f' lines with 3 or more vertices)",
        ));
    }
    Ok(mesh)
}

/// Lines of the OBJ text, 1-based, with their first token.
fn statements(bytes: &[u8]) -> impl Iterator<Item = (usize, &str, std::str::SplitWhitespace<'_>)> {
    bytes
        .split(|&c| c == b'\n')
        .enumerate()
        .filter_map(|(i, l)| {
            let l = std::str::from_utf8(l).ok()?;
            let mut toks = l.split_whitespace();
            let key = toks.next()?;
            Some((i + 1, key, toks))
        })
}

fn non_finite_vertex(path: &Path, bytes: &[u8]) -> SceneError {
    for (line, key, toks) in statements(bytes) {
        if key == "v" {
            let vals: Vec<f64> = toks.take(4).filter_map(|s| s.parse().ok()).collect();
            let w = vals.get(3).copied().unwrap_or(1.0);
            if vals.iter().take(3).any(|v| !(v / w).is_finite()) {
                return parse_error(
                    path,
                    line,
                    "this vertex is not finite (NaN or infinite); every \
                     coordinate must be a finite number",
                );
            }
        }
    }
    parse_error(
        path,
        0,
        "a vertex is not finite (NaN or infinite); every coordinate must be a finite number",
    )
}

fn first_short_face_line(bytes: &[u8]) -> Option<usize> {
    statements(bytes)
        .find(|(_, key, toks)| *key == "f" && toks.clone().count() < 3)
        .map(|(line, _, _)| line)
}

/// The line of the first face referring to a vertex that does not exist (yet).
fn first_bad_index_line(bytes: &[u8]) -> Option<(usize, String)> {
    let mut nv: i64 = 0;
    for (line, key, toks) in statements(bytes) {
        match key {
            "v" => nv += 1,
            "f" | "l" | "p" => {
                for t in toks {
                    let first = t.split('/').next().unwrap_or("");
                    let Ok(i) = first.parse::<i64>() else {
                        return Some((line, format!("'{t}' is not a vertex reference")));
                    };
                    let ok = (i > 0 && i <= nv) || (i < 0 && -i <= nv);
                    if !ok {
                        return Some((
                            line,
                            format!(
                                "vertex reference {i} is out of range ({nv} vertices defined so far; \
                                 OBJ counts from 1, negative values count back from the last)"
                            ),
                        ));
                    }
                }
            }
            _ => {}
        }
    }
    None
}

fn check_usemtl(path: &Path, bytes: &[u8], materials: &[tobj::Material]) -> Result<(), SceneError> {
    for (line, key, toks) in statements(bytes) {
        if key == "usemtl" {
            let name = toks.collect::<Vec<_>>().join(" ");
            if !materials.iter().any(|m| m.name == name) {
                let known: Vec<&str> = materials.iter().map(|m| m.name.as_str()).collect();
                return Err(parse_error(
                    path,
                    line,
                    format!(
                        "usemtl '{name}': no MTL file loaded by this OBJ defines it (defined: {})",
                        if known.is_empty() {
                            "none; is there an 'mtllib' line?".to_string()
                        } else {
                            known.join(", ")
                        }
                    ),
                ));
            }
        }
    }
    Ok(())
}

fn obj_error(path: &Path, bytes: &[u8], e: tobj::LoadError, line: usize) -> SceneError {
    use tobj::LoadError as E;
    match e {
        E::FaceVertexOutOfBounds
        | E::FaceTexCoordOutOfBounds
        | E::FaceNormalOutOfBounds
        | E::FaceColorOutOfBounds => match first_bad_index_line(bytes) {
            Some((l, msg)) => parse_error(path, l, msg),
            None => parse_error(
                path,
                line,
                format!(
                    "a face refers to data that does not exist ({e}), detected at the end of its group"
                ),
            ),
        },
        E::PositionParseError => parse_error(
            path,
            line,
            "a vertex ('v') needs three numbers x y z (is the file cut short?)",
        ),
        E::FaceParseError => parse_error(
            path,
            line,
            "a face ('f') has a vertex reference that is not a number (is the file cut short?)",
        ),
        E::ColorParseError => parse_error(
            path,
            line,
            "a vertex ('v') has a wrong number of values: x y z, x y z w or x y z r g b",
        ),
        E::ScalingByZeroError => parse_error(path, line, "a vertex has w = 0"),
        E::ReadError => parse_error(
            path,
            line,
            "cannot read this line (is it valid UTF-8 text?)",
        ),
        other => parse_error(path, line, format!("cannot read this line: {other}")),
    }
}

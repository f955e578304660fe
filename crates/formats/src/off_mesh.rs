//! Object File Format (OFF) meshes, as the CGAL demo meshes (bunny, armadillo, elephant) use it:
//!
//! ```text
//! OFF                      header: OFF, optionally prefixed by C (vertex colours), N (normals), ST (texture)
//! nv nf ne                 counts (may also follow the header keyword on its line)
//! x y z [...]              nv vertex lines; values after x y z (normals, colours) are ignored
//! n i0 i1 ... [r g b [a]]  nf face lines: n zero-based vertex indices, then an optional face colour
//! ```
//!
//! `#` starts a comment; blank lines are skipped. This reader expects one vertex or face per line (as every
//! OFF writer we know of does), which lets each error name its line. A face colour becomes the face's
//! reflectance: integers are read as 0–255, decimals as 0–1, then clamped to
//! [0, [`super::MAX_COLOUR_REFLECTANCE`]]; faces without a colour get the default grey.

use std::path::Path;

use glam::DVec3;

use crate::{ColourMaterials, PolygonMesh, parse_error, read_bytes};
use radlab_scene::SceneError;

/// Reads an OFF file.
pub fn read_off(path: &Path) -> Result<PolygonMesh, SceneError> {
    let bytes = read_bytes(path)?;
    let text = String::from_utf8_lossy(&bytes);
    parse_off(&text, path)
}

/// Parses OFF text; `path` names the file in errors.
pub fn parse_off(text: &str, path: &Path) -> Result<PolygonMesh, SceneError> {
    // (1-based line, tokens) of every line with content.
    let mut lines = text.lines().enumerate().filter_map(|(i, l)| {
        let content = l.split('#').next().unwrap_or("").trim();
        (!content.is_empty()).then_some((i + 1, content))
    });
    let last_line = text.lines().count().max(1);
    let cut_short = |what: &str| {
        parse_error(
            path,
            last_line,
            format!("the file ends before {what} (the file is cut short)"),
        )
    };

    let (hline, header) = lines.next().ok_or_else(|| cut_short("its OFF header"))?;
    let mut htoks = header.split_whitespace();
    let keyword = htoks.next().unwrap_or("");
    let prefix = keyword.strip_suffix("OFF");
    let ok_prefix =
        prefix.is_some_and(|p| ["", "C", "N", "NC", "CN", "ST", "STC", "STN", "STNC"].contains(&p));
    if !ok_prefix {
        return Err(parse_error(
            path,
            hline,
            format!(
                "expected the header 'OFF' (or COFF, NOFF, STOFF), found '{keyword}'; is this an OFF file?"
            ),
        ));
    }
    let rest: Vec<&str> = htoks.collect();
    let (cline, counts): (usize, Vec<&str>) = if rest.is_empty() {
        let (l, c) = lines
            .next()
            .ok_or_else(|| cut_short("the vertex and face counts"))?;
        (l, c.split_whitespace().collect())
    } else {
        (hline, rest)
    };
    let count = |k: usize, what: &str| -> Result<usize, SceneError> {
        let s = counts.get(k).ok_or_else(|| {
            parse_error(
                path,
                cline,
                format!("expected the counts 'vertices faces edges', the {what} count is missing"),
            )
        })?;
        s.parse::<usize>().map_err(|_| {
            parse_error(
                path,
                cline,
                format!("the {what} count '{s}' is not a whole number"),
            )
        })
    };
    let nv = count(0, "vertex")?;
    let nf = count(1, "face")?;
    if nv > u32::MAX as usize {
        return Err(parse_error(
            path,
            cline,
            format!("{nv} vertices is more than radlab supports (2^32 - 1)"),
        ));
    }

    let mut mesh = PolygonMesh::new();
    mesh.positions.reserve(nv.min(1 << 24));
    for k in 0..nv {
        let (line, content) = lines
            .next()
            .ok_or_else(|| cut_short(&format!("vertex {} of {nv}", k + 1)))?;
        let mut toks = content.split_whitespace();
        let mut p = [0.0f64; 3];
        for (c, slot) in p.iter_mut().enumerate() {
            let s = toks.next().ok_or_else(|| {
                parse_error(
                    path,
                    line,
                    format!("vertex {k} needs x y z, found {c} number(s)"),
                )
            })?;
            *slot = s.parse().map_err(|_| {
                parse_error(path, line, format!("vertex {k}: '{s}' is not a number"))
            })?;
        }
        let p = DVec3::from(p);
        if !p.is_finite() {
            return Err(parse_error(
                path,
                line,
                format!(
                    "vertex {k} ({}, {}, {}) is not finite; every coordinate must be a finite number",
                    p.x, p.y, p.z
                ),
            ));
        }
        mesh.positions.push(p);
    }

    let prefix = path
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    let mut colours = ColourMaterials::new(&prefix);
    let mut idx: Vec<u32> = Vec::with_capacity(8);
    for k in 0..nf {
        let (line, content) = lines
            .next()
            .ok_or_else(|| cut_short(&format!("face {} of {nf}", k + 1)))?;
        let toks: Vec<&str> = content.split_whitespace().collect();
        let n: usize = toks.first().and_then(|s| s.parse().ok()).ok_or_else(|| {
            parse_error(
                path,
                line,
                format!("face {k} should start with its vertex count"),
            )
        })?;
        if n < 3 {
            return Err(parse_error(
                path,
                line,
                format!("face {k} has {n} vertices; a face needs at least 3"),
            ));
        }
        if toks.len() < 1 + n {
            return Err(parse_error(
                path,
                line,
                format!(
                    "face {k} declares {n} vertices but lists {} (is the file cut short?)",
                    toks.len() - 1
                ),
            ));
        }
        idx.clear();
        for s in &toks[1..=n] {
            let i: usize = s.parse().map_err(|_| {
                parse_error(
                    path,
                    line,
                    format!("face {k}: vertex index '{s}' is not a whole number >= 0"),
                )
            })?;
            if i >= nv {
                return Err(parse_error(
                    path,
                    line,
                    format!(
                        "face {k}: vertex index {i} is out of range (the file has {nv} vertices, numbered from 0)"
                    ),
                ));
            }
            idx.push(i as u32);
        }
        let extra = &toks[1 + n..];
        let material = match extra.len() {
            0 => mesh.default_material(),
            3 | 4 => {
                let ints = extra[..3].iter().all(|s| s.parse::<i64>().is_ok());
                let mut c = [0.0f64; 3];
                for (slot, s) in c.iter_mut().zip(&extra[..3]) {
                    let v: f64 = s.parse().map_err(|_| {
                        parse_error(
                            path,
                            line,
                            format!("face {k}: colour value '{s}' is not a number"),
                        )
                    })?;
                    if !v.is_finite() {
                        return Err(parse_error(
                            path,
                            line,
                            format!("face {k}: colour value '{s}' is not finite"),
                        ));
                    }
                    *slot = if ints { v / 255.0 } else { v };
                }
                colours.material(&mut mesh, DVec3::from(c))
            }
            m => {
                return Err(parse_error(
                    path,
                    line,
                    format!(
                        "face {k} has {m} values after its {n} indices; expected none or a colour r g b [a]"
                    ),
                ));
            }
        };
        if extra.is_empty() {
            mesh.notes.default_material_faces += 1;
        }
        mesh.push_polygon(&idx, material);
    }
    Ok(mesh)
}

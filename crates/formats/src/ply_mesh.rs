//! PLY meshes (Turk's Polygon File Format), ASCII or binary little/big endian, read with ply-rs-bw.
//!
//! Used: element `vertex` with properties `x`, `y`, `z` (any numeric type) and optional colour `red`, `green`,
//! `blue` (also `r`/`g`/`b` or `diffuse_red`/...); element `face` with the list `vertex_indices` (or
//! `vertex_index`) and optional colour. Other elements and properties are read and ignored.
//!
//! Reflectance from colour: integer colours are read as 0–255 and divided by 255, floating-point colours as
//! 0–1. A face colour wins; otherwise a face whose vertices all have colours takes their mean; the result is
//! clamped to [0, [`super::MAX_COLOUR_REFLECTANCE`]] per channel (counted when it moves). Faces without
//! colour get the default grey. Equal colours share one material.

use std::io::ErrorKind;
use std::path::Path;

use glam::DVec3;
use ply_rs_bw::parser::{ParseError, Parser, Reader};
use ply_rs_bw::ply::{
    Encoding, Header, Property, PropertyAccess, PropertyAccessResult, PropertyType,
};

use crate::{ColourMaterials, PolygonMesh, parse_error, read_bytes};
use radlab_scene::SceneError;

/// A number and its colour reading (integers / 255, floats as they are).
fn scalar(p: &Property) -> Option<(f64, f64)> {
    let int = |v: f64| Some((v, v / 255.0));
    match *p {
        Property::Char(v) => int(v.into()),
        Property::UChar(v) => int(v.into()),
        Property::Short(v) => int(v.into()),
        Property::UShort(v) => int(v.into()),
        Property::Int(v) => int(v.into()),
        Property::UInt(v) => int(v.into()),
        Property::Float(v) => Some((v.into(), v.into())),
        Property::Double(v) => Some((v, v)),
        _ => None,
    }
}

fn colour_channel(name: &str) -> Option<usize> {
    match name {
        "red" | "r" | "diffuse_red" => Some(0),
        "green" | "g" | "diffuse_green" => Some(1),
        "blue" | "b" | "diffuse_blue" => Some(2),
        _ => None,
    }
}

#[derive(Default)]
struct Vertex {
    p: [f64; 3],
    colour: [f64; 3],
    has_colour: u8,
}

impl PropertyAccess for Vertex {
    fn new() -> Self {
        Self::default()
    }

    fn set_property(&mut self, name: &str, prop: Property) -> PropertyAccessResult {
        let axis = match name {
            "x" => Some(0),
            "y" => Some(1),
            "z" => Some(2),
            _ => None,
        };
        let channel = colour_channel(name);
        if axis.is_none() && channel.is_none() {
            return PropertyAccessResult::Ignored;
        }
        let Some((v, c)) = scalar(&prop) else {
            return PropertyAccessResult::UnsupportedType;
        };
        if let Some(a) = axis {
            self.p[a] = v;
        } else if let Some(k) = channel {
            self.colour[k] = c;
            self.has_colour |= 1 << k;
        }
        PropertyAccessResult::Set
    }
}

#[derive(Default)]
struct Face {
    indices: Vec<i64>,
    colour: [f64; 3],
    has_colour: u8,
}

impl PropertyAccess for Face {
    fn new() -> Self {
        Self::default()
    }

    fn set_property(&mut self, name: &str, prop: Property) -> PropertyAccessResult {
        if name == "vertex_indices" || name == "vertex_index" {
            self.indices = match prop {
                Property::ListChar(v) => v.into_iter().map(i64::from).collect(),
                Property::ListUChar(v) => v.into_iter().map(i64::from).collect(),
                Property::ListShort(v) => v.into_iter().map(i64::from).collect(),
                Property::ListUShort(v) => v.into_iter().map(i64::from).collect(),
                Property::ListInt(v) => v.into_iter().map(i64::from).collect(),
                Property::ListUInt(v) => v.into_iter().map(i64::from).collect(),
                _ => return PropertyAccessResult::UnsupportedType,
            };
            return PropertyAccessResult::Set;
        }
        let Some(k) = colour_channel(name) else {
            return PropertyAccessResult::Ignored;
        };
        let Some((_, c)) = scalar(&prop) else {
            return PropertyAccessResult::UnsupportedType;
        };
        self.colour[k] = c;
        self.has_colour |= 1 << k;
        PropertyAccessResult::Set
    }
}

/// Any other element: read and dropped.
struct Skip;

impl PropertyAccess for Skip {
    fn new() -> Self {
        Skip
    }
}

/// The first line of a ply-rs-bw error, without its "Line N: " prefix (the line goes in our own error).
fn first_line(e: &ParseError) -> String {
    let text = e.to_string();
    let first = text.lines().next().unwrap_or("");
    let first = match first.split_once(": ") {
        Some((head, rest)) if head.starts_with("Line ") => rest,
        _ => first,
    };
    first.to_string()
}

fn ply_error(path: &Path, e: &ParseError, element: &str, count: usize) -> SceneError {
    let first = first_line(e);
    let message = if e.kind() == ErrorKind::UnexpectedEof {
        format!(
            "the file ends before the {count} '{element}' elements its header declares (the file is cut \
             short): {first}"
        )
    } else {
        format!("cannot read the '{element}' elements: {first}")
    };
    parse_error(path, e.line().unwrap_or(0), message)
}

/// Reads a PLY file.
pub fn read_ply(path: &Path) -> Result<PolygonMesh, SceneError> {
    let bytes = read_bytes(path)?;
    let mut reader = Reader::new(std::io::Cursor::new(&bytes[..]));
    let header = Parser::<Vertex>::new()
        .read_header(&mut reader)
        .map_err(|e| {
            parse_error(
                path,
                e.line().unwrap_or(0),
                format!("not a valid PLY header: {}", first_line(&e)),
            )
        })?;
    check_header(path, &header)?;

    let header_lines = bytes
        .windows(10)
        .position(|w| w == b"end_header")
        .map_or(0, |i| super::line_at(&bytes, i));
    let ascii = header.encoding == Encoding::Ascii;
    let mut vertices: Vec<Vertex> = Vec::new();
    let mut faces: Vec<Face> = Vec::new();
    let mut vertex_first_line = 0;
    let mut face_first_line = 0;
    let mut lines_before = header_lines;
    for (name, def) in &header.elements {
        match name.as_str() {
            "vertex" => {
                vertex_first_line = lines_before + 1;
                vertices = Parser::<Vertex>::new()
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(|e| ply_error(path, &e, name, def.count))?;
            }
            "face" => {
                face_first_line = lines_before + 1;
                faces = Parser::<Face>::new()
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(|e| ply_error(path, &e, name, def.count))?;
            }
            _ => {
                Parser::<Skip>::new()
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(|e| ply_error(path, &e, name, def.count))?;
            }
        }
        lines_before += def.count;
    }
    let where_vertex = |k: usize| {
        if ascii {
            (vertex_first_line + k, format!("vertex {k}"))
        } else {
            (0, format!("vertex {k} (binary file)"))
        }
    };

    let mut mesh = PolygonMesh::new();
    mesh.positions.reserve(vertices.len());
    for (k, v) in vertices.iter().enumerate() {
        let p = DVec3::from(v.p);
        if !p.is_finite() {
            let (line, what) = where_vertex(k);
            return Err(parse_error(
                path,
                line,
                format!(
                    "{what} ({}, {}, {}) is not finite; every coordinate must be a finite number",
                    p.x, p.y, p.z
                ),
            ));
        }
        if v.has_colour == 0b111 && !DVec3::from(v.colour).is_finite() {
            let (line, what) = where_vertex(k);
            return Err(parse_error(
                path,
                line,
                format!("{what} has a colour that is not finite"),
            ));
        }
        mesh.positions.push(p);
    }
    let nv = vertices.len();
    let prefix = path
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    let mut colours = ColourMaterials::new(&prefix);
    let mut idx: Vec<u32> = Vec::with_capacity(8);
    let face_line = |k: usize| if ascii { face_first_line + k } else { 0 };
    for (k, f) in faces.iter().enumerate() {
        if f.indices.len() < 3 {
            return Err(parse_error(
                path,
                face_line(k),
                format!(
                    "face {k} has {} vertices; a face needs at least 3",
                    f.indices.len()
                ),
            ));
        }
        idx.clear();
        for &i in &f.indices {
            if i < 0 || i as usize >= nv {
                return Err(parse_error(
                    path,
                    face_line(k),
                    format!(
                        "face {k}: vertex index {i} is out of range (the file has {nv} vertices, numbered from 0)"
                    ),
                ));
            }
            idx.push(i as u32);
        }
        let colour = if f.has_colour == 0b111 {
            Some(DVec3::from(f.colour))
        } else if idx.iter().all(|&i| {
            vertices
                .get(i as usize)
                .is_some_and(|v| v.has_colour == 0b111)
        }) {
            let sum: DVec3 = idx
                .iter()
                .filter_map(|&i| vertices.get(i as usize))
                .map(|v| DVec3::from(v.colour))
                .sum();
            Some(sum / idx.len() as f64)
        } else {
            None
        };
        let material = match colour {
            Some(c) if !c.is_finite() => {
                return Err(parse_error(
                    path,
                    face_line(k),
                    format!("face {k} has a colour that is not finite"),
                ));
            }
            Some(c) => colours.material(&mut mesh, c),
            None => {
                mesh.notes.default_material_faces += 1;
                mesh.default_material()
            }
        };
        mesh.push_polygon(&idx, material);
    }
    Ok(mesh)
}

fn check_header(path: &Path, header: &Header) -> Result<(), SceneError> {
    let bad = |message: String| Err(parse_error(path, 0, message));
    let Some(vertex) = header.elements.get("vertex") else {
        return bad(
            "the header declares no 'vertex' element; a mesh needs vertices with x, y, z".into(),
        );
    };
    for axis in ["x", "y", "z"] {
        match vertex.properties.get(axis).map(|p| &p.data_type) {
            Some(PropertyType::Scalar(_)) => {}
            Some(PropertyType::List(..)) => {
                return bad(format!(
                    "vertex property '{axis}' is a list; it must be a number"
                ));
            }
            None => return bad(format!("the 'vertex' element has no '{axis}' property")),
        }
    }
    let Some(face) = header.elements.get("face") else {
        return bad(
            "the header declares no 'face' element; radlab needs polygons, not a point cloud"
                .into(),
        );
    };
    let list = ["vertex_indices", "vertex_index"]
        .iter()
        .find_map(|n| face.properties.get(*n));
    match list.map(|p| &p.data_type) {
        Some(PropertyType::List(..)) => Ok(()),
        Some(PropertyType::Scalar(_)) => {
            bad("the face property 'vertex_indices' must be a list".into())
        }
        None => bad("the 'face' element has no 'vertex_indices' (or 'vertex_index') list".into()),
    }
}

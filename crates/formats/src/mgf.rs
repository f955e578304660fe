//! The Materials and Geometry Format (MGF 1.1; Ward 1995, "The Materials and Geometry Format", Lawrence
//! Berkeley Laboratory), the format of the radiosity literature's scenes (RenderPark reads it, Radiance's
//! `mgf2rad` converts it). One entity per line (a trailing `\` continues a line), `#` starts a comment.
//!
//! Read:
//! - **vertices** `v id = [template]`, `v id`, `p x y z`, `n dx dy dz`; a vertex is placed by the transform in
//!   force where a surface uses it, not where it is defined (as the format says);
//! - **surfaces** `f v1 v2 … vN` (right-hand rule; N > 4 convex polygons are fanned, non-convex ones, such as
//!   MGF's seamed polygons with holes, are cut into triangles by ear clipping in their plane), and the
//!   primitives `sph`, `cyl`, `cone`, `ring`, `prism`, tessellated as below;
//! - **transforms** `xf [-t x y z] [-rx|-ry|-rz deg] [-s f] [-mx|-my|-mz] [-i N] [-a N] …` … `xf`: arguments act
//!   in the order given, `-i N` repeats the arguments after it (up to the next `-i`/`-a`) N times, `-a N` makes
//!   N instances of the enclosed entities, instance k applying the arguments after it k times; nested
//!   transforms act inside out. Every `xf` must be closed in the file it opens in. Mirrors reverse the winding
//!   so normals stay on the surface's front;
//! - **includes** `i file [transform]`, the path relative to the including file;
//! - **materials** `m id = [template]`, `m id`, `m`, with `rd ρ` (diffuse reflectance) and `ed ε` (diffuse
//!   emittance), each in the colour current when it is given; **colours** `c id = [template]`, `c id`, `c`,
//!   with `cxy x y`, `cspec λmin λmax v…` and `cct T`. Colour conversion is [`radlab_scene::builtin`]'s
//!   (`spectrum_rgb`): (x, y, Y) → CIE XYZ → linear sRGB (IEC 61966-2-1 primaries, D65 white); reflectance is
//!   the ratio to the equal-energy white MGF defines reflectance against, so neutral grey (x = y = 1/3) at
//!   `rd 0.5` is 0.5 in every channel; emission is the exitance E = M · XYZ(x, y, ε / K) W/m². MGF's ε is
//!   photometric (lm/m²); K = [`WHITE_EFFICACY`] = 179 lm/W is the luminous efficacy of equal-energy white by
//!   which Radiance's `mgf2rad` and RenderPark read it too, so a scene taken from the literature keeps its
//!   absolute values across the three programs: `ed 179` of neutral colour is E = (1.2049, 0.9484, 0.9091).
//!
//! Not read (each reported once with its first line in [`LoadNotes::unsupported`], then ignored, as radlab's
//! world is diffuse): specular and transmitting materials `rs`, `ts`, `td`, `ir`, two-sided `sides 2` (radlab's
//! faces have one side, the right-hand-rule front), `cmix`, `fh`, `torus`, `ies`, and unknown entities.
//! A colour outside the sRGB gamut has its negative channels set to 0, noted the same way. Malformed input (a
//! missing or non-numeric argument, an undefined vertex, material or colour, an unclosed `xf`, a reflectance
//! of 1 or more in a channel) is refused with the file, the line and the fix.
//!
//! **Tessellation.** A circle of radius r becomes a polygon of n = [`circle_segments`]([`CHORD_TOLERANCE`]) =
//! 24 segments, the smallest multiple of 4 whose chords stray at most `CHORD_TOLERANCE` · r (1%) from the
//! circle: sagitta r (1 − cos(π/n)) ≤ 0.01 r. `cyl` and `cone` are n quads (triangles where a radius is
//! zero), `ring` n quads (n triangles when r_min = 0), `sph` a latitude–longitude grid of n meridians and n/2
//! zones (planar trapezoids, triangles at the poles), every vertex on the sphere; `prism` is exact. Areas
//! fall short of the curved surface's by O(1/n²): 1.1% for a disc (n sin(2π/n)/(2π)), about 1.7% for a
//! sphere.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;

use glam::{DAffine3, DMat3, DVec3};

use crate::{LoadNotes, parse_error, read_bytes};
use radlab_scene::builtin::spectrum_rgb::{
    blackbody_xy, reflectance_rgb_from_xyz, spectrum_xy, xyy_to_xyz, xyz_to_linear_srgb,
};
use radlab_scene::{Material, Scene, SceneBuilder, SceneError};

/// Luminous efficacy of equal-energy white (lm/W) by which MGF's photometric emittance `ed` becomes
/// radiometric exitance, as Radiance and RenderPark convert it.
pub const WHITE_EFFICACY: f64 = 179.0;

/// Largest distance of a tessellated circle's chords from the circle, relative to its radius.
pub const CHORD_TOLERANCE: f64 = 0.01;

/// Deepest nesting of `i` includes (deeper is taken for an include cycle).
pub const MAX_INCLUDE_DEPTH: usize = 64;

/// Segments per full circle for a chord tolerance `tol` (relative to the radius): the smallest multiple of 4
/// with r (1 − cos(π/n)) ≤ tol · r.
pub fn circle_segments(tol: f64) -> usize {
    let half_angle = (1.0 - tol.clamp(1e-9, 1.0)).acos();
    let n = (std::f64::consts::PI / half_angle).ceil() as usize;
    n.div_ceil(4).max(1) * 4
}

/// Loads an MGF file (and the files it includes) as a scene named after the file.
pub fn load_mgf(path: &Path) -> Result<(Scene, LoadNotes), SceneError> {
    let name = path
        .file_stem()
        .map_or_else(|| "mgf".to_string(), |s| s.to_string_lossy().into_owned());
    let mut r = Reader::new(&name);
    let stmts = r.file(path, path, 0)?;
    r.run(&stmts, 0)?;
    let mut notes = LoadNotes::default();
    let mut unsupported: Vec<_> = r.unsupported.into_values().collect();
    unsupported.sort();
    notes.unsupported = unsupported.into_iter().map(|(_, _, m)| m).collect();
    Ok((r.b.build()?, notes))
}

/// One entity: where it is and its words.
struct Stmt {
    file: Rc<PathBuf>,
    line: usize,
    words: Vec<String>,
}

impl Stmt {
    fn err(&self, message: impl Into<String>) -> SceneError {
        parse_error(&self.file, self.line, message)
    }

    fn num(&self, k: usize, what: &str) -> Result<f64, SceneError> {
        let s = self.words.get(k).ok_or_else(|| {
            self.err(format!(
                "'{}' needs {what} as argument {k}; see the MGF entity reference for '{}'",
                self.words[0], self.words[0]
            ))
        })?;
        let v: f64 = s
            .parse()
            .map_err(|_| self.err(format!("'{}': {what} '{s}' is not a number", self.words[0])))?;
        if !v.is_finite() {
            return Err(self.err(format!("'{}': {what} '{s}' is not finite", self.words[0])));
        }
        Ok(v)
    }

    fn vec3(&self, k: usize, what: &str) -> Result<DVec3, SceneError> {
        Ok(DVec3::new(
            self.num(k, &format!("{what} x"))?,
            self.num(k + 1, &format!("{what} y"))?,
            self.num(k + 2, &format!("{what} z"))?,
        ))
    }

    fn arity(&self, n: usize, usage: &str) -> Result<(), SceneError> {
        if self.words.len() != n + 1 {
            return Err(self.err(format!(
                "'{}' takes {n} argument(s), found {}: write '{usage}'",
                self.words[0],
                self.words.len() - 1
            )));
        }
        Ok(())
    }
}

#[derive(Clone, Copy, Debug, Default)]
struct Vertex {
    p: DVec3,
    n: DVec3,
}

/// A colour as chromaticity.
#[derive(Clone, Copy, Debug)]
struct Colour {
    x: f64,
    y: f64,
}

impl Default for Colour {
    /// MGF's default: equal-energy grey.
    fn default() -> Self {
        Self {
            x: 1.0 / 3.0,
            y: 1.0 / 3.0,
        }
    }
}

#[derive(Clone, Copy, Debug, Default)]
struct MgfMaterial {
    rd: f64,
    rd_colour: Colour,
    ed: f64,
    ed_colour: Colour,
}

/// A named context (vertex, colour or material): the named ones, the unnamed one, and which is current.
struct Contexts<T> {
    named: HashMap<String, T>,
    unnamed: T,
    current: Option<String>,
}

impl<T: Clone + Default> Contexts<T> {
    fn new() -> Self {
        Self {
            named: HashMap::new(),
            unnamed: T::default(),
            current: None,
        }
    }

    fn get(&self) -> &T {
        self.current
            .as_ref()
            .and_then(|n| self.named.get(n))
            .unwrap_or(&self.unnamed)
    }

    fn get_mut(&mut self) -> &mut T {
        match self.current.as_ref().and_then(|n| self.named.get_mut(n)) {
            Some(t) => t,
            None => &mut self.unnamed,
        }
    }

    /// The `v`/`c`/`m` entity: `kw`, `kw id`, `kw id =`, `kw id = template`.
    fn select(&mut self, s: &Stmt, what: &str) -> Result<(), SceneError> {
        let w = &s.words;
        match w.len() {
            1 => {
                self.unnamed = T::default();
                self.current = None;
            }
            2 => {
                if !self.named.contains_key(&w[1]) {
                    return Err(s.err(format!(
                        "{what} '{}' is not defined; define it first with '{} {} ='",
                        w[1], w[0], w[1]
                    )));
                }
                self.current = Some(w[1].clone());
            }
            3 | 4 if w[2] == "=" => {
                let value = match w.get(3) {
                    Some(t) => self.named.get(t).cloned().ok_or_else(|| {
                        s.err(format!(
                            "template {what} '{t}' is not defined; define it before '{} {} = {t}'",
                            w[0], w[1]
                        ))
                    })?,
                    None => T::default(),
                };
                self.named.insert(w[1].clone(), value);
                self.current = Some(w[1].clone());
            }
            _ => {
                return Err(s.err(format!(
                    "expected '{0}', '{0} id', '{0} id =' or '{0} id = template' (the '=' separated by spaces)",
                    w[0]
                )));
            }
        }
        Ok(())
    }
}

/// A transform's argument list, split where `-i` and `-a` start a repeated part.
struct XfSpec {
    /// Each part's transform (its arguments composed in order) and how it repeats.
    parts: Vec<(DAffine3, Repeat)>,
}

#[derive(Clone, Copy, PartialEq)]
enum Repeat {
    Once,
    Times(usize),
    Array(usize),
}

impl XfSpec {
    fn parse(s: &Stmt, first: usize) -> Result<Self, SceneError> {
        let w = &s.words;
        let mut parts = vec![(DAffine3::IDENTITY, Repeat::Once)];
        let mut k = first;
        let count = |k: usize, flag: &str| -> Result<usize, SceneError> {
            let v = s.num(k, &format!("the count after {flag}"))?;
            if !(v >= 1.0 && v.fract() == 0.0 && v <= 1e6) {
                return Err(s.err(format!(
                    "{flag} {v}: the count must be a whole number from 1 to 1000000"
                )));
            }
            Ok(v as usize)
        };
        while k < w.len() {
            let flag = w[k].as_str();
            let step = match flag {
                "-t" => {
                    let t = s.vec3(k + 1, "-t")?;
                    k += 4;
                    DAffine3::from_translation(t)
                }
                "-rx" | "-ry" | "-rz" => {
                    let a = s
                        .num(k + 1, &format!("the angle after {flag}"))?
                        .to_radians();
                    k += 2;
                    DAffine3::from_mat3(match flag {
                        "-rx" => DMat3::from_rotation_x(a),
                        "-ry" => DMat3::from_rotation_y(a),
                        _ => DMat3::from_rotation_z(a),
                    })
                }
                "-s" => {
                    let f = s.num(k + 1, "the factor after -s")?;
                    if f == 0.0 {
                        return Err(s.err("-s 0: the scale factor must not be zero"));
                    }
                    k += 2;
                    DAffine3::from_scale(DVec3::splat(f))
                }
                "-mx" | "-my" | "-mz" => {
                    k += 1;
                    DAffine3::from_scale(match flag {
                        "-mx" => DVec3::new(-1.0, 1.0, 1.0),
                        "-my" => DVec3::new(1.0, -1.0, 1.0),
                        _ => DVec3::new(1.0, 1.0, -1.0),
                    })
                }
                "-i" | "-a" => {
                    let n = count(k + 1, flag)?;
                    k += 2;
                    parts.push((
                        DAffine3::IDENTITY,
                        if flag == "-i" {
                            Repeat::Times(n)
                        } else {
                            Repeat::Array(n)
                        },
                    ));
                    continue;
                }
                other => {
                    return Err(s.err(format!(
                        "unknown transform argument '{other}'; MGF transforms take -t x y z, -rx/-ry/-rz degrees, \
                         -s factor, -mx/-my/-mz, -i N and -a N"
                    )));
                }
            };
            let last = parts.last_mut().expect("at least one part");
            last.0 = step * last.0;
        }
        Ok(Self { parts })
    }

    /// Number of instances (the product of the array counts).
    fn instances(&self) -> usize {
        self.parts
            .iter()
            .map(|(_, r)| match r {
                Repeat::Array(n) => *n,
                _ => 1,
            })
            .product()
    }

    /// The transform of instance `index` (0 ≤ index < instances()), first array fastest.
    fn instance(&self, mut index: usize) -> DAffine3 {
        let mut m = DAffine3::IDENTITY;
        for (t, r) in &self.parts {
            let times = match *r {
                Repeat::Once => 1,
                Repeat::Times(n) => n,
                Repeat::Array(n) => {
                    let k = index % n;
                    index /= n;
                    k
                }
            };
            for _ in 0..times {
                m = *t * m;
            }
        }
        m
    }
}

struct Reader {
    b: SceneBuilder,
    vertices: Contexts<Vertex>,
    colours: Contexts<Colour>,
    materials: Contexts<MgfMaterial>,
    /// World transform of the enclosing contexts.
    xf: Vec<DAffine3>,
    /// Parsed files, by path.
    files: HashMap<PathBuf, Rc<Vec<Stmt>>>,
    /// Builder vertex of each world position (shared vertices keep meshes connected).
    positions: HashMap<[u64; 3], u32>,
    /// Builder material of each (name, ρ, E).
    built_materials: HashMap<(String, [u64; 6]), u32>,
    /// Unsupported entities: keyword → (file, line, message), the first occurrence.
    unsupported: HashMap<String, (PathBuf, usize, String)>,
    segments: usize,
}

impl Reader {
    fn new(name: &str) -> Self {
        Self {
            b: SceneBuilder::new(name),
            vertices: Contexts::new(),
            colours: Contexts::new(),
            materials: Contexts::new(),
            xf: vec![DAffine3::IDENTITY],
            files: HashMap::new(),
            positions: HashMap::new(),
            built_materials: HashMap::new(),
            unsupported: HashMap::new(),
            segments: circle_segments(CHORD_TOLERANCE),
        }
    }

    /// Reads and splits a file into entities (cached).
    fn file(&mut self, path: &Path, from: &Path, line: usize) -> Result<Rc<Vec<Stmt>>, SceneError> {
        if let Some(s) = self.files.get(path) {
            return Ok(s.clone());
        }
        let bytes = read_bytes(path).map_err(|e| {
            if line > 0 {
                parse_error(
                    from,
                    line,
                    format!("cannot read the included file {}: {e}", path.display()),
                )
            } else {
                e
            }
        })?;
        let text = String::from_utf8_lossy(&bytes);
        let file = Rc::new(path.to_path_buf());
        let mut stmts = Vec::new();
        let mut pending: Vec<String> = Vec::new();
        let mut start = 0;
        for (i, raw) in text.lines().enumerate() {
            let content = raw.split('#').next().unwrap_or("");
            let (content, continued) = match content.trim_end().strip_suffix('\\') {
                Some(c) => (c, true),
                None => (content, false),
            };
            if pending.is_empty() {
                start = i + 1;
            }
            pending.extend(content.split_whitespace().map(str::to_string));
            if !continued && !pending.is_empty() {
                stmts.push(Stmt {
                    file: file.clone(),
                    line: start,
                    words: std::mem::take(&mut pending),
                });
            }
        }
        if !pending.is_empty() {
            stmts.push(Stmt {
                file,
                line: start,
                words: pending,
            });
        }
        let stmts = Rc::new(stmts);
        self.files.insert(path.to_path_buf(), stmts.clone());
        Ok(stmts)
    }

    fn note(&mut self, s: &Stmt, why: &str) {
        let kw = s.words[0].clone();
        self.unsupported.entry(kw.clone()).or_insert_with(|| {
            (
                s.file.to_path_buf(),
                s.line,
                format!(
                    "{}:{}: '{kw}' {why}; ignored (reported once)",
                    s.file.display(),
                    s.line
                ),
            )
        });
    }

    /// Interprets entities.
    fn run(&mut self, stmts: &[Stmt], depth: usize) -> Result<(), SceneError> {
        let mut k = 0;
        while k < stmts.len() {
            let s = &stmts[k];
            k += 1;
            match s.words[0].as_str() {
                "xf" if s.words.len() == 1 => {
                    return Err(s.err(
                        "this 'xf' closes no transform (every 'xf' with arguments is closed by one lone 'xf' \
                         in the same file); remove it or add the transform it should close",
                    ));
                }
                "xf" => {
                    let spec = XfSpec::parse(s, 1)?;
                    let end = matching_end(stmts, k).ok_or_else(|| {
                        s.err(
                            "this 'xf' is never closed in its file; add a lone 'xf' line after the entities it \
                             transforms",
                        )
                    })?;
                    for i in 0..spec.instances() {
                        self.push(spec.instance(i));
                        self.run(&stmts[k..end], depth)?;
                        self.xf.pop();
                    }
                    k = end + 1;
                }
                "i" => {
                    let name = s
                        .words
                        .get(1)
                        .ok_or_else(|| s.err("'i' needs a file name: 'i file.mgf [transform]'"))?;
                    if depth + 1 > MAX_INCLUDE_DEPTH {
                        return Err(s.err(format!(
                            "includes nest deeper than {MAX_INCLUDE_DEPTH} levels; does a file include itself?"
                        )));
                    }
                    let path = s
                        .file
                        .parent()
                        .map_or_else(|| PathBuf::from(name), |d| d.join(name));
                    let spec = XfSpec::parse(s, 2)?;
                    let sub = self.file(&path, &s.file, s.line)?;
                    for i in 0..spec.instances() {
                        self.push(spec.instance(i));
                        self.run(&sub, depth + 1)?;
                        self.xf.pop();
                    }
                }
                "o" => {}
                "v" => self.vertices.select(s, "vertex")?,
                "p" => {
                    s.arity(3, "p x y z")?;
                    self.vertices.get_mut().p = s.vec3(1, "point")?;
                }
                "n" => {
                    s.arity(3, "n dx dy dz")?;
                    self.vertices.get_mut().n = s.vec3(1, "normal")?.normalize_or_zero();
                }
                "c" => self.colours.select(s, "colour")?,
                "cxy" => {
                    s.arity(2, "cxy x y")?;
                    let (x, y) = (s.num(1, "x")?, s.num(2, "y")?);
                    if !(x > 0.0 && y > 0.0 && x + y < 1.0) {
                        return Err(s.err(format!(
                            "cxy {x} {y}: CIE chromaticity needs x > 0, y > 0 and x + y < 1 (neutral is 0.333 0.333)"
                        )));
                    }
                    *self.colours.get_mut() = Colour { x, y };
                }
                "cspec" => {
                    let (lo, hi) = (s.num(1, "l_min")?, s.num(2, "l_max")?);
                    let values = (3..s.words.len())
                        .map(|i| s.num(i, "spectrum value"))
                        .collect::<Result<Vec<_>, _>>()?;
                    if values.len() < 2 || !(hi > lo) || values.iter().any(|&v| v < 0.0) {
                        return Err(s.err(
                            "write 'cspec l_min l_max v1 v2 ...' with l_min < l_max (nm) and at least two \
                             values, all >= 0",
                        ));
                    }
                    let step = (hi - lo) / (values.len() - 1) as f64;
                    let (x, y) = spectrum_xy(lo, step, &values).ok_or_else(|| {
                        s.err(
                            "this spectrum has no colour between 400 and 700 nm; give values there",
                        )
                    })?;
                    *self.colours.get_mut() = Colour { x, y };
                }
                "cct" => {
                    s.arity(1, "cct kelvin")?;
                    let t = s.num(1, "temperature")?;
                    let (x, y) =
                        (t >= 500.0)
                            .then(|| blackbody_xy(t))
                            .flatten()
                            .ok_or_else(|| {
                                s.err(format!(
                                    "cct {t}: give a black-body temperature of at least 500 K"
                                ))
                            })?;
                    *self.colours.get_mut() = Colour { x, y };
                }
                "m" => self.materials.select(s, "material")?,
                "rd" | "ed" => {
                    s.arity(1, &format!("{} value", s.words[0]))?;
                    let v = s.num(1, "value")?;
                    let colour = *self.colours.get();
                    let m = self.materials.get_mut();
                    if s.words[0] == "rd" {
                        if !(0.0..1.0).contains(&v) {
                            return Err(s.err(format!(
                                "rd {v}: a diffuse reflectance must be at least 0 and below 1"
                            )));
                        }
                        m.rd = v;
                        m.rd_colour = colour;
                    } else {
                        if v < 0.0 {
                            return Err(s.err(format!("ed {v}: emittance must be at least 0")));
                        }
                        m.ed = v;
                        m.ed_colour = colour;
                    }
                }
                "rs" | "ts" | "td" | "ir" => {
                    let zero =
                        (1..s.words.len()).all(|i| s.num(i, "value").is_ok_and(|v| v == 0.0));
                    if !(zero || s.words[0] == "ir") {
                        self.note(
                            s,
                            "(specular or transmitted light) is not diffuse reflection",
                        );
                    }
                }
                "sides" => {
                    s.arity(1, "sides 1|2")?;
                    match s.words[1].as_str() {
                        "1" => {}
                        "2" => self.note(
                            s,
                            "(two-sided surfaces): radlab's faces have one side, the front given by the \
                             right-hand rule",
                        ),
                        other => {
                            return Err(s.err(format!("sides {other}: write 'sides 1' or 'sides 2'")));
                        }
                    }
                }
                "cmix" | "fh" | "torus" | "ies" => {
                    self.note(s, "is not supported by radlab's MGF reader")
                }
                "f" => self.face(s)?,
                "sph" => self.sphere(s)?,
                "cyl" => self.cone(s, true)?,
                "cone" => self.cone(s, false)?,
                "ring" => self.ring(s)?,
                "prism" => self.prism(s)?,
                _ => self.note(s, "is not an MGF 1.1 entity radlab knows"),
            }
        }
        Ok(())
    }

    fn push(&mut self, local: DAffine3) {
        let top = *self.xf.last().expect("identity at the bottom");
        self.xf.push(top * local);
    }

    fn vertex(&self, s: &Stmt, name: &str) -> Result<Vertex, SceneError> {
        self.vertices.named.get(name).copied().ok_or_else(|| {
            s.err(format!(
                "vertex '{name}' is not defined; define it before use with 'v {name} =' and 'p x y z'"
            ))
        })
    }

    /// The builder material for the current MGF material (created on first use).
    fn material(&mut self, s: &Stmt) -> Result<u32, SceneError> {
        let m = *self.materials.get();
        let c = m.rd_colour;
        let rho = reflectance_rgb_from_xyz(xyy_to_xyz(c.x, c.y, m.rd));
        let c = m.ed_colour;
        let e = xyz_to_linear_srgb(xyy_to_xyz(c.x, c.y, m.ed / WHITE_EFFICACY));
        let name = self
            .materials
            .current
            .clone()
            .unwrap_or_else(|| "(unnamed)".into());
        if rho.min_element() < 0.0 || e.min_element() < 0.0 {
            self.unsupported.entry(format!("gamut {name}")).or_insert_with(|| {
                (
                    s.file.to_path_buf(),
                    s.line,
                    format!(
                        "{}:{}: material '{name}' has a colour outside the sRGB gamut (reflectance ({:.4}, {:.4}, \
                         {:.4}), emission ({:.4}, {:.4}, {:.4})); negative channels set to 0 (reported once)",
                        s.file.display(),
                        s.line,
                        rho.x,
                        rho.y,
                        rho.z,
                        e.x,
                        e.y,
                        e.z
                    ),
                )
            });
        }
        let rho = rho.max(DVec3::ZERO);
        if rho.max_element() >= 1.0 {
            return Err(s.err(format!(
                "material '{name}' (rd {} in colour x {:.4} y {:.4}) is the linear sRGB reflectance ({:.4}, \
                 {:.4}, {:.4}), 1 or more in a channel; lower rd below {:.4} for this colour",
                m.rd,
                m.rd_colour.x,
                m.rd_colour.y,
                rho.x,
                rho.y,
                rho.z,
                0.999 * m.rd / rho.max_element()
            )));
        }
        let e = e.max(DVec3::ZERO);
        let mut key = [0u64; 6];
        for (k, v) in rho.to_array().into_iter().chain(e.to_array()).enumerate() {
            key[k] = v.to_bits();
        }
        if let Some(&i) = self.built_materials.get(&(name.clone(), key)) {
            return Ok(i);
        }
        let mut unique = name.clone();
        let mut n = 2;
        while self.b.material_index(&unique).is_some() {
            unique = format!("{name}#{n}");
            n += 1;
        }
        let i = self.b.add_material(Material::new(&unique, rho, e)?)?;
        self.built_materials.insert((name, key), i);
        Ok(i)
    }

    fn what(s: &Stmt) -> String {
        format!("{}:{}", s.file.display(), s.line)
    }

    /// Index of a world position, shared between surfaces that meet there.
    fn point(&mut self, p: DVec3, what: &str) -> Result<u32, SceneError> {
        let key = (p + DVec3::ZERO).to_array().map(f64::to_bits);
        if let Some(&i) = self.positions.get(&key) {
            return Ok(i);
        }
        let i = self.b.add_vertex(p, what)?;
        self.positions.insert(key, i);
        Ok(i)
    }

    /// Adds a polygon given in local coordinates: placed by the current transform (winding reversed by a
    /// mirror); larger non-convex polygons are ear-clipped.
    fn polygon(&mut self, s: &Stmt, local: &[DVec3], m: u32) -> Result<(), SceneError> {
        let xf = *self.xf.last().expect("identity at the bottom");
        let mut pts: Vec<DVec3> = local.iter().map(|&p| xf.transform_point3(p)).collect();
        if xf.matrix3.determinant() < 0.0 {
            pts.reverse();
        }
        let what = Self::what(s);
        let idx = pts
            .iter()
            .map(|&p| self.point(p, &what))
            .collect::<Result<Vec<_>, _>>()?;
        if pts.len() <= 4 || is_convex(&pts) {
            self.b.add_polygon(&idx, m, &what)?;
        } else {
            for t in ear_clip(&pts) {
                self.b.add_polygon(&t.map(|k| idx[k]), m, &what)?;
            }
            self.b.warnings_mut().polygons_triangulated += 1;
        }
        Ok(())
    }

    fn face(&mut self, s: &Stmt) -> Result<(), SceneError> {
        if s.words.len() < 4 {
            return Err(s.err("'f' needs at least three vertices: 'f v1 v2 v3 ...'"));
        }
        let pts = s.words[1..]
            .iter()
            .map(|n| self.vertex(s, n).map(|v| v.p))
            .collect::<Result<Vec<_>, _>>()?;
        let m = self.material(s)?;
        self.polygon(s, &pts, m)
    }

    fn sphere(&mut self, s: &Stmt) -> Result<(), SceneError> {
        s.arity(2, "sph centre radius")?;
        let c = self.vertex(s, &s.words[1])?.p;
        let r = s.num(2, "radius")?;
        if r == 0.0 {
            return Err(
                s.err("sph: the radius must not be zero (negative makes the normals point in)")
            );
        }
        let m = self.material(s)?;
        let (n, zones) = (self.segments, self.segments / 2);
        let at = |j: usize, k: usize| {
            let th = std::f64::consts::PI * j as f64 / zones as f64;
            let ph = std::f64::consts::TAU * (k % n) as f64 / n as f64;
            let (st, ct) = if j == zones {
                (0.0, -1.0)
            } else {
                th.sin_cos()
            };
            c + r.abs() * DVec3::new(st * ph.cos(), st * ph.sin(), ct)
        };
        for j in 0..zones {
            for k in 0..n {
                let mut q = if j == 0 {
                    vec![at(0, 0), at(1, k), at(1, k + 1)]
                } else if j + 1 == zones {
                    vec![at(j, k), at(zones, 0), at(j, k + 1)]
                } else {
                    vec![at(j, k), at(j + 1, k), at(j + 1, k + 1), at(j, k + 1)]
                };
                if r < 0.0 {
                    q.reverse();
                }
                self.polygon(s, &q, m)?;
            }
        }
        Ok(())
    }

    /// `cyl v1 r v2` (`cylinder`) or `cone v1 r1 v2 r2`.
    fn cone(&mut self, s: &Stmt, cylinder: bool) -> Result<(), SceneError> {
        let (v1, r1, v2, r2) = if cylinder {
            s.arity(3, "cyl v1 radius v2")?;
            let r = s.num(2, "radius")?;
            (&s.words[1], r, &s.words[3], r)
        } else {
            s.arity(4, "cone v1 radius1 v2 radius2")?;
            (
                &s.words[1],
                s.num(2, "radius1")?,
                &s.words[3],
                s.num(4, "radius2")?,
            )
        };
        let (a, b) = (self.vertex(s, v1)?.p, self.vertex(s, v2)?.p);
        if (r1 == 0.0 && r2 == 0.0) || r1 * r2 < 0.0 {
            return Err(s.err(format!(
                "{}: the radii must not both be zero and must have the same sign (negative: normals point in)",
                s.words[0]
            )));
        }
        if a == b {
            return Err(s.err(format!(
                "{}: the end vertices '{v1}' and '{v2}' coincide; use 'ring' for a flat disc",
                s.words[0]
            )));
        }
        let inward = r1 < 0.0 || r2 < 0.0;
        let m = self.material(s)?;
        let (u, w) = basis(b - a);
        let n = self.segments;
        let rim = |c: DVec3, r: f64, k: usize| {
            let ph = std::f64::consts::TAU * (k % n) as f64 / n as f64;
            c + r.abs() * (ph.cos() * u + ph.sin() * w)
        };
        for k in 0..n {
            let mut q = vec![
                rim(a, r1, k),
                rim(a, r1, k + 1),
                rim(b, r2, k + 1),
                rim(b, r2, k),
            ];
            q.dedup();
            if inward {
                q.reverse();
            }
            self.polygon(s, &q, m)?;
        }
        Ok(())
    }

    fn ring(&mut self, s: &Stmt) -> Result<(), SceneError> {
        s.arity(3, "ring centre r_min r_max")?;
        let c = self.vertex(s, &s.words[1])?;
        let (r0, r1) = (s.num(2, "r_min")?, s.num(3, "r_max")?);
        if !(r0 >= 0.0 && r1 > r0) {
            return Err(s.err(format!(
                "ring: need 0 <= r_min < r_max, found {r0} and {r1}"
            )));
        }
        if c.n == DVec3::ZERO {
            return Err(s.err(format!(
                "ring: the centre vertex '{}' has no normal; give it one with 'n dx dy dz' (the ring faces that way)",
                s.words[1]
            )));
        }
        let m = self.material(s)?;
        let (u, w) = basis(c.n);
        let n = self.segments;
        let at = |r: f64, k: usize| {
            let ph = std::f64::consts::TAU * (k % n) as f64 / n as f64;
            c.p + r * (ph.cos() * u + ph.sin() * w)
        };
        for k in 0..n {
            let q = if r0 == 0.0 {
                vec![c.p, at(r1, k), at(r1, k + 1)]
            } else {
                vec![at(r0, k), at(r1, k), at(r1, k + 1), at(r0, k + 1)]
            };
            self.polygon(s, &q, m)?;
        }
        Ok(())
    }

    fn prism(&mut self, s: &Stmt) -> Result<(), SceneError> {
        if s.words.len() < 5 {
            return Err(s.err(
                "'prism' needs at least three vertices and a length: 'prism v1 v2 v3 ... length'",
            ));
        }
        let last = s.words.len() - 1;
        let len = s.num(last, "length")?;
        if len == 0.0 {
            return Err(
                s.err("prism: the length must not be zero (negative extrudes above the face)")
            );
        }
        let base = s.words[1..last]
            .iter()
            .map(|n| self.vertex(s, n).map(|v| v.p))
            .collect::<Result<Vec<_>, _>>()?;
        let normal = newell(&base);
        if normal == DVec3::ZERO {
            return Err(
                s.err("prism: the base polygon has no area (repeated or collinear vertices)")
            );
        }
        let m = self.material(s)?;
        let d = -len * normal;
        self.polygon(s, &base, m)?;
        let top: Vec<DVec3> = base.iter().rev().map(|&p| p + d).collect();
        self.polygon(s, &top, m)?;
        for k in 0..base.len() {
            let (p, q) = (base[k], base[(k + 1) % base.len()]);
            self.polygon(s, &[p, p + d, q + d, q], m)?;
        }
        Ok(())
    }
}

/// Index of the lone `xf` closing the transform opened just before `from`.
fn matching_end(stmts: &[Stmt], from: usize) -> Option<usize> {
    let mut depth = 0usize;
    for (k, s) in stmts.iter().enumerate().skip(from) {
        if s.words[0] == "xf" {
            if s.words.len() > 1 {
                depth += 1;
            } else if depth == 0 {
                return Some(k);
            } else {
                depth -= 1;
            }
        }
    }
    None
}

/// Unit vectors u, w with u × w = the unit `axis`.
fn basis(axis: DVec3) -> (DVec3, DVec3) {
    let a = axis.normalize();
    let u = a.any_orthonormal_vector();
    (u, a.cross(u))
}

/// The unit normal of a polygon by Newell's method (zero if degenerate).
fn newell(p: &[DVec3]) -> DVec3 {
    let mut s = DVec3::ZERO;
    for k in 1..p.len() - 1 {
        s += (p[k] - p[0]).cross(p[k + 1] - p[0]);
    }
    s.normalize_or_zero()
}

/// Whether a polygon turns the same way at every corner about its Newell normal.
fn is_convex(p: &[DVec3]) -> bool {
    let n = newell(p);
    let m = p.len();
    (0..m).all(|k| {
        let (a, b, c) = (p[k], p[(k + 1) % m], p[(k + 2) % m]);
        (b - a).cross(c - b).dot(n) >= 0.0
    })
}

/// Triangles (corner indices, same winding) of a simple planar polygon by ear clipping (Meisters 1975, "Polygons
/// have ears"): repeatedly cut off a convex corner whose triangle holds no other corner, not even on its edges. A seam (an edge
/// walked both ways, as MGF draws holes) leaves zero-area ears, which the builder drops. Falls back to a fan if
/// no ear is found (a self-intersecting polygon).
fn ear_clip(p: &[DVec3]) -> Vec<[usize; 3]> {
    let n = newell(p);
    let mut left: Vec<usize> = (0..p.len()).collect();
    let mut out = Vec::with_capacity(p.len() - 2);
    let inside = |q: DVec3, a: DVec3, b: DVec3, c: DVec3| {
        (b - a).cross(q - a).dot(n) >= 0.0
            && (c - b).cross(q - b).dot(n) >= 0.0
            && (a - c).cross(q - c).dot(n) >= 0.0
    };
    while left.len() > 3 {
        let m = left.len();
        let ear = (0..m).find(|&k| {
            let (i, j, l) = (left[(k + m - 1) % m], left[k], left[(k + 1) % m]);
            let (a, b, c) = (p[i], p[j], p[l]);
            (b - a).cross(c - b).dot(n) > 0.0
                && left.iter().all(|&o| {
                    o == i
                        || o == j
                        || o == l
                        || p[o] == a
                        || p[o] == b
                        || p[o] == c
                        || !inside(p[o], a, b, c)
                })
        });
        match ear {
            Some(k) => {
                out.push([left[(k + m - 1) % m], left[k], left[(k + 1) % m]]);
                left.remove(k);
            }
            None => {
                for k in 1..m - 1 {
                    out.push([left[0], left[k], left[k + 1]]);
                }
                return out;
            }
        }
    }
    out.push([left[0], left[1], left[2]]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segments_meet_the_chord_tolerance_and_no_fewer() {
        let n = circle_segments(CHORD_TOLERANCE);
        assert_eq!(n, 24);
        let sagitta = |n: usize| 1.0 - (std::f64::consts::PI / n as f64).cos();
        assert!(sagitta(n) <= CHORD_TOLERANCE);
        assert!(
            sagitta(n - 4) > CHORD_TOLERANCE,
            "a multiple of 4 fewer would do"
        );
    }

    #[test]
    fn ear_clipping_keeps_the_area_of_a_non_convex_polygon() {
        // An L of area 3 (unit squares), counter-clockwise seen from +z.
        let l: Vec<DVec3> = [(0., 0.), (2., 0.), (2., 1.), (1., 1.), (1., 2.), (0., 2.)]
            .iter()
            .map(|&(x, y)| DVec3::new(x, y, 0.0))
            .collect();
        assert!(!is_convex(&l));
        let tris = ear_clip(&l);
        assert_eq!(tris.len(), 4);
        let area: f64 = tris
            .iter()
            .map(|t| {
                let v = (l[t[1]] - l[t[0]]).cross(l[t[2]] - l[t[0]]);
                assert!(v.z > 0.0, "winding kept");
                0.5 * v.z
            })
            .sum();
        assert!((area - 3.0).abs() < 1e-12, "{area}");
        // A 4 × 4 square with a 2 × 2 hole, drawn as MGF draws holes: outer loop, a seam to the hole, the hole
        // the other way round, back along the seam. Area 12.
        let p = |x: f64, y: f64| DVec3::new(x, y, 0.0);
        let holed = [
            p(0., 0.),
            p(4., 0.),
            p(4., 4.),
            p(0., 4.),
            p(1., 3.),
            p(3., 3.),
            p(3., 1.),
            p(1., 1.),
            p(1., 3.),
            p(0., 4.),
        ];
        let tris = ear_clip(&holed);
        let area: f64 = tris
            .iter()
            .map(|t| {
                0.5 * (holed[t[1]] - holed[t[0]])
                    .cross(holed[t[2]] - holed[t[0]])
                    .z
            })
            .sum();
        assert!((area - 12.0).abs() < 1e-12, "{area}: {tris:?}");
        for t in &tris {
            let z = (holed[t[1]] - holed[t[0]])
                .cross(holed[t[2]] - holed[t[0]])
                .z;
            assert!(z >= 0.0, "{t:?} is inverted");
        }
    }

    #[test]
    fn array_instances_apply_their_step_k_times_after_the_prefix() {
        let s = Stmt {
            file: Rc::new(PathBuf::from("t.mgf")),
            line: 1,
            words: "xf -t 1 0 0 -a 3 -t 0 2 0 -a 2 -rz 90"
                .split(' ')
                .map(str::to_string)
                .collect(),
        };
        let x = XfSpec::parse(&s, 1).expect("parses");
        assert_eq!(x.instances(), 6);
        // Instance (k1 = 2, k2 = 1): translate (1,0,0), then 2 × (0,2,0), then rotate 90° about z once.
        let p = x.instance(2 + 3).transform_point3(DVec3::ZERO);
        assert!((p - DVec3::new(-4.0, 1.0, 0.0)).length() < 1e-12, "{p}");
    }
}

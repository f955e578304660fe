//! The scene every method solves: indexed planar convex faces (triangles and quads) in f64, one diffuse
//! material per face (reflectance ρ ∈ [0,1) per RGB channel, emission E ≥ 0 as radiant exitance in W/m²),
//! and an optional camera.
//!
//! Built through [`SceneBuilder`], which validates everything (finite coordinates, reflectance and emission
//! ranges, vertex indices) and drops degenerate faces (zero area, non-planar or non-convex quads), counting
//! them in [`Scene::warnings`] instead of printing: the scene crate never prints.

use glam::DVec3;

use crate::{Camera, Polygon, Rgb, SceneError};

/// Index of a face in [`Scene::faces`].
pub type FaceId = usize;

/// A diffuse material.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name, for messages and output.
    pub name: String,
    /// Diffuse reflectance per channel, each in [0, 1).
    pub reflectance: Rgb,
    /// Emitted radiant exitance per channel, W/m², each ≥ 0.
    pub emission: Rgb,
}

impl Material {
    /// A validated material. `what` names the material's origin for the error message.
    pub fn new(name: &str, reflectance: Rgb, emission: Rgb) -> Result<Self, SceneError> {
        let m = Self {
            name: name.to_string(),
            reflectance,
            emission,
        };
        m.validate()?;
        Ok(m)
    }

    /// Checks ρ ∈ [0,1) and E ≥ 0, finite.
    pub fn validate(&self) -> Result<(), SceneError> {
        for c in self.reflectance.to_array() {
            if !(c.is_finite() && (0.0..1.0).contains(&c)) {
                return Err(SceneError::Invalid {
                    field: format!("material '{}' reflectance", self.name),
                    message: format!(
                        "{c} is outside [0, 1); a diffuse reflectance must be at least 0 and below 1 \
                         (use 0.999 for a near-perfect reflector)"
                    ),
                });
            }
        }
        for c in self.emission.to_array() {
            if !(c.is_finite() && c >= 0.0) {
                return Err(SceneError::Invalid {
                    field: format!("material '{}' emission", self.name),
                    message: format!(
                        "{c} is not a finite value >= 0 (emission is radiant exitance in W/m²)"
                    ),
                });
            }
        }
        Ok(())
    }

    /// Whether any channel emits.
    pub fn is_emitter(&self) -> bool {
        self.emission.max_element() > 0.0
    }
}

/// A face: a triangle or planar convex quad over the scene's vertex array, with cached geometry.
#[derive(Clone, Copy, Debug)]
pub struct Face {
    /// Vertex indices; for a triangle the fourth is `u32::MAX`.
    pub indices: [u32; 4],
    /// Index into [`Scene::materials`].
    pub material: u32,
    /// Unit normal (right-hand rule over the vertex order).
    pub normal: DVec3,
    /// Area.
    pub area: f64,
    /// Area centroid.
    pub centroid: DVec3,
}

impl Face {
    /// Number of vertices (3 or 4).
    pub fn vertex_count(&self) -> usize {
        if self.indices[3] == u32::MAX { 3 } else { 4 }
    }

    /// The vertex indices in use.
    pub fn vertex_indices(&self) -> &[u32] {
        &self.indices[..self.vertex_count()]
    }
}

/// Counted problems that did not stop the scene from being built.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SceneWarnings {
    /// Faces dropped because their area was zero or negligible (slivers, repeated vertices).
    pub degenerate_faces: usize,
    /// Quads dropped because they were not planar and convex.
    pub nonplanar_faces: usize,
    /// Polygons with more than four vertices that were split into triangles (a fan from vertex 0).
    pub polygons_triangulated: usize,
}

impl SceneWarnings {
    /// Whether anything was counted.
    pub fn is_empty(&self) -> bool {
        *self == Self::default()
    }
}

/// A validated scene.
#[derive(Clone, Debug)]
pub struct Scene {
    /// A short name for output (file stem or builtin name).
    pub name: String,
    /// Vertex positions.
    pub vertices: Vec<DVec3>,
    /// Faces.
    pub faces: Vec<Face>,
    /// Materials, indexed by [`Face::material`].
    pub materials: Vec<Material>,
    /// The camera, if the scene has one.
    pub camera: Option<Camera>,
    /// What the builder dropped or changed.
    pub warnings: SceneWarnings,
    bounds: (DVec3, DVec3),
}

impl Scene {
    /// The face's polygon.
    pub fn polygon(&self, f: FaceId) -> Polygon {
        let face = &self.faces[f];
        let v = |k: usize| self.vertices[face.indices[k] as usize];
        if face.vertex_count() == 3 {
            Polygon::triangle(v(0), v(1), v(2))
        } else {
            Polygon::quad(v(0), v(1), v(2), v(3))
        }
    }

    /// The face's material.
    pub fn material(&self, f: FaceId) -> &Material {
        &self.materials[self.faces[f].material as usize]
    }

    /// Reflectance of a face.
    pub fn reflectance(&self, f: FaceId) -> Rgb {
        self.material(f).reflectance
    }

    /// Emission (radiant exitance, W/m²) of a face.
    pub fn emission(&self, f: FaceId) -> Rgb {
        self.material(f).emission
    }

    /// Number of faces.
    pub fn face_count(&self) -> usize {
        self.faces.len()
    }

    /// Axis-aligned bounds (min, max) of the vertices in use.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        self.bounds
    }

    /// Length of the bounding-box diagonal: the scene's scale, from which scale-free defaults derive.
    pub fn diagonal(&self) -> f64 {
        (self.bounds.1 - self.bounds.0).length()
    }

    /// Whether the faces form a closed surface: every edge, matched by position (vertices within 1e-9 of the
    /// diagonal are one), is shared by exactly two faces. Then every point sees only the scene's own faces, so
    /// a furnace (one material) has B = E/(1 − ρ) everywhere.
    pub fn is_closed(&self) -> bool {
        type GridPoint = (i64, i64, i64);
        let q = 1e-9 * self.diagonal();
        let key = |p: DVec3| {
            (
                (p.x / q).round() as i64,
                (p.y / q).round() as i64,
                (p.z / q).round() as i64,
            )
        };
        let mut edges: std::collections::HashMap<(GridPoint, GridPoint), u32> =
            std::collections::HashMap::new();
        for f in 0..self.faces.len() {
            let poly = self.polygon(f);
            let v = poly.vertices();
            for k in 0..v.len() {
                let (a, b) = (key(v[k]), key(v[(k + 1) % v.len()]));
                *edges
                    .entry(if a < b { (a, b) } else { (b, a) })
                    .or_default() += 1;
            }
        }
        edges.values().all(|&c| c == 2)
    }

    /// Faces whose material emits.
    pub fn emitters(&self) -> Vec<FaceId> {
        (0..self.faces.len())
            .filter(|&f| self.material(f).is_emitter())
            .collect()
    }

    /// Total emitted power per channel, Σ A_i E_i (W).
    pub fn emitted_power(&self) -> Rgb {
        (0..self.faces.len())
            .map(|f| self.faces[f].area * self.emission(f))
            .sum()
    }

    /// Total surface area.
    pub fn total_area(&self) -> f64 {
        self.faces.iter().map(|f| f.area).sum()
    }

    /// Approximate heap bytes held by the scene (for memory reports).
    pub fn bytes(&self) -> usize {
        self.vertices.len() * size_of::<DVec3>() + self.faces.len() * size_of::<Face>()
    }
}

/// Accumulates vertices, materials and polygons, validating each, then builds a [`Scene`].
#[derive(Clone, Debug, Default)]
pub struct SceneBuilder {
    name: String,
    vertices: Vec<DVec3>,
    faces: Vec<Face>,
    materials: Vec<Material>,
    camera: Option<Camera>,
    warnings: SceneWarnings,
}

/// Relative tolerance for planarity and convexity of quads, and for degenerate area (relative to the squared
/// diameter of the polygon).
pub const DEGENERATE_REL_TOL: f64 = 1e-9;

impl SceneBuilder {
    /// An empty builder for a scene of that name.
    pub fn new(name: &str) -> Self {
        Self {
            name: name.to_string(),
            ..Self::default()
        }
    }

    /// Adds a material (validated) and returns its index.
    pub fn add_material(&mut self, m: Material) -> Result<u32, SceneError> {
        m.validate()?;
        self.materials.push(m);
        Ok((self.materials.len() - 1) as u32)
    }

    /// Index of the material with that name, if any.
    pub fn material_index(&self, name: &str) -> Option<u32> {
        self.materials
            .iter()
            .position(|m| m.name == name)
            .map(|i| i as u32)
    }

    /// Adds a vertex, rejecting non-finite coordinates. `what` names the source for the message
    /// (e.g. "room.obj line 12").
    pub fn add_vertex(&mut self, p: DVec3, what: &str) -> Result<u32, SceneError> {
        if !p.is_finite() {
            return Err(SceneError::Invalid {
                field: what.to_string(),
                message: format!(
                    "vertex ({}, {}, {}) is not finite; every coordinate must be a finite number",
                    p.x, p.y, p.z
                ),
            });
        }
        self.vertices.push(p);
        Ok((self.vertices.len() - 1) as u32)
    }

    /// Number of vertices so far (the index the next vertex gets).
    pub fn vertex_count(&self) -> usize {
        self.vertices.len()
    }

    /// Adds a polygon over existing vertex indices. Triangles and planar convex quads are kept as they are;
    /// larger polygons are fanned into triangles (counted); degenerate ones are dropped (counted).
    /// Returns the number of faces added.
    pub fn add_polygon(
        &mut self,
        idx: &[u32],
        material: u32,
        what: &str,
    ) -> Result<usize, SceneError> {
        if idx.len() < 3 {
            return Err(SceneError::Invalid {
                field: what.to_string(),
                message: format!(
                    "a face needs at least 3 vertices, this one has {}",
                    idx.len()
                ),
            });
        }
        if material as usize >= self.materials.len() {
            return Err(SceneError::Invalid {
                field: what.to_string(),
                message: format!(
                    "material index {material} does not exist ({} materials defined)",
                    self.materials.len()
                ),
            });
        }
        for &i in idx {
            if i as usize >= self.vertices.len() {
                return Err(SceneError::Invalid {
                    field: what.to_string(),
                    message: format!(
                        "vertex index {i} is out of range ({} vertices defined)",
                        self.vertices.len()
                    ),
                });
            }
        }
        if idx.len() > 4 {
            self.warnings.polygons_triangulated += 1;
            let mut added = 0;
            for k in 1..idx.len() - 1 {
                added += self.push_face(&[idx[0], idx[k], idx[k + 1]], material);
            }
            return Ok(added);
        }
        if idx.len() == 4 {
            let q = self.poly(idx);
            if !q.is_planar_convex(1e-6) && q.area() > 0.0 {
                // A non-planar or non-convex quad becomes two triangles, split along its shorter diagonal.
                let v = |k: usize| self.vertices[idx[k] as usize];
                let (d02, d13) = ((v(2) - v(0)).length(), (v(3) - v(1)).length());
                self.warnings.nonplanar_faces += 1;
                return Ok(if d02 <= d13 {
                    self.push_face(&[idx[0], idx[1], idx[2]], material)
                        + self.push_face(&[idx[0], idx[2], idx[3]], material)
                } else {
                    self.push_face(&[idx[0], idx[1], idx[3]], material)
                        + self.push_face(&[idx[1], idx[2], idx[3]], material)
                });
            }
        }
        Ok(self.push_face(idx, material))
    }

    fn poly(&self, idx: &[u32]) -> Polygon {
        let pts: Vec<DVec3> = idx.iter().map(|&i| self.vertices[i as usize]).collect();
        Polygon::from_slice(&pts).expect("3 or 4 vertices")
    }

    fn push_face(&mut self, idx: &[u32], material: u32) -> usize {
        let p = self.poly(idx);
        let d = p.diameter();
        let area = p.area();
        if !(area > DEGENERATE_REL_TOL * d * d) || !area.is_finite() {
            self.warnings.degenerate_faces += 1;
            return 0;
        }
        let mut indices = [u32::MAX; 4];
        indices[..idx.len()].copy_from_slice(idx);
        self.faces.push(Face {
            indices,
            material,
            normal: p.normal(),
            area,
            centroid: p.centroid(),
        });
        1
    }

    /// Adds a polygon given by its vertex positions (3 or more), creating the vertices.
    pub fn add_polygon_points(
        &mut self,
        pts: &[DVec3],
        material: u32,
        what: &str,
    ) -> Result<usize, SceneError> {
        let mut idx = Vec::with_capacity(pts.len());
        for &p in pts {
            idx.push(self.add_vertex(p, what)?);
        }
        self.add_polygon(&idx, material, what)
    }

    /// Sets the camera.
    pub fn set_camera(&mut self, c: Camera) {
        self.camera = Some(c);
    }

    /// Counted warnings so far (mutable, for readers that drop input themselves).
    pub fn warnings_mut(&mut self) -> &mut SceneWarnings {
        &mut self.warnings
    }

    /// Number of faces so far.
    pub fn face_count(&self) -> usize {
        self.faces.len()
    }

    /// Builds the scene. Fails if no face survived.
    pub fn build(self) -> Result<Scene, SceneError> {
        if self.faces.is_empty() {
            return Err(SceneError::Invalid {
                field: self.name.clone(),
                message: "the scene has no usable faces (all were missing or degenerate)".into(),
            });
        }
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for f in &self.faces {
            for &i in f.vertex_indices() {
                lo = lo.min(self.vertices[i as usize]);
                hi = hi.max(self.vertices[i as usize]);
            }
        }
        Ok(Scene {
            name: self.name,
            vertices: self.vertices,
            faces: self.faces,
            materials: self.materials,
            camera: self.camera,
            warnings: self.warnings,
            bounds: (lo, hi),
        })
    }
}

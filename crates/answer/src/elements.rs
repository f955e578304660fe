//! A fixed element mesh over the scene: each input face regularly subdivided into elements no longer than a
//! target size along an edge (quads into bilinear grids, triangles into m² triangles). Matrix, progressive and
//! mesh-based Monte Carlo radiosity all solve over such a mesh; the element containing a surface point is found
//! by [`ElementMesh::locate`] (the shared [`ElementLocator`], O(1) per query).

use std::ops::Range;

use glam::DVec3;

use crate::gouraud::ElementValue;
use crate::locate::{ElementLocator, ElementTree};
use radlab_method::SolveError;
use radlab_scene::{FaceId, Polygon, Rgb, Scene};

/// The default element size as a fraction of the scene's bounding-box diagonal, so every scene's scale gets the
/// same mesh: 1/25 of the diagonal gives the Cornell box about 1,700 elements. Chosen by the worst case of the
/// suite of scenes in `experiments/defaults-suite.toml`: at 1/20 matrix, progressive and mesh Monte Carlo
/// radiosity answered the Cornell box's contact shadows beside the blocks 22-30% off at their worst point (the
/// element means there are those of strips 47 mm wide, lit parts and shadowed ones together), at 1/25 within
/// 8-15% over three seeds, for about twice the time of matrix and progressive radiosity (docs/defaults.md).
/// Matrix and mesh Monte Carlo radiosity's default; progressive radiosity's is 1/30 (its floors and walls,
/// 2026-12-07).
pub const DEFAULT_ELEMENT_SIZE_REL: f64 = 0.04;

/// One element: a piece of an input face.
#[derive(Clone, Copy, Debug)]
pub struct Element {
    /// The input face it belongs to.
    pub face: u32,
    /// Its geometry.
    pub polygon: Polygon,
    /// Area.
    pub area: f64,
    /// Centroid.
    pub centroid: DVec3,
}

/// Elements grouped by input face.
#[derive(Clone, Debug)]
pub struct ElementMesh {
    /// All elements, those of face f contiguous in [`ElementMesh::elements_of`]\(f).
    pub elements: Vec<Element>,
    face_start: Vec<u32>,
    /// The element size it was meshed to, in scene units.
    pub element_size: f64,
    locator: ElementLocator,
}

/// The mesh's elements and face ranges, as the locator sees them (no element has children).
struct Flat<'a> {
    elements: &'a [Element],
    face_start: &'a [u32],
}

impl ElementTree for Flat<'_> {
    fn roots(&self, face: FaceId) -> Range<u32> {
        match (self.face_start.get(face), self.face_start.get(face + 1)) {
            (Some(&a), Some(&b)) => a..b,
            _ => 0..0,
        }
    }

    fn polygon(&self, e: u32) -> Option<&Polygon> {
        self.elements.get(e as usize).map(|el| &el.polygon)
    }

    fn children(&self, _e: u32) -> Range<u32> {
        0..0
    }
}

impl ElementMesh {
    /// Meshes every face to elements no longer than `element_size` along an edge.
    pub fn new(scene: &Scene, element_size: f64) -> Self {
        let mut elements = Vec::new();
        let mut face_start = Vec::with_capacity(scene.faces.len() + 1);
        for f in 0..scene.faces.len() {
            face_start.push(elements.len() as u32);
            for polygon in scene.polygon(f).subdivide(element_size) {
                elements.push(Element {
                    face: f as u32,
                    area: polygon.area(),
                    centroid: polygon.centroid(),
                    polygon,
                });
            }
        }
        face_start.push(elements.len() as u32);
        let locator = ElementLocator::new(
            scene,
            &Flat {
                elements: &elements,
                face_start: &face_start,
            },
        );
        Self {
            elements,
            face_start,
            element_size,
            locator,
        }
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        self.elements.len()
    }

    /// Whether there are no elements.
    pub fn is_empty(&self) -> bool {
        self.elements.is_empty()
    }

    /// The elements of face `f`.
    pub fn elements_of(&self, f: FaceId) -> Range<usize> {
        self.face_start[f] as usize..self.face_start[f + 1] as usize
    }

    /// The element of face `f` that contains `point` (the nearest one if the point lies slightly outside).
    pub fn locate(&self, f: FaceId, point: DVec3) -> usize {
        let flat = Flat {
            elements: &self.elements,
            face_start: &self.face_start,
        };
        match self.locator.locate(&flat, f, point) {
            Some(e) => e as usize,
            None => self.elements_of(f).start,
        }
    }

    /// Approximate heap bytes held.
    pub fn bytes(&self) -> usize {
        self.elements.len() * size_of::<Element>()
            + self.face_start.len() * 4
            + self.locator.bytes()
    }

    /// Every element with its value from `radiosity` (in element order), as the reconstructions take them.
    pub fn values(&self, radiosity: &[Rgb]) -> Vec<ElementValue> {
        self.elements
            .iter()
            .zip(radiosity)
            .map(|(e, &b)| ElementValue {
                face: e.face as FaceId,
                polygon: e.polygon,
                radiosity: b,
                open: 1.0,
            })
            .collect()
    }
}

/// The default element size for a scene: [`DEFAULT_ELEMENT_SIZE_REL`] × its bounding-box diagonal.
pub fn default_element_size(scene: &Scene) -> f64 {
    DEFAULT_ELEMENT_SIZE_REL * scene.diagonal()
}

/// The element size a method meshes `scene` with: `size` when set, else [`default_element_size`]; refused,
/// naming the `element_size` parameter, when that is not a positive finite length (the default of a
/// degenerate scene, e.g. one whose bounding diagonal is zero or infinite).
pub fn element_size(size: Option<f64>, scene: &Scene) -> Result<f64, SolveError> {
    element_size_or(size, DEFAULT_ELEMENT_SIZE_REL, scene)
}

/// [`element_size`] for a method whose default is `default_rel` × the scene's bounding-box diagonal.
pub fn element_size_or(
    size: Option<f64>,
    default_rel: f64,
    scene: &Scene,
) -> Result<f64, SolveError> {
    let size = size.unwrap_or_else(|| default_rel * scene.diagonal());
    if size.is_finite() && size > 0.0 {
        Ok(size)
    } else {
        Err(SolveError::param(
            "element_size",
            format!(
                "the default element size {size} is unusable for scene '{}' (bounding diagonal {}); set \
                 element_size to a length > 0",
                scene.name,
                scene.diagonal()
            ),
        ))
    }
}

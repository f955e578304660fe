//! Substructuring (Cohen, Greenberg, Immel & Brock 1986, "An efficient radiosity approach for realistic image
//! synthesis"): a two-level mesh in which coarse *patches* shoot and finer *elements* receive.
//!
//! Every face is split regularly into patches no longer than `patch_size`, every patch regularly into elements
//! no longer than `element_size`, and adaptive subdivision later splits elements into quadtrees
//! ([`radlab_scene::Polygon::split4`]). A patch's radiosity is the area-weighted mean of its elements
//! (Cohen et al. 1986):
//!
//! B_p = Σ_{e ⊂ p} A_e B_e / A_p,
//!
//! and the radiosity it shoots is its unshot part ΔB_p. Each patch keeps the invariant B_p = S_p + ΔB_p, where
//! S_p is the total radiosity it has shot so far; that total is what elements created later re-gather from.
//!
//! Radiosities are those of the open parts ([`radlab_kernels::open_fraction`]): an element with open share o_e
//! holds B_e over o_e A_e, and the means above are taken over the open areas, B_p = Σ_e o_e A_e B_e / Σ_e o_e
//! A_e, so an element half under a floor covering neither absorbs nor sends the light its sealed half cannot
//! receive. An element with no open probe point divides its (next to nothing) gains by 1 but weighs 0 in its
//! patch's means: counted at o = 1 it diluted a patch along a block's foot, whose shots' visibility rays then
//! discounted the sealed area a second time (the Cornell box's points 0.41% low, 0.00% since). Where nothing is
//! sealed every o_e is 1 and these are the plain area means.

use radlab_kernels::open_fraction::{open_fraction, open_shares};
use radlab_method::SolveError;
use radlab_scene::{Polygon, Rgb, Scene};
use radlab_visibility::Accel;

/// A shooting patch.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Patch {
    /// Its geometry.
    pub polygon: Polygon,
    /// Open area Σ_e o_e A_e over its leaves; until the open shares are estimated, its area (the sum of its
    /// elements' areas, so area means over elements are exact).
    pub open_area: f64,
    /// The input face it belongs to.
    pub face: u32,
    /// Whether its face emits (its shots are direct light).
    pub emits: bool,
    /// Unshot radiosity ΔB_p (W/m²). May turn negative: after adaptive subdivision corrects B_p, and whenever
    /// the patch has shot more than it held (overshooting).
    pub unshot: Rgb,
    /// Whether light has reached it: it emits, or some shot or re-gather changed its radiosity. Only such
    /// patches overshoot, so light never enters a part of the scene no light reaches.
    pub lit: bool,
    /// Total radiosity shot so far, S_p.
    pub shot: Rgb,
    /// Its top-level elements: `first_root .. first_root + root_count` in the element arena.
    pub first_root: u32,
    /// Number of top-level elements.
    pub root_count: u32,
}

/// An element: a node of the element quadtrees (leaves receive and carry the solution).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Element {
    /// Its geometry.
    pub polygon: Polygon,
    /// Area.
    pub area: f64,
    /// The input face it lies on.
    pub face: u32,
    /// The patch it belongs to.
    pub patch: u32,
    /// First of its four children (consecutive), or [`LEAF`].
    pub first_child: u32,
    /// Open share o_e of its area (1 until estimated; [`radlab_kernels::open_fraction::open_fraction`]: 1 also
    /// where no probe point is open, the divisor of what it receives).
    pub open: f64,
    /// No probe point of it is open: it receives nothing and sends nothing, so it weighs nothing in its patch's
    /// mean ([`Element::open_area`]).
    pub sealed: bool,
}

impl Element {
    /// Its open area o_e A_e: the weight of its radiosity in its patch's mean and of its gains in its patch's
    /// unshot radiosity; 0 for a sealed element. A patch's sealed elements counted at o = 1 held its radiosity
    /// as a mean over area no light reaches, which its shots then sent through visibility rays that their sealed
    /// points block: the light of a patch straddling a contact was counted out twice.
    pub fn open_area(&self) -> f64 {
        if self.sealed {
            0.0
        } else {
            self.open * self.area
        }
    }
}

/// `first_child` of a leaf.
pub(crate) const LEAF: u32 = u32::MAX;

impl Element {
    /// Whether it has no children.
    pub fn is_leaf(&self) -> bool {
        self.first_child == LEAF
    }
}

/// Patches, the element arena and the current leaves.
#[derive(Clone, Debug)]
pub(crate) struct Mesh {
    /// All patches, those of face f contiguous and in face order.
    pub patches: Vec<Patch>,
    /// All elements ever created (split ones stay, as interior quadtree nodes).
    pub elements: Vec<Element>,
    /// Radiosity B_e (W/m²) of each element's open part, including emission, by element index. Meaningful for
    /// leaves; a split element keeps its last value. Kept apart from [`Element`] so that a shot writes, and the
    /// contrast scan of adaptive subdivision reads, one compact array.
    pub radiosity: Vec<Rgb>,
    /// The leaves, in ascending element index.
    pub leaves: Vec<u32>,
    /// Top-level elements of face f: `face_roots[f] .. face_roots[f + 1]`.
    pub face_roots: Vec<u32>,
}

/// Slack on the element size so a patch cut to exactly `element_size` is not split again by rounding.
const SIZE_SLACK: f64 = 1.0 + 1e-9;

/// Pieces [`Polygon::subdivide`] makes of `poly` at `size`.
pub(crate) fn piece_count(poly: &Polygon, size: f64) -> f64 {
    let (nu, nv) = poly.subdivision(size);
    (nu * nv) as f64
}

/// Bytes held per element, for budgets and reports: the element and its radiosity, its leaf entry, its place in
/// the face grid and its share of the neighbour pairs.
pub(crate) const BYTES_PER_ELEMENT: f64 =
    (size_of::<Element>() + size_of::<Rgb>() + 4 + 8 + 4 * 8) as f64;

impl Mesh {
    /// Meshes every face into patches of `patch_size` and elements of `element_size`. Emitting faces start with
    /// B = ΔB = E; the rest with zero. Refuses a mesh whose estimated size exceeds `budget_bytes`.
    pub fn new(
        scene: &Scene,
        patch_size: f64,
        element_size: f64,
        budget_bytes: f64,
    ) -> Result<Self, SolveError> {
        // Upper bound on the element count before allocating anything: per direction, a face of length L cut
        // into k patches then into elements has at most ceil(L / element_size) + k pieces.
        let mut estimate = 0.0;
        for f in 0..scene.face_count() {
            let poly = scene.polygon(f);
            let p = piece_count(&poly, patch_size);
            let e = piece_count(&poly, element_size);
            estimate += (e.sqrt() + p.sqrt()).powi(2);
        }
        let needed = estimate * BYTES_PER_ELEMENT;
        if needed > budget_bytes {
            return Err(SolveError::over_budget(
                "the progressive radiosity element mesh",
                needed as u64,
                budget_bytes as u64,
                "raise element_size (and patch_size) or memory_budget_mib",
            ));
        }
        let mut patches = Vec::new();
        let mut elements = Vec::new();
        let mut radiosity = Vec::new();
        let mut face_roots = Vec::with_capacity(scene.face_count() + 1);
        for f in 0..scene.face_count() {
            face_roots.push(elements.len() as u32);
            let e_face = scene.emission(f);
            for pp in scene.polygon(f).subdivide(patch_size) {
                let first_root = elements.len() as u32;
                let pieces = if patch_size == element_size {
                    vec![pp]
                } else {
                    pp.subdivide(element_size * SIZE_SLACK)
                };
                let mut area = 0.0;
                for polygon in pieces {
                    let a = polygon.area();
                    area += a;
                    elements.push(Element {
                        polygon,
                        area: a,
                        face: f as u32,
                        patch: patches.len() as u32,
                        first_child: LEAF,
                        open: 1.0,
                        sealed: false,
                    });
                    radiosity.push(e_face);
                }
                patches.push(Patch {
                    polygon: pp,
                    open_area: area,
                    face: f as u32,
                    emits: scene.material(f).is_emitter(),
                    unshot: e_face,
                    lit: e_face != Rgb::ZERO,
                    shot: Rgb::ZERO,
                    first_root,
                    root_count: elements.len() as u32 - first_root,
                });
            }
        }
        face_roots.push(elements.len() as u32);
        let leaves = (0..elements.len() as u32).collect();
        Ok(Self {
            patches,
            elements,
            radiosity,
            leaves,
            face_roots,
        })
    }

    /// Top-level elements of face `f`.
    #[cfg(test)]
    pub fn roots_of(&self, f: usize) -> std::ops::Range<usize> {
        self.face_roots[f] as usize..self.face_roots[f + 1] as usize
    }

    /// The leaves below element `e` (itself if a leaf), in depth-first order.
    pub fn leaves_below(&self, e: u32, out: &mut Vec<u32>) {
        let el = &self.elements[e as usize];
        if el.is_leaf() {
            out.push(e);
        } else {
            for c in el.first_child..el.first_child + 4 {
                self.leaves_below(c, out);
            }
        }
    }

    /// Estimates the open share of every element (the roots, before any split) and sets each patch's open
    /// area from them; returns the rays cast. The stream of element e is keyed by e.
    pub(crate) fn estimate_open(&mut self, scene: &Scene, accel: &Accel, seed: u64) -> u64 {
        let rays = self.estimate_open_of(scene, accel, seed, 0..self.elements.len());
        for p in 0..self.patches.len() {
            let patch = self.patches[p];
            let roots = patch.first_root as usize..(patch.first_root + patch.root_count) as usize;
            self.patches[p].open_area = self.elements[roots].iter().map(Element::open_area).sum();
        }
        rays
    }

    /// Estimates the open share of the elements in `range`; returns the rays cast.
    pub(crate) fn estimate_open_of(
        &mut self,
        scene: &Scene,
        accel: &Accel,
        seed: u64,
        range: std::ops::Range<usize>,
    ) -> u64 {
        let first = range.start;
        let (shares, rays) = open_shares(
            scene,
            accel,
            &self.elements[range],
            |e| (&e.polygon, e.face as usize),
            seed,
            first as u64,
        );
        for (k, share) in shares.into_iter().enumerate() {
            let el = &mut self.elements[first + k];
            el.open = open_fraction(share);
            el.sealed = share == 0.0;
        }
        rays
    }

    /// Radiosity of patch `p`: the open-area-weighted mean of its leaves (Cohen et al. 1986).
    pub fn patch_radiosity(&self, p: usize) -> Rgb {
        let patch = &self.patches[p];
        let mut leaves = Vec::new();
        for r in patch.first_root..patch.first_root + patch.root_count {
            self.leaves_below(r, &mut leaves);
        }
        let sum: Rgb = leaves
            .iter()
            .map(|&e| self.radiosity[e as usize] * self.elements[e as usize].open_area())
            .sum();
        if patch.open_area > 0.0 {
            sum / patch.open_area
        } else {
            // Wholly sealed: the area mean of what its elements hold (their emission).
            let area: f64 = leaves.iter().map(|&e| self.elements[e as usize].area).sum();
            leaves
                .iter()
                .map(|&e| self.radiosity[e as usize] * self.elements[e as usize].area)
                .sum::<Rgb>()
                / area
        }
    }

    /// Splits the leaves `marked` (ascending) into four children each ([`Polygon::split4`]), appended in the
    /// order of their parents with the parents' radiosity, and updates the leaf list (ascending); returns the
    /// index of the first child.
    pub(crate) fn split_leaves(&mut self, marked: &[u32]) -> usize {
        let first_new = self.elements.len();
        for &e in marked {
            let parent = self.elements[e as usize];
            let b = self.radiosity[e as usize];
            self.elements[e as usize].first_child = self.elements.len() as u32;
            for polygon in parent.polygon.split4() {
                self.elements.push(Element {
                    polygon,
                    area: polygon.area(),
                    first_child: LEAF,
                    ..parent
                });
                self.radiosity.push(b);
            }
        }
        let elements = &self.elements;
        self.leaves.retain(|&e| elements[e as usize].is_leaf());
        self.leaves
            .extend(first_new as u32..self.elements.len() as u32);
        first_new
    }

    /// Approximate heap bytes held.
    pub fn bytes(&self) -> usize {
        self.patches.capacity() * size_of::<Patch>()
            + self.elements.capacity() * size_of::<Element>()
            + self.radiosity.capacity() * size_of::<Rgb>()
            + self.leaves.capacity() * 4
            + self.face_roots.capacity() * 4
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn elements_nest_in_patches_and_conserve_area() {
        let scene = radlab_scene::builtin("furnace-cube?tessellation=1&emission=2").expect("scene");
        let m = Mesh::new(&scene, 0.5, 0.25, 1e9).expect("mesh");
        assert_eq!(m.patches.len(), 6 * 4);
        assert_eq!(m.elements.len(), 6 * 16);
        assert_eq!(m.leaves.len(), m.elements.len());
        for (p, patch) in m.patches.iter().enumerate() {
            assert_eq!(patch.root_count, 4);
            assert!((patch.open_area - patch.polygon.area()).abs() < 1e-14);
            for r in patch.first_root..patch.first_root + patch.root_count {
                let e = &m.elements[r as usize];
                assert_eq!(e.patch as usize, p);
                assert!(patch.polygon.contains(e.polygon.centroid(), 1e-12));
            }
            // Patch radiosity is the area mean: B = E = 2 everywhere here, and B_p = S_p + ΔB_p.
            let b = m.patch_radiosity(p);
            assert!((b - Rgb::splat(2.0)).abs().max_element() < 1e-14);
            assert_eq!(patch.unshot + patch.shot, b);
        }
        // patch_size == element_size: one element per patch, identical to the scene's ElementMesh.
        let m = Mesh::new(&scene, 0.25, 0.25, 1e9).expect("mesh");
        let reference = radlab_answer::ElementMesh::new(&scene, 0.25);
        assert_eq!(m.elements.len(), reference.len());
        for (a, b) in m.elements.iter().zip(&reference.elements) {
            assert_eq!(a.polygon, b.polygon);
        }
    }

    #[test]
    fn over_budget_is_refused_before_allocating() {
        let scene = radlab_scene::builtin("furnace-cube").expect("scene");
        let e = Mesh::new(&scene, 1e-4, 1e-4, 1e9)
            .expect_err("too many elements")
            .to_string();
        assert!(e.contains("memory_budget_mib"), "{e}");
    }
}

//! Adaptive subdivision of receiving elements (Cohen, Greenberg, Immel & Brock 1986; used with progressive
//! refinement by Cohen, Chen, Wallace & Greenberg 1988).
//!
//! Two elements of one face are neighbours when a point just outside an edge of one (at a quarter and three
//! quarters along the edge) lies in the other. Where neighbouring radiosities differ by more than a threshold,
//!
//! |B_a − B_b| / max(B_a, B_b) > τ   (B summed over the RGB channels),
//!
//! both are split into four ([`radlab_scene::Polygon::split4`]) unless that would make an edge shorter than the
//! minimum element size. A new element e gets its radiosity by re-gathering from every patch shot so far:
//!
//! B_e = E_e + ρ_e Σ_j F_{e→j} S_j,
//!
//! S_j the total radiosity patch j has shot — exactly what e would hold had it existed from the start, since
//! every shot of j adds ρ_e F_{e→j} ΔB_j with the same factor (divided by the child's open share o_c, as
//! every gain is: [`crate::substructuring`]). The parent's patch then corrects its unshot radiosity by the
//! change of its mean radiosity, ΔB_p += Σ_c A_c B_c / A_p − A_e B_e / A_p (areas open areas, and the
//! patch's open area updated when the children's open shares differ from their parent's), keeping
//! B_p = S_p + ΔB_p. Splitting repeats until no neighbour pair exceeds the threshold or the minimum size is
//! reached.

use glam::DVec3;
use radlab_method::SolveError;
use radlab_scene::{Rgb, Scene};
use radlab_visibility::Accel;
use rayon::prelude::*;

use crate::element_location::ElementLocator;
use crate::shooting::{Kernel, Work, element_patch_factor};
use crate::substructuring::{BYTES_PER_ELEMENT, Element, Mesh};

/// Where along an edge the neighbour probes go.
const PROBE_AT: [f64; 2] = [0.25, 0.75];
/// How far outside an edge a probe goes, relative to the element's longest edge.
const PROBE_OFFSET: f64 = 1e-4;

/// Relative contrast |a − b| / max(a, b) of two radiosities (channel sums); 0 when both are 0.
pub(crate) fn contrast(a: Rgb, b: Rgb) -> f64 {
    let (ga, gb) = (a.element_sum(), b.element_sum());
    let m = ga.abs().max(gb.abs());
    if m > 0.0 { (ga - gb).abs() / m } else { 0.0 }
}

/// The neighbour pairs (e.min(o), e.max(o)) that leaf `e`'s edge probes find.
fn probe(scene: &Scene, mesh: &Mesh, locator: &ElementLocator, e: u32) -> Vec<(u32, u32)> {
    let el = &mesh.elements[e as usize];
    let n = scene.faces[el.face as usize].normal;
    let v = el.polygon.vertices();
    let offset = PROBE_OFFSET * el.polygon.max_edge();
    let mut out = Vec::with_capacity(2 * v.len());
    for k in 0..v.len() {
        let (a, b) = (v[k], v[(k + 1) % v.len()]);
        let outward = (b - a).cross(n).normalize_or_zero();
        for t in PROBE_AT {
            let p: DVec3 = a.lerp(b, t) + offset * outward;
            match locator.locate_containing(mesh, el.face as usize, p) {
                Some(o) if o != e => out.push((e.min(o), e.max(o))),
                _ => {}
            }
        }
    }
    out
}

/// Neighbouring leaf pairs (a < b), sorted, each once: the union of every leaf's probes.
pub(crate) fn neighbour_pairs(
    scene: &Scene,
    mesh: &Mesh,
    locator: &ElementLocator,
) -> Vec<(u32, u32)> {
    let mut pairs: Vec<(u32, u32)> = mesh
        .leaves
        .par_iter()
        .flat_map_iter(|&e| probe(scene, mesh, locator, e))
        .collect();
    pairs.sort_unstable();
    pairs.dedup();
    pairs
}

/// The neighbour pairs after the elements `split` (sorted) were split, from the pairs before: the union of
/// every leaf's probes again, probing only the leaves whose probes can have changed. A leaf's probes change
/// only if it is new (a child) or a probe of it landed in a split element, which then had a pair with it; the
/// other leaves' probes, and the pairs they found, are as before. Equal to [`neighbour_pairs`] on the new
/// leaves (tested), at the cost of the changed neighbourhood instead of the whole mesh.
fn update_pairs(
    scene: &Scene,
    mesh: &Mesh,
    locator: &ElementLocator,
    pairs: &[(u32, u32)],
    split: &[u32],
    first_new: u32,
) -> Vec<(u32, u32)> {
    let was_split = |e: u32| split.binary_search(&e).is_ok();
    let mut reprobe: Vec<u32> = (first_new..mesh.elements.len() as u32).collect();
    let mut kept = Vec::with_capacity(pairs.len());
    for &(a, b) in pairs {
        match (was_split(a), was_split(b)) {
            (false, false) => kept.push((a, b)),
            (true, false) => reprobe.push(b),
            (false, true) => reprobe.push(a),
            (true, true) => {}
        }
    }
    reprobe.sort_unstable();
    reprobe.dedup();
    let mut found: Vec<(u32, u32)> = reprobe
        .par_iter()
        .flat_map_iter(|&e| probe(scene, mesh, locator, e))
        .collect();
    found.sort_unstable();
    found.dedup();
    union_sorted(&kept, &found)
}

/// The union of two ascending lists without repeats, ascending and without repeats (a merge: the kept pairs
/// are most of the list, and sorting them again would cost O(n log n) on every refinement).
fn union_sorted<T: Ord + Copy>(a: &[T], b: &[T]) -> Vec<T> {
    let mut out = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut k) = (0, 0);
    while let (Some(&x), Some(&y)) = (a.get(i), b.get(k)) {
        match x.cmp(&y) {
            std::cmp::Ordering::Less => {
                out.push(x);
                i += 1;
            }
            std::cmp::Ordering::Greater => {
                out.push(y);
                k += 1;
            }
            std::cmp::Ordering::Equal => {
                out.push(x);
                i += 1;
                k += 1;
            }
        }
    }
    out.extend_from_slice(&a[i..]);
    out.extend_from_slice(&b[k..]);
    out
}

/// Settings of a refinement pass.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Refinement {
    /// Contrast above which neighbours split.
    pub threshold: f64,
    /// Smallest edge a child may have.
    pub min_element_size: f64,
    /// Most elements the arena may hold.
    pub max_elements: usize,
    /// Whether new elements get their own open share ([`radlab_kernels::open_fraction`]); otherwise they keep
    /// their parent's.
    pub estimate_open: bool,
}

/// Whether `el` may be split: its children's longest edge would not fall below the minimum size.
fn splittable(el: &Element, min_size: f64) -> bool {
    0.5 * el.polygon.max_edge() >= min_size * (1.0 - 1e-9)
}

/// Neighbour pairs per rayon task of the contrast scan.
const SCAN_RUN: usize = 1024;

/// Appends to `out` the elements to split among `pairs`: both of every pair whose contrast exceeds the
/// threshold, each if it is splittable (unsorted, with repeats).
fn marked_in(
    pairs: &[(u32, u32)],
    elements: &[Element],
    radiosity: &[Rgb],
    r: &Refinement,
    out: &mut Vec<u32>,
) {
    for &(a, b) in pairs {
        if contrast(radiosity[a as usize], radiosity[b as usize]) > r.threshold {
            for e in [a, b] {
                if splittable(&elements[e as usize], r.min_element_size) {
                    out.push(e);
                }
            }
        }
    }
}

/// The elements to split among the neighbour `pairs` of the current leaves, at the current radiosities
/// (unsorted, with repeats): on rayon tasks when there are threads to share them.
pub(crate) fn scan(
    pairs: &[(u32, u32)],
    elements: &[Element],
    radiosity: &[Rgb],
    r: &Refinement,
) -> Vec<u32> {
    let mut marked = Vec::new();
    if rayon::current_num_threads() == 1 || pairs.len() <= SCAN_RUN {
        marked_in(pairs, elements, radiosity, r, &mut marked);
    } else {
        marked = pairs
            .par_chunks(SCAN_RUN)
            .flat_map_iter(|run| {
                let mut out = Vec::new();
                marked_in(run, elements, radiosity, r, &mut out);
                out
            })
            .collect();
    }
    marked
}

/// Splits leaves across contrasts above the threshold until none remain; new elements re-gather from every
/// patch shot so far. `pairs` holds the neighbour pairs of the current leaves and is kept up to date;
/// `scanned`, if given, is [`scan`] of the current mesh (taken alongside the last shot's sums). Returns the
/// number of elements split and the form-factor work.
#[allow(clippy::too_many_arguments)]
pub(crate) fn refine(
    scene: &Scene,
    accel: &Accel,
    kernel: &Kernel,
    mesh: &mut Mesh,
    locator: &ElementLocator,
    pairs: &mut Vec<(u32, u32)>,
    shot_patches: &[u32],
    r: &Refinement,
    mut scanned: Option<Vec<u32>>,
) -> Result<(usize, Work), SolveError> {
    let mut split_total = 0;
    let mut work = Work::default();
    loop {
        // Every step scans all pairs (sorted after, so the same on any number of threads).
        let mut marked = match scanned.take() {
            Some(m) => m,
            None => scan(pairs, &mesh.elements, &mesh.radiosity, r),
        };
        marked.sort_unstable();
        marked.dedup();
        if marked.is_empty() {
            return Ok((split_total, work));
        }
        let new_total = mesh.elements.len() + 4 * marked.len();
        if new_total > r.max_elements {
            return Err(SolveError::over_budget(
                "adaptive subdivision",
                (new_total as f64 * BYTES_PER_ELEMENT) as u64,
                (r.max_elements as f64 * BYTES_PER_ELEMENT) as u64,
                "raise min_element_size, adaptive_threshold or memory_budget_mib, or set adaptive = false",
            ));
        }
        let first_new = mesh.split_leaves(&marked);
        if r.estimate_open {
            let new = first_new..mesh.elements.len();
            work.rays += mesh.estimate_open_of(scene, accel, kernel.seed, new);
        }
        // Re-gather: B_c = E + ρ Σ_j F_cj S_j / o_c over the patches shot so far, in shot order.
        let elements = &mesh.elements;
        let patches = &mesh.patches;
        let gathered: Vec<(Rgb, Work)> = (first_new..elements.len())
            .into_par_iter()
            .map(|c| {
                let el = &elements[c];
                let f = el.face as usize;
                let rho = scene.reflectance(f);
                let mut sum = Rgb::ZERO;
                let mut w = Work::default();
                if rho != Rgb::ZERO {
                    for &j in shot_patches {
                        let p = &patches[j as usize];
                        let (ff, ww) =
                            element_patch_factor(scene, accel, kernel, el, c as u32, p, j);
                        w += ww;
                        sum += ff * p.shot;
                    }
                }
                (scene.emission(f) + rho * sum / el.open, w)
            })
            .collect();
        for (k, (b, w)) in gathered.into_iter().enumerate() {
            mesh.radiosity[first_new + k] = b;
            work += w;
        }
        // Correct each parent's patch by the change of its mean radiosity over the open area, which the
        // children's own open shares may change too: B_p = S_p + ΔB_p before and after.
        for &e in &marked {
            let parent = mesh.elements[e as usize];
            let c0 = parent.first_child as usize;
            let children = &mesh.elements[c0..c0 + 4];
            let after: Rgb = children
                .iter()
                .zip(&mesh.radiosity[c0..c0 + 4])
                .map(|(c, &b)| c.open_area() * b)
                .sum();
            let same_open = children
                .iter()
                .all(|c| c.open == parent.open && c.sealed == parent.sealed);
            let patch = &mut mesh.patches[parent.patch as usize];
            let d_sum = after - parent.open_area() * mesh.radiosity[e as usize];
            let before = patch.unshot;
            if same_open {
                // The children's areas sum to their parent's (up to rounding): the open area stays.
                if patch.open_area > 0.0 {
                    patch.unshot += d_sum / patch.open_area;
                }
            } else {
                let after_area: f64 = children.iter().map(|c| c.open_area()).sum();
                let d_area = after_area - parent.open_area();
                let b = patch.shot + patch.unshot;
                let area = patch.open_area + d_area;
                if area > 0.0 {
                    patch.unshot = (b * patch.open_area + d_sum) / area - patch.shot;
                }
                patch.open_area = area.max(0.0);
            }
            patch.lit |= patch.unshot != before;
        }
        split_total += marked.len();
        *pairs = update_pairs(scene, mesh, locator, pairs, &marked, first_new as u32);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn contrast_is_relative_and_symmetric() {
        let a = Rgb::new(1.0, 2.0, 3.0);
        assert_eq!(contrast(a, a), 0.0);
        assert!((contrast(a, 0.5 * a) - 0.5).abs() < 1e-15);
        assert_eq!(contrast(a, 0.5 * a), contrast(0.5 * a, a));
        assert_eq!(contrast(Rgb::ZERO, Rgb::ZERO), 0.0);
        // Scale-free: multiplying both by any factor keeps the contrast.
        assert!((contrast(1e-30 * a, 0.7e-30 * a) - contrast(a, 0.7 * a)).abs() < 1e-12);
    }

    #[test]
    fn union_of_sorted_lists_equals_sorting_both() {
        // Against sort + dedup of the concatenation, on lists with shared items, empty lists and runs of
        // either list beyond the other's end.
        let lists: [&[u32]; 5] = [&[], &[1, 4, 9], &[0, 1, 2, 9, 10], &[4], &[11, 12]];
        for a in lists {
            for b in lists {
                let mut expect = [a, b].concat();
                expect.sort_unstable();
                expect.dedup();
                assert_eq!(union_sorted(a, b), expect, "{a:?} ∪ {b:?}");
            }
        }
    }

    #[test]
    fn grid_neighbours_are_edge_sharing_elements_of_one_face() {
        let scene = radlab_scene::builtin("furnace-cube?tessellation=1").expect("scene");
        let mesh = Mesh::new(&scene, 1.0, 0.25, 1e9).expect("mesh");
        let loc = ElementLocator::new(&scene, &mesh);
        let pairs = neighbour_pairs(&scene, &mesh, &loc);
        // A 4 × 4 grid has 2 · 4 · 3 = 24 edge-sharing pairs; six faces.
        assert_eq!(pairs.len(), 6 * 24);
        for (a, b) in pairs {
            let (ea, eb) = (&mesh.elements[a as usize], &mesh.elements[b as usize]);
            assert_eq!(ea.face, eb.face);
            let d = (ea.polygon.centroid() - eb.polygon.centroid()).length();
            assert!((d - 0.25).abs() < 1e-12, "{d}");
        }
    }

    #[test]
    fn updated_pairs_equal_the_pairs_probed_afresh() {
        // Split a scattered set of leaves six times over (so finer leaves border coarser ones, the case
        // where one side's probes miss the other), updating the pairs after each round; they must equal the
        // pairs found by probing every leaf again.
        let scene = radlab_scene::builtin("furnace-cube?tessellation=2").expect("scene");
        let mut mesh = Mesh::new(&scene, 1.0, 0.25, 1e9).expect("mesh");
        let loc = ElementLocator::new(&scene, &mesh);
        let mut pairs = neighbour_pairs(&scene, &mesh, &loc);
        for round in 0..6u32 {
            let marked: Vec<u32> = mesh
                .leaves
                .iter()
                .copied()
                .filter(|&e| {
                    radlab_scene::sampling::mix64(u64::from(e) ^ u64::from(round)).is_multiple_of(3)
                })
                .collect();
            assert!(!marked.is_empty());
            let first_new = mesh.split_leaves(&marked);
            pairs = update_pairs(&scene, &mesh, &loc, &pairs, &marked, first_new as u32);
            let fresh = neighbour_pairs(&scene, &mesh, &loc);
            let differ: Vec<_> = fresh
                .iter()
                .filter(|p| pairs.binary_search(p).is_err())
                .collect();
            assert!(
                pairs == fresh,
                "round {round}: {} updated pairs, {} probed afresh; missing: {:?}",
                pairs.len(),
                fresh.len(),
                &differ[..differ.len().min(8)]
            );
            assert!(pairs.len() > 6 * 24);
        }
    }
}

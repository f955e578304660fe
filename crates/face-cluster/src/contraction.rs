//! Greedy dual-graph contraction (Garland, Willmott & Heckbert 2001, section 3): a region per face, a dual
//! edge per mesh edge shared by exactly two faces, and a priority queue that always contracts the cheapest
//! dual edge, merging its two regions into a new one, until no dual edge is left. Boundary and non-manifold
//! edges are not dual edges, so each dual-connected part of a mesh ends as its own root.
//!
//! Cost of merging R₁ and R₂ (sharing boundary length L) into R, each term dimensionless so the order is
//! the same at any scale (Garland et al. 2001, section 4, normalised):
//! - planarity E_fit = (λ_min(S) / c) / ā: mean squared distance of the region's face corners to their
//!   least-squares plane (section 4.1; moments in [`crate::moments`]) in units of ā, the mean face area of
//!   the region's dual-connected part. Garland's E_fit is a squared length; over ā it is scale-free and,
//!   like Garland's, grows with the region's size on a curved surface, which makes small merges come first.
//!   (Over the region's own area instead, E_fit falls with size on rough surfaces: measured on the 10⁵-face
//!   terrain, large regions then took in stranded faces one at a time, the tree was 2,346 deep and the
//!   queue saw 34 pushes per face; over ā, 103 deep and 7.5 pushes per face.)
//! - orientation E_dir = Σ A_f (1 − n̄·n_f)² / A = 1 − 2 n̄·N₁/A + n̄ᵀN₂n̄/A with N₁ = Σ A_f n_f,
//!   N₂ = Σ A_f n_f n_fᵀ and n̄ = N₁/|N₁| (section 4.2); when N₁ vanishes (a closed region) n̄ minimises it:
//!   E_dir = 1 + λ_min(N₂)/A;
//! - shape E_shape = 1 − max(γ₁, γ₂)/γ with irregularity γ = P²/A and P = P₁ + P₂ − 2L (section 4.3);
//! - balance E_bal = |A₁ − A₂| / A, radlab's addition: with Garland's three terms alone a large round region
//!   can take in its neighbours one face at a time (E_shape < 0 rewards it), making the tree deep and
//!   re-queueing the region's many neighbours at every merge; E_bal makes equal-area merges cheapest, so
//!   regions grow in step (measured on the 10⁵-face bumpy sphere: 455 deep without it, 44 with it);
//! - stranded regions: the balance term has a cost of its own. A small region whose neighbours have all grown
//!   large has no balanced merge left, so it waited, and the last few regions of a terrain took in hundreds of
//!   such pairs and quads one at a time, a tree level each. A region becomes stranded when every neighbour has
//!   at least [`STRANDED`] times its area; its merge with the region that made it so is then queued again
//!   without the balance term (10⁵-face terrain 104 → 34 deep, bumpy sphere 44 → 30). On a gently rolling
//!   surface regions of tens to thousands of faces are still taken in one at a time near the top (the terrain
//!   at a tenth of its relief: 94 deep at 3.2·10⁴ faces, 22 at 10³; a known failure, kept as an ignored test).
//!
//! The queue orders (cost rounded to 2⁻³² absolute, smaller region id, larger region id), so ties and
//! rounding differences of a few ulps (a scaled copy of the scene) give the same order. Stale entries are
//! skipped when popped (lazy deletion): a region's statistics never change, a merge makes a new region id.
//! Each merge costs O(d log n) for a new region of d neighbours: O(k log k) on meshes of bounded valence.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use glam::DVec3;
use radlab_scene::{EdgeAdjacency, Scene};
use rayon::prelude::*;

use crate::FaceClusterParams;
use crate::moments::{Moments, SymMat3};

/// What a region carries through the contraction.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Region {
    pub moments: Moments,
    pub area: f64,
    /// Σ A_f n_f.
    pub n1: DVec3,
    /// Σ A_f n_f n_fᵀ.
    pub n2: SymMat3,
    pub perimeter: f64,
    /// ā: mean face area of the dual-connected part the region belongs to.
    pub unit_area: f64,
}

impl Region {
    pub fn of_face(scene: &Scene, f: usize, unit_area: f64) -> Self {
        let face = &scene.faces[f];
        let poly = scene.polygon(f);
        let v = poly.vertices();
        let perimeter = (0..v.len())
            .map(|i| (v[(i + 1) % v.len()] - v[i]).length())
            .sum();
        Self {
            moments: Moments::of_points(v),
            area: face.area,
            n1: face.normal * face.area,
            n2: SymMat3::outer(face.normal, face.area),
            perimeter,
            unit_area,
        }
    }

    fn combine(&self, o: &Self, shared: f64) -> Self {
        Self {
            moments: self.moments.combine(&o.moments),
            area: self.area + o.area,
            n1: self.n1 + o.n1,
            n2: self.n2 + o.n2,
            perimeter: (self.perimeter + o.perimeter - 2.0 * shared).max(0.0),
            unit_area: self.unit_area,
        }
    }
}

/// The three cost terms of one merge (see the module doc), before weighting.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MergeCost {
    /// E_fit: mean squared distance to the least-squares plane over area.
    pub planarity: f64,
    /// E_dir: area-weighted (1 − n̄·n_f)².
    pub orientation: f64,
    /// E_shape: 1 − max(γ₁, γ₂)/γ.
    pub shape: f64,
    /// E_bal: |A₁ − A₂| / (A₁ + A₂).
    pub balance: f64,
}

impl MergeCost {
    fn of(r1: &Region, r2: &Region, merged: &Region) -> Self {
        let a = merged.area;
        let planarity = merged.moments.plane_fit_error() / merged.unit_area;
        let len = merged.n1.length();
        let orientation = if len > 1e-9 * a {
            let nbar = merged.n1 / len;
            (1.0 - 2.0 * len / a + merged.n2.quadratic(nbar) / a).max(0.0)
        } else {
            1.0 + merged.n2.min_eigenvalue().max(0.0) / a
        };
        let gamma = |r: &Region| r.perimeter * r.perimeter / r.area;
        let shape = 1.0 - gamma(r1).max(gamma(r2)) / gamma(merged);
        let balance = (r1.area - r2.area).abs() / a;
        Self {
            planarity,
            orientation,
            shape,
            balance,
        }
    }

    fn total_without_balance(&self, p: &FaceClusterParams) -> f64 {
        p.planarity_weight * self.planarity
            + p.orientation_weight * self.orientation
            + p.shape_weight * self.shape
    }

    fn total(&self, p: &FaceClusterParams) -> f64 {
        p.planarity_weight * self.planarity
            + p.orientation_weight * self.orientation
            + p.shape_weight * self.shape
            + p.balance_weight * self.balance
    }
}

/// Area ratio at which a region is stranded: when every neighbour has at least this many times its area, none
/// of its merges is balanced, and waiting only lets the regions around it grow further. Left to the queue, the
/// terrain's stranded pairs and quads were taken in one at a time by the last few regions, one tree level
/// each (10⁵-face terrain 104 deep; a gentle terrain 285 deep at 3.2·10⁴ faces); merged without the balance
/// term as soon as they are stranded, 34 and 94 (factor 8: 33 and 96).
pub const STRANDED: f64 = 4.0;

/// The queue's key for a cost: rounded to 2⁻³², clamped to ±10⁹, NaN last.
fn key(cost: f64) -> i64 {
    if cost.is_nan() {
        return i64::MAX;
    }
    (cost.clamp(-1e9, 1e9) * 4_294_967_296.0).round() as i64
}

/// A queued merge: (key, smaller region, larger region, shared length's bits).
type Entry = Reverse<(i64, u32, u32, u64)>;

/// Counts from one contraction.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ContractionStats {
    /// Mesh edges shared by exactly two faces (the dual graph's edges).
    pub dual_edges: usize,
    /// Mesh edges of one face.
    pub boundary_edges: usize,
    /// Mesh edges of three or more faces.
    pub non_manifold_edges: usize,
    /// Merges done (= faces − roots).
    pub merges: usize,
    /// Entries pushed onto the queue.
    pub queue_pushes: usize,
    /// Merges queued again, without the balance term, for a stranded region ([`STRANDED`]).
    pub stranded: usize,
    /// Stale entries popped and skipped.
    pub stale_pops: usize,
}

/// The result: regions 0..k are the faces, region k + i is made by merge i of `merges[i]`.
pub(crate) struct Contraction {
    pub regions: Vec<Region>,
    pub merges: Vec<[u32; 2]>,
    pub stats: ContractionStats,
}

fn find(rep: &mut [u32], mut x: u32) -> u32 {
    let mut root = x;
    while rep[root as usize] != root {
        root = rep[root as usize];
    }
    while rep[x as usize] != root {
        let next = rep[x as usize];
        rep[x as usize] = root;
        x = next;
    }
    root
}

/// Sorts a neighbour list by id and adds the lengths of repeated ids.
fn combine_neighbours(list: &mut Vec<(u32, f64)>) {
    list.sort_by_key(|&(id, _)| id);
    let mut out = 0;
    for i in 0..list.len() {
        if out > 0 && list[out - 1].0 == list[i].0 {
            list[out - 1].1 += list[i].1;
        } else {
            list[out] = list[i];
            out += 1;
        }
    }
    list.truncate(out);
}

/// Contracts the scene's dual graph completely.
pub(crate) fn contract(scene: &Scene, params: &FaceClusterParams) -> Contraction {
    let k = scene.face_count();
    let adjacency = EdgeAdjacency::new(scene);
    // Dual-connected parts (union-find over the dual edges) and their mean face areas ā.
    let mut rep: Vec<u32> = (0..k as u32).collect();
    for (_, a, b) in adjacency.manifold_pairs() {
        let (ra, rb) = (find(&mut rep, a as u32), find(&mut rep, b as u32));
        if ra != rb {
            rep[ra.max(rb) as usize] = ra.min(rb);
        }
    }
    let mut part_area = vec![(0.0f64, 0usize); k];
    let part: Vec<u32> = (0..k as u32).map(|f| find(&mut rep, f)).collect();
    for (f, &p) in part.iter().enumerate() {
        part_area[p as usize].0 += scene.faces[f].area;
        part_area[p as usize].1 += 1;
    }
    let mut regions: Vec<Region> = (0..k)
        .into_par_iter()
        .map(|f| {
            let (area, count) = part_area[part[f] as usize];
            Region::of_face(scene, f, area / count as f64)
        })
        .collect();
    drop((part, part_area));
    let mut stats = ContractionStats {
        boundary_edges: adjacency.boundary_edge_count(),
        non_manifold_edges: adjacency.non_manifold_edge_count(),
        ..ContractionStats::default()
    };
    let mut adj: Vec<Vec<(u32, f64)>> = vec![Vec::new(); k];
    for (e, a, b) in adjacency.manifold_pairs() {
        stats.dual_edges += 1;
        let [p, q] = adjacency.edge(e).vertices;
        let len = (scene.vertices[p as usize] - scene.vertices[q as usize]).length();
        adj[a].push((b as u32, len));
        adj[b].push((a as u32, len));
    }
    drop(adjacency);
    adj.par_iter_mut().for_each(combine_neighbours);

    let cost = |r1: &Region, r2: &Region, shared: f64| {
        let merged = r1.combine(r2, shared);
        MergeCost::of(r1, r2, &merged).total(params)
    };
    let initial: Vec<Entry> = adj
        .par_iter()
        .enumerate()
        .flat_map_iter(|(a, list)| {
            let regions = &regions;
            list.iter()
                .filter(move |&&(b, _)| (b as usize) > a)
                .map(move |&(b, len)| {
                    let c = cost(&regions[a], &regions[b as usize], len);
                    Reverse((key(c), a as u32, b, len.to_bits()))
                })
        })
        .collect();
    stats.queue_pushes = initial.len();
    let mut heap: BinaryHeap<Entry> = BinaryHeap::from(initial);

    let mut rep: Vec<u32> = (0..k as u32).collect();
    let mut alive = vec![true; k];
    let mut merges: Vec<[u32; 2]> = Vec::with_capacity(k);
    regions.reserve(k);
    rep.reserve(k);
    alive.reserve(k);
    adj.reserve(k);
    while let Some(Reverse((_, a, b, len))) = heap.pop() {
        let (ua, ub) = (a as usize, b as usize);
        if !(alive[ua] && alive[ub]) {
            stats.stale_pops += 1;
            continue;
        }
        let w = regions.len() as u32;
        let merged = regions[ua].combine(&regions[ub], f64::from_bits(len));
        regions.push(merged);
        alive[ua] = false;
        alive[ub] = false;
        alive.push(true);
        rep[ua] = w;
        rep[ub] = w;
        rep.push(w);
        let mut list = std::mem::take(&mut adj[ua]);
        list.append(&mut std::mem::take(&mut adj[ub]));
        for item in list.iter_mut() {
            item.0 = find(&mut rep, item.0);
        }
        list.retain(|&(x, _)| x != w);
        combine_neighbours(&mut list);
        let rw = regions[w as usize];
        for &(x, shared) in &list {
            let c = cost(&regions[x as usize], &rw, shared);
            heap.push(Reverse((key(c), x, w, shared.to_bits())));
            stats.queue_pushes += 1;
        }
        // A neighbour every one of whose other neighbours is already STRANDED times its area, and w too, has no
        // balanced merge left: its merge with w is queued again without the balance term, so the regions
        // around it take it in now rather than at the top of the tree.
        for &(x, shared) in &list {
            let ax = regions[x as usize].area;
            if rw.area < STRANDED * ax {
                continue;
            }
            let mut stranded = true;
            for &(y, _) in &adj[x as usize] {
                let y = find(&mut rep, y);
                if y != w && regions[y as usize].area < STRANDED * ax {
                    stranded = false;
                    break;
                }
            }
            if stranded {
                let rx = &regions[x as usize];
                let c =
                    MergeCost::of(rx, &rw, &rx.combine(&rw, shared)).total_without_balance(params);
                heap.push(Reverse((key(c), x, w, shared.to_bits())));
                stats.queue_pushes += 1;
                stats.stranded += 1;
            }
        }
        adj.push(list);
        merges.push([a, b]);
    }
    stats.merges = merges.len();
    Contraction {
        regions,
        merges,
        stats,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_round_away_a_few_ulps_and_order_nan_last() {
        let c = 0.123_456_789_f64;
        assert_eq!(key(c), key(c * (1.0 + 4.0 * f64::EPSILON)));
        assert!(key(-0.5) < key(0.0) && key(0.0) < key(2.0));
        assert_eq!(key(f64::NAN), i64::MAX);
        assert!(key(f64::INFINITY) < i64::MAX);
    }
}

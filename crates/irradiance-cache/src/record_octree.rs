//! The record octree: irradiance records keyed by the radius of the sphere they are valid in, answering
//! "which records' spheres hold this point" (Ward, Rubinstein & Clear 1988, §3; Radiance's ambient octree).
//!
//! A record of validity radius ρ is stored in the deepest cell, among those on the path to its centre, whose
//! half-size is still at least ρ; the cell's *loose* bound (the cell grown by its half-size on every side)
//! then holds the record's whole sphere. A query at x visits the cells whose loose bounds (grown by the
//! query's own radius s, for sphere-overlap queries) contain x, and tests their records. Records never move;
//! their radii may only shrink (neighbour clamping), which keeps every sphere inside its cell's loose bound.

use glam::DVec3;

/// Depth cap: cells no smaller than 2⁻²⁴ of the root.
const MAX_DEPTH: u32 = 24;

#[derive(Clone, Debug, Default)]
struct Cell {
    children: [u32; 8],
    records: Vec<u32>,
}

/// An octree of record indices over a cube.
#[derive(Clone, Debug)]
pub struct RecordOctree {
    centre: DVec3,
    half: f64,
    cells: Vec<Cell>,
}

impl RecordOctree {
    /// An empty tree over the box [lo, hi] (records outside it are kept at the root).
    pub fn new(lo: DVec3, hi: DVec3) -> Self {
        let half = ((hi - lo).max_element() * 0.5).max(f64::MIN_POSITIVE) * (1.0 + 1e-9);
        Self {
            centre: (lo + hi) * 0.5,
            half,
            cells: vec![Cell::default()],
        }
    }

    /// Stores record `id` centred at `p` with validity radius `radius`.
    pub fn insert(&mut self, id: u32, p: DVec3, radius: f64) {
        let (mut cell, mut c, mut h) = (0usize, self.centre, self.half);
        let inside = (p - self.centre).abs().max_element() <= self.half;
        let mut depth = 0;
        while inside && depth < MAX_DEPTH && h * 0.5 >= radius {
            let oct = octant(p, c);
            h *= 0.5;
            c += offset(oct) * h;
            let child = self.cells[cell].children[oct];
            cell = if child == 0 {
                self.cells.push(Cell::default());
                let new = self.cells.len() - 1;
                self.cells[cell].children[oct] = new as u32;
                new
            } else {
                child as usize
            };
            depth += 1;
        }
        self.cells[cell].records.push(id);
    }

    /// Calls `visit(id)` for every record stored in a cell whose loose bound, grown by `grow`, holds `x`: a
    /// superset of the records whose sphere (grown by `grow`) holds x. Order: depth first, children by octant.
    pub fn for_each_candidate(&self, x: DVec3, grow: f64, visit: &mut impl FnMut(u32)) {
        self.visit(0, self.centre, self.half, x, grow, visit);
    }

    fn visit(&self, cell: usize, c: DVec3, h: f64, x: DVec3, grow: f64, f: &mut impl FnMut(u32)) {
        let node = &self.cells[cell];
        node.records.iter().for_each(|&id| f(id));
        let hc = h * 0.5;
        for (oct, &child) in node.children.iter().enumerate() {
            if child == 0 {
                continue;
            }
            let cc = c + offset(oct) * hc;
            // Loose bound of the child: its cell grown by its half-size, then by `grow`.
            if (x - cc).abs().max_element() <= 2.0 * hc + grow {
                self.visit(child as usize, cc, hc, x, grow, f);
            }
        }
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.cells.capacity() * size_of::<Cell>()
            + self
                .cells
                .iter()
                .map(|c| c.records.capacity() * size_of::<u32>())
                .sum::<usize>()
    }
}

fn octant(p: DVec3, c: DVec3) -> usize {
    (p.x >= c.x) as usize | ((p.y >= c.y) as usize) << 1 | ((p.z >= c.z) as usize) << 2
}

fn offset(oct: usize) -> DVec3 {
    let s = |b: usize| if oct & b != 0 { 1.0 } else { -1.0 };
    DVec3::new(s(1), s(2), s(4))
}

#[cfg(test)]
mod tests {
    use super::*;
    use radlab_scene::sampling;

    #[test]
    fn finds_every_record_whose_sphere_holds_the_point() {
        let mut r = sampling::rng(5, 0);
        let mut u = || sampling::uniform(&mut r);
        let recs: Vec<(DVec3, f64)> = (0..400)
            .map(|_| (DVec3::new(u(), u(), u()), 0.3 * u() * u() * u()))
            .collect();
        let mut tree = RecordOctree::new(DVec3::ZERO, DVec3::ONE);
        for (i, &(p, rad)) in recs.iter().enumerate() {
            tree.insert(i as u32, p, rad);
        }
        for _ in 0..300 {
            let x = DVec3::new(u(), u(), u()) * 1.2 - 0.1;
            let grow = 0.05 * u();
            let mut found = Vec::new();
            tree.for_each_candidate(x, grow, &mut |id| found.push(id));
            for (i, &(p, rad)) in recs.iter().enumerate() {
                if (x - p).length() <= rad + grow {
                    assert!(found.contains(&(i as u32)), "record {i} missed at {x}");
                }
            }
            // It prunes: far fewer candidates than records on average.
            assert!(found.len() < recs.len());
        }
    }
}

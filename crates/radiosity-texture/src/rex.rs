//! A "rex" (Heckbert 1990, "Adaptive radiosity textures for bidirectional ray tracing", §4): an adaptive
//! quadtree over one face's own parameter domain whose leaves are histogram bins of deposited particle power.
//! A leaf ℓ of area A_ℓ holding power Φ_ℓ after N_e particles were emitted estimates the mean irradiance
//! H_ℓ = Φ_ℓ / (N_e A_ℓ) over it, so B_ℓ = E + ρ H_ℓ (unbiased for the leaf's mean, as any histogram is).
//!
//! The domain is the face's parameterisation of [`radlab_scene::Polygon::param_coords`]: (s, t) ∈ [0, 1]²
//! bilinear over a quad, barycentric over a triangle. A cell splits into the four children of
//! [`radlab_scene::Polygon::split4`], the images of the parameter quadrants (a triangle's corner triangles
//! and its middle one), so every cell lies wholly inside its face and its area is exact: no clipping.
//!
//! Split rule (`split`): a leaf holding more than T particles splits while half its longest edge is at least
//! `min_cell` (so no leaf is smaller); under `contrast` its four children's counts c_k must also differ from
//! counts proportional to their areas e_k = n A_k/A, Pearson's χ² = Σ (c_k − e_k)²/e_k > 16.27 (3 degrees of
//! freedom, p = 0.001). The hit points are kept (their parameters and power), so a split divides the parent's
//! earlier deposits exactly among the children; the tree is a function of the set of hits alone (not of the
//! order they arrived in), and is rebuilt from them after each pass.

use glam::DVec2;
use radlab_scene::{Polygon, Rgb};

use crate::params::SplitRule;

/// Pearson's χ² with 3 degrees of freedom at p = 0.001: the `contrast` rule's threshold.
pub const CONTRAST_CHI2: f64 = 16.27;
/// Depth cap of a rex (far below what `min_cell` allows on any sane face; a guard only).
const MAX_DEPTH: u32 = 40;
/// Marks a leaf in [`Cell::children`].
const LEAF: u32 = u32::MAX;

/// A particle landing as a rex keeps it: its face parameters and its power (not yet divided by N_e).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// (s, t) in the face's parameterisation.
    pub st: DVec2,
    /// Power per channel.
    pub power: Rgb,
}

/// One cell of a rex.
#[derive(Clone, Copy, Debug)]
pub struct Cell {
    /// Its part of the face.
    pub polygon: Polygon,
    /// Area of `polygon`.
    pub area: f64,
    /// Index of the first of its four children (contiguous), or none for a leaf.
    children: u32,
    /// Particles deposited in it (its subtree).
    pub count: u32,
    /// Power deposited in it (its subtree), not yet divided by N_e.
    pub power: Rgb,
    /// Depth (the root is 0).
    pub depth: u32,
}

impl Cell {
    /// Whether it is a leaf.
    pub fn is_leaf(&self) -> bool {
        self.children == LEAF
    }
}

/// How a rex grows.
#[derive(Clone, Copy, Debug)]
pub struct SplitSettings {
    /// The rule.
    pub rule: SplitRule,
    /// More particles than this split a leaf.
    pub threshold: u32,
    /// Smallest leaf edge (scene units).
    pub min_cell: f64,
}

/// The adaptive quadtree of one face.
#[derive(Clone, Debug)]
pub struct Rex {
    cells: Vec<Cell>,
}

/// The child of a cell holding local parameters `st`, and `st` in that child's parameters.
fn child_of(triangle: bool, st: DVec2) -> (usize, DVec2) {
    let (s, t) = (st.x, st.y);
    if triangle {
        // split4's children: (a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca).
        if s >= 0.5 {
            (1, DVec2::new(2.0 * s - 1.0, 2.0 * t))
        } else if t >= 0.5 {
            (2, DVec2::new(2.0 * s, 2.0 * t - 1.0))
        } else if s + t < 0.5 {
            (0, DVec2::new(2.0 * s, 2.0 * t))
        } else {
            (3, DVec2::new(2.0 * (s + t) - 1.0, 1.0 - 2.0 * s))
        }
    } else {
        // split4's children are the quadrants (0,0), (1,0), (1,1), (0,1) of (s, t).
        let (i, j) = (s >= 0.5, t >= 0.5);
        let k = match (i, j) {
            (false, false) => 0,
            (true, false) => 1,
            (true, true) => 2,
            (false, true) => 3,
        };
        (
            k,
            DVec2::new(
                2.0 * s - f64::from(u8::from(i)),
                2.0 * t - f64::from(u8::from(j)),
            ),
        )
    }
}

impl Rex {
    /// The rex of `face` (its polygon) grown over `hits`.
    pub fn build(face: Polygon, hits: &[Hit], split: SplitSettings) -> Self {
        let mut rex = Self {
            cells: vec![Cell {
                area: face.area(),
                polygon: face,
                children: LEAF,
                count: 0,
                power: Rgb::ZERO,
                depth: 0,
            }],
        };
        rex.grow(0, hits.to_vec(), split);
        rex
    }

    /// Deposits `hits` (parameters local to cell `c`) in cell `c` and splits it as the rule says.
    fn grow(&mut self, c: usize, hits: Vec<Hit>, split: SplitSettings) {
        let mut stack = vec![(c, hits)];
        while let Some((c, hits)) = stack.pop() {
            let cell = &mut self.cells[c];
            cell.count = hits.len() as u32;
            cell.power = hits.iter().map(|h| h.power).sum();
            let polygon = cell.polygon;
            let depth = cell.depth;
            if hits.len() <= split.threshold as usize
                || depth >= MAX_DEPTH
                || !(0.5 * polygon.max_edge() >= split.min_cell)
            {
                continue;
            }
            let triangle = polygon.is_triangle();
            let mut parts: [Vec<Hit>; 4] = Default::default();
            for h in &hits {
                let (k, st) = child_of(triangle, h.st);
                parts[k].push(Hit { st, power: h.power });
            }
            let children = polygon.split4();
            if split.rule == SplitRule::Contrast {
                let n = hits.len() as f64;
                let total: f64 = children.iter().map(Polygon::area).sum();
                let chi2: f64 = children
                    .iter()
                    .zip(&parts)
                    .map(|(p, h)| {
                        let e = n * p.area() / total;
                        if e > 0.0 {
                            let d = h.len() as f64 - e;
                            d * d / e
                        } else {
                            0.0
                        }
                    })
                    .sum();
                if !(chi2 > CONTRAST_CHI2) {
                    continue;
                }
            }
            let first = self.cells.len();
            self.cells[c].children = first as u32;
            for p in children {
                self.cells.push(Cell {
                    area: p.area(),
                    polygon: p,
                    children: LEAF,
                    count: 0,
                    power: Rgb::ZERO,
                    depth: depth + 1,
                });
            }
            // Children pushed in reverse so they are grown in order 0..4 (the order only affects indices).
            for (k, part) in parts.into_iter().enumerate().rev() {
                stack.push((first + k, part));
            }
        }
    }

    /// The leaf holding face parameters `st` (outside [0, 1]², the nearest in the descent).
    pub fn leaf_at(&self, st: DVec2) -> usize {
        let mut c = 0;
        let mut st = st;
        while !self.cells[c].is_leaf() {
            let (k, local) = child_of(self.cells[c].polygon.is_triangle(), st);
            c = self.cells[c].children as usize + k;
            st = local;
        }
        c
    }

    /// The cells (index 0 is the root).
    pub fn cells(&self) -> &[Cell] {
        &self.cells
    }

    /// Indices of the leaves, in cell order.
    pub fn leaves(&self) -> impl Iterator<Item = usize> + '_ {
        self.cells
            .iter()
            .enumerate()
            .filter(|(_, c)| c.is_leaf())
            .map(|(i, _)| i)
    }

    /// The deepest leaf's depth.
    pub fn depth(&self) -> u32 {
        self.cells.iter().map(|c| c.depth).max().unwrap_or(0)
    }

    /// Approximate heap bytes.
    pub fn bytes(&self) -> usize {
        self.cells.capacity() * size_of::<Cell>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DVec3, dvec3};

    fn settle(poly: Polygon) {
        // Points at known parameters land in the child whose polygon contains them, at the right local
        // parameters, through two levels.
        for k in 0..200 {
            let (s, t) = (
                (k as f64 * 0.618_034).fract(),
                (k as f64 * 0.754_877).fract(),
            );
            let st = if poly.is_triangle() && s + t > 1.0 {
                DVec2::new(1.0 - s, 1.0 - t)
            } else {
                DVec2::new(s, t)
            };
            let p = poly.point_at_params(st);
            let (c, local) = child_of(poly.is_triangle(), st);
            let child = poly.split4()[c];
            assert!(child.contains(p, 1e-9), "{st} not in child {c}");
            let back = child.point_at_params(local);
            assert!(
                (back - p).length() < 1e-12,
                "{st}: child {c} maps back to {back}, not {p}"
            );
            let (c2, local2) = child_of(poly.is_triangle(), local);
            let grand = child.split4()[c2];
            assert!(grand.contains(p, 1e-9));
            assert!((grand.point_at_params(local2) - p).length() < 1e-12);
        }
    }

    trait AtParams {
        fn point_at_params(&self, st: DVec2) -> DVec3;
    }

    impl AtParams for Polygon {
        /// The point whose `param_coords` are `st`.
        fn point_at_params(&self, st: DVec2) -> DVec3 {
            let v = self.vertices();
            if self.is_triangle() {
                v[0] + st.x * (v[1] - v[0]) + st.y * (v[2] - v[0])
            } else {
                self.point_at(st.x, st.y)
            }
        }
    }

    #[test]
    fn child_parameters_follow_split4() {
        settle(Polygon::triangle(
            dvec3(0.0, 0.0, 0.0),
            dvec3(2.0, 0.1, 0.0),
            dvec3(0.3, 1.5, 0.0),
        ));
        settle(Polygon::quad(
            dvec3(0.0, 0.0, 0.0),
            dvec3(2.0, 0.0, 0.0),
            dvec3(1.7, 1.2, 0.0),
            dvec3(0.2, 1.0, 0.0),
        ));
    }

    #[test]
    fn a_split_divides_the_deposits_exactly() {
        let poly = Polygon::quad(
            dvec3(0.0, 0.0, 0.0),
            dvec3(1.0, 0.0, 0.0),
            dvec3(1.0, 1.0, 0.0),
            dvec3(0.0, 1.0, 0.0),
        );
        let hits: Vec<Hit> = (0..1000)
            .map(|k| Hit {
                st: DVec2::new(
                    (k as f64 * 0.618_034).fract(),
                    (k as f64 * 0.754_877).fract(),
                ),
                power: Rgb::splat(1.0 + (k % 3) as f64),
            })
            .collect();
        let split = SplitSettings {
            rule: SplitRule::Count,
            threshold: 10,
            min_cell: 1e-3,
        };
        let rex = Rex::build(poly, &hits, split);
        let leaves: Vec<usize> = rex.leaves().collect();
        let total: Rgb = leaves.iter().map(|&l| rex.cells()[l].power).sum();
        let all: Rgb = hits.iter().map(|h| h.power).sum();
        assert!((total - all).abs().max_element() < 1e-9 * all.x);
        assert_eq!(
            leaves.iter().map(|&l| rex.cells()[l].count).sum::<u32>(),
            1000
        );
        assert!(leaves.iter().all(|&l| rex.cells()[l].count <= 10));
        let area: f64 = leaves.iter().map(|&l| rex.cells()[l].area).sum();
        assert!((area - 1.0).abs() < 1e-12);
        // Every hit is found in the leaf that counted it: leaf_at agrees with the build.
        let mut counted = vec![0u32; rex.cells().len()];
        for h in &hits {
            counted[rex.leaf_at(h.st)] += 1;
        }
        for &l in &leaves {
            assert_eq!(counted[l], rex.cells()[l].count);
        }
    }
}

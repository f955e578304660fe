//! The per-leaf gather ([`crate::Gather::Leaf`]): a leaf's irradiance from every link (a ← s) on its path to
//! the root, with the kernel integrated over the leaf itself,
//!
//! H_leaf = Σ_{(a←s), a ∋ leaf} V_as F_{leaf→s} B_s,   F_{leaf→s} = Σ_k w_k F_{dA(x_k)→s} over the leaf's Gauss points,
//!
//! instead of the ancestor's mean F_{a→s} pushed down (HSA91). The sources on a leaf's path partition what its
//! face sees, so at every Gauss point the exact point-to-polygon factors sum to the point's full form factor
//! (one in a closed, unoccluded scene): the row sums are exact and the furnace B = E/(1 − ρ) holds at any ρ.
//! The links still decide at which level each source is taken and carry the visibility estimate.
//!
//! Rows are cached per leaf and rebuilt only for leaves below a node whose links changed.

use rayon::prelude::*;

use crate::hierarchy::Engine;
use crate::link::Kernel;
use crate::node::NodeKind;

impl<N: NodeKind, K: Kernel<N>> Engine<N, K> {
    /// Rebuilds the rows of leaves whose path has a changed node; clears the marks.
    pub(crate) fn rebuild_rows(&mut self) {
        let n = self.nodes.len();
        // A node is stale if it or an ancestor is dirty (parents precede children).
        let mut stale = self.dirty.clone();
        for i in 0..n {
            let p = self.parent[i];
            if p != crate::hierarchy::NONE && stale[p as usize] {
                stale[i] = true;
            }
        }
        let todo: Vec<u32> = (0..n as u32)
            .filter(|&i| stale[i as usize] && self.children[i as usize].1 == 0)
            .collect();
        let built: Vec<Vec<(u32, f64)>> = todo
            .par_iter()
            .map(|&leaf| {
                let node = &self.nodes[leaf as usize];
                let mut row = Vec::new();
                let mut a = leaf;
                loop {
                    for l in &self.links[a as usize] {
                        let c = if a == leaf {
                            l.coefficient
                        } else {
                            self.kernel
                                .leaf_coefficient(node, &self.nodes[l.source as usize], l)
                        };
                        if c > 0.0 {
                            row.push((l.source, c));
                        }
                    }
                    let p = self.parent[a as usize];
                    if p == crate::hierarchy::NONE {
                        break;
                    }
                    a = p;
                }
                row.shrink_to_fit();
                row
            })
            .collect();
        for (leaf, row) in todo.into_iter().zip(built) {
            self.rows[leaf as usize] = row;
        }
        self.dirty.iter_mut().for_each(|d| *d = false);
    }
}

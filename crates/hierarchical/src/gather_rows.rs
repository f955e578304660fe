//! Gather rows: for every gather target, the links evaluated there and their coefficients, cached between
//! passes. A link r ← s is evaluated where its transport says ([`GatherAt`]):
//!
//! - at r itself (HSA91's per-link gather; cluster links), its contribution pushed to r's children;
//! - at each input face below r (an oriented cluster receiver hands each face its own share, Smits, Arvo &
//!   Greenberg 1994), then pushed within the face;
//! - at each leaf below r, with the kernel integrated over the leaf itself:
//!   H_leaf = Σ_{(a←s), a ∋ leaf} V_as F_{leaf→s} B_s, F_{leaf→s} by the leaf's own Gauss points. The sources
//!   on a leaf's path partition what its face sees, so the exact point-to-polygon factors sum to the point's
//!   full form factor at every Gauss point (one in a closed, unoccluded scene): the row sums are exact and the
//!   furnace B = E/(1 − ρ) holds at any ρ.
//!
//! Every evaluation below the receiver is a kernel evaluation and is counted in the engine's form factors, so a
//! gather that re-evaluates links pays for it in the statistics. Rows are rebuilt only for targets below a
//! node whose links changed, and only the entries of the changed nodes' links are evaluated again.

use rayon::prelude::*;

use crate::hierarchy::{Engine, NONE, RowEntry};
use crate::node::NodeKind;
use crate::transport::{GatherAt, Transport};

impl<N: NodeKind, T: Transport<N>> Engine<N, T> {
    /// Whether node `t` is the input-face target of [`GatherAt::Faces`] links from above it.
    fn is_face_target(&self, t: u32) -> bool {
        let p = self.parent[t as usize];
        self.nodes[t as usize].face().is_some()
            && (p == NONE || self.nodes[p as usize].face().is_none())
    }

    /// The row of target `t`: its own links, and the links of its ancestors that distribute to it. Entries
    /// of ancestors whose links have not changed are kept from `old` (the row as last built, valid unless `t`
    /// itself changed); the rest are evaluated. Returns the row and the number of kernel evaluations it took.
    fn build_row(
        &self,
        t: u32,
        old: &[RowEntry<T::Coefficient>],
        distributes: &[bool],
    ) -> (Vec<RowEntry<T::Coefficient>>, u64) {
        let node = &self.nodes[t as usize];
        let leaf = self.children[t as usize].1 == 0;
        let within_face = node.face().is_some();
        let renew = self.dirty[t as usize];
        let mut row: Vec<RowEntry<T::Coefficient>> = if renew {
            Vec::new()
        } else {
            old.iter()
                .filter(|(r, _, _)| !self.dirty[*r as usize])
                .copied()
                .collect()
        };
        let mut evaluations = 0;
        if renew {
            for (k, l) in self.links[t as usize].iter().enumerate() {
                if l.overlap {
                    continue;
                }
                let src = &self.nodes[l.source as usize];
                let here = match self.kernel.gather_at(node, src) {
                    GatherAt::Receiver => true,
                    GatherAt::Faces => within_face,
                    GatherAt::Leaves => leaf,
                };
                if here {
                    row.push((t, k as u32, self.kernel.coefficient(node, src, l, true)));
                }
            }
        }
        let face_target = self.is_face_target(t);
        if leaf || face_target {
            let mut a = self.parent[t as usize];
            while a != NONE {
                if distributes[a as usize] && (renew || self.dirty[a as usize]) {
                    let recv = &self.nodes[a as usize];
                    for (k, l) in self.links[a as usize].iter().enumerate() {
                        if l.overlap {
                            continue;
                        }
                        let src = &self.nodes[l.source as usize];
                        let here = match self.kernel.gather_at(recv, src) {
                            GatherAt::Receiver => false,
                            GatherAt::Faces => face_target && recv.face().is_none(),
                            GatherAt::Leaves => leaf,
                        };
                        if here {
                            evaluations += 1;
                            row.push((a, k as u32, self.kernel.coefficient(node, src, l, false)));
                        }
                    }
                }
                a = self.parent[a as usize];
            }
        }
        // A fixed order whatever was kept: by receiver, then link.
        row.sort_unstable_by_key(|(r, k, _)| (*r, *k));
        row.shrink_to_fit();
        (row, evaluations)
    }

    /// Rebuilds the rows of targets whose path has a changed node; clears the marks.
    pub(crate) fn rebuild_rows(&mut self) {
        let n = self.nodes.len();
        // A node is stale if it or an ancestor is dirty (parents precede children).
        let mut stale = self.dirty.clone();
        for i in 0..n {
            let p = self.parent[i];
            if p != NONE && stale[p as usize] {
                stale[i] = true;
            }
        }
        // Nodes with links evaluated below them.
        let distributes: Vec<bool> = (0..n)
            .into_par_iter()
            .map(|a| {
                self.links[a].iter().any(|l| {
                    !l.overlap
                        && self
                            .kernel
                            .gather_at(&self.nodes[a], &self.nodes[l.source as usize])
                            != GatherAt::Receiver
                })
            })
            .collect();
        let todo: Vec<u32> = (0..n as u32).filter(|&i| stale[i as usize]).collect();
        let built: Vec<(Vec<RowEntry<T::Coefficient>>, u64)> = todo
            .par_iter()
            .map(|&t| self.build_row(t, &self.rows[t as usize], &distributes))
            .collect();
        for (t, (row, evaluations)) in todo.into_iter().zip(built) {
            self.rows[t as usize] = row;
            self.form_factors += evaluations;
        }
        self.dirty.iter_mut().for_each(|d| *d = false);
    }
}

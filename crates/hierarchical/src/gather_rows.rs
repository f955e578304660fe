//! Gather rows: for every gather target, the links evaluated there and their coefficients, cached between
//! passes. A link r ← s is evaluated where its transport says ([`GatherAt`]):
//!
//! - at r itself (HSA91's per-link gather; cluster links), its contribution pushed to r's children;
//! - at each input face below r (an oriented cluster receiver hands each face its own share, Smits, Arvo &
//!   Greenberg 1994), then pushed within the face;
//! - at the shallowest nodes below r that the transport resolves, or the input faces where none on the way
//!   does ([`GatherAt::Descend`]), then pushed below. These landings are found top down from r, once per
//!   rebuild of a changed r ([`Frontier`]), so a link costs its frontier (on a smooth surface about √m of a
//!   receiver's m faces), not a test at every node below r;
//! - at each leaf below r, with the kernel integrated over the leaf itself:
//!   H_leaf = Σ_{(a←s), a ∋ leaf} V_as F_{leaf→s} B_s, F_{leaf→s} by the leaf's own Gauss points. The sources
//!   on a leaf's path partition what its face sees, so the exact point-to-polygon factors sum to the point's
//!   full form factor at every Gauss point (one in a closed, unoccluded scene): the row sums are exact and the
//!   furnace B = E/(1 − ρ) holds at any ρ.
//!
//! The source side mirrors the leaf gather: a link r ← s whose source is an inner node (of patches, toward a
//! patch, and sending radiosity: [`Transport::weighs_source_leaves`]) sends Σ_y w_y B_y / Σ_y w_y over the
//! leaves y below s, w_y = A_y F_{y→r} by y's own Gauss points, so each source leaf's power is divided among
//! the receivers by how much of it each sees: Σ_t A_t F_{t→s} · A_y F_{y→r} / (A_s F_{s→r}) = A_y F_{y→r} up
//! to quadrature, since both sides integrate the same A_r F_rs = A_s F_sr. Rows and columns of the discrete
//! operator are then exact together, and energy is conserved whatever mix of levels the refinement chose.
//! (The area mean, HSA91's pull, gives every leaf of s the same share of a coarse link. When near receivers
//! see a face through its small elements and far ones through its whole area, a leaf in the face's corner,
//! whose view the adjacent faces fill, sends its own share to those and still the face's mean share to
//! everything farther: more than its whole hemisphere, while the face's centre sends less than its own. Dark
//! corners over-send, bright centres under-send, and energy is lost.)
//!
//! Every evaluation below the receiver or the source is a kernel evaluation and is counted in the engine's
//! form factors, so a gather that re-evaluates links pays for it in the statistics. Rows are rebuilt only for
//! targets below a node whose links changed, and only the entries of links made since the last build are
//! evaluated: a refinement keeps a node's other links unchanged (a link is a pure function of its two ends),
//! so their coefficients are found in the old row by source; a link's source weights are evaluated again
//! only when its receiver's links changed or a node below its source was split.

use rayon::prelude::*;

use crate::hierarchy::{Engine, NONE, RowEntry, SourceWeight};
use crate::node::NodeKind;
use crate::transport::{GatherAt, LinkPayload, Transport};

/// Where the descending links of changed receivers land this rebuild, found top down from each receiver
/// (through the clusters that pass them on, stopping at those that resolve them and at input faces), so a
/// link costs what its frontier holds, not what lies below its receiver.
pub(crate) struct Frontier {
    /// (target, receiver, link index), by target.
    landings: Vec<(u32, u32, u32)>,
    /// Receivers below which a node above the faces was split since the last rebuild: their descending
    /// links' landings were found again.
    regrown: Vec<bool>,
}

impl Frontier {
    /// The landings on target `t`.
    fn at(&self, t: u32) -> &[(u32, u32, u32)] {
        let lo = self.landings.partition_point(|e| e.0 < t);
        let hi = self.landings.partition_point(|e| e.0 <= t);
        &self.landings[lo..hi]
    }
}

impl<N: NodeKind, T: Transport<N>> Engine<N, T> {
    /// The nodes where receiver `a`'s descending link `l` (index `k`) is evaluated: the shallowest nodes
    /// strictly below `a` that the transport resolves it at, or the input faces where none on the way does.
    fn landings(&self, a: u32, k: u32, l: &T::Link, out: &mut Vec<(u32, u32, u32)>) {
        let src = &self.tree.nodes[l.source() as usize];
        let (first, count) = self.tree.children[a as usize];
        let mut stack: Vec<u32> = (first..first + count).rev().collect();
        while let Some(c) = stack.pop() {
            let node = &self.tree.nodes[c as usize];
            if self.is_face_target(c)
                || (node.face().is_none() && self.kernel.resolves(node, src, l))
            {
                out.push((c, a, k));
            } else if node.face().is_none() {
                let (first, count) = self.tree.children[c as usize];
                stack.extend((first..first + count).rev());
            }
        }
    }

    /// Whether node `t` is the input-face target of [`GatherAt::Faces`] links from above it.
    fn is_face_target(&self, t: u32) -> bool {
        let p = self.tree.parent[t as usize];
        self.tree.nodes[t as usize].face().is_some()
            && (p == NONE || self.tree.nodes[p as usize].face().is_none())
    }

    /// The row of target `t`: its own links, and the links of its ancestors that distribute to it. Entries
    /// of ancestors whose links have not changed are kept from `old` (the row as last built, valid unless `t`
    /// itself changed; a descending link's entries are kept even then, unless a cluster below its receiver
    /// was split, since where it lands depends only on the clusters between); the rest are evaluated, the
    /// descending links' at the targets `descend` found for `t`. Returns the row and the number of kernel
    /// evaluations it took.
    fn build_row(
        &self,
        t: u32,
        old: &[RowEntry<T::Coefficient>],
        below: &[Option<Vec<GatherAt>>],
        descend: &Frontier,
        reuse: &[bool],
    ) -> (Vec<RowEntry<T::Coefficient>>, u64) {
        let node = &self.tree.nodes[t as usize];
        let leaf = self.tree.children[t as usize].1 == 0;
        let within_face = node.face().is_some();
        let renew = self.cache.dirty[t as usize];
        let descends = |r: u32, k: u32| {
            below[r as usize]
                .as_ref()
                .is_some_and(|m| m[k as usize] == GatherAt::Descend)
        };
        let mut row: Vec<RowEntry<T::Coefficient>> = old
            .iter()
            .filter(|&&(r, k, _)| {
                !self.cache.dirty[r as usize]
                    && if descends(r, k) {
                        !descend.regrown[r as usize]
                    } else {
                        !renew
                    }
            })
            .copied()
            .collect();
        // The old entries of changed nodes whose links can be told apart by source, by (node, source).
        let mut kept: Vec<(u32, u32, T::Coefficient)> = old
            .iter()
            .filter(|(r, _, _)| {
                (renew || self.cache.dirty[*r as usize] || descend.regrown[*r as usize])
                    && reuse[*r as usize]
            })
            .filter_map(|&(r, k, c)| {
                let s = *self.cache.row_sources.get(r as usize)?.get(k as usize)?;
                Some((r, s, c))
            })
            .collect();
        kept.sort_unstable_by_key(|(r, s, _)| (*r, *s));
        let find = |r: u32, s: u32| -> Option<T::Coefficient> {
            if !reuse[r as usize] {
                return None;
            }
            kept.binary_search_by_key(&(r, s), |(r, s, _)| (*r, *s))
                .ok()
                .map(|i| kept[i].2)
        };
        let mut evaluations = 0;
        let mut evaluate =
            |row: &mut Vec<RowEntry<T::Coefficient>>, a: u32, k: u32, l: &T::Link| {
                let c = find(a, l.source()).unwrap_or_else(|| {
                    evaluations += 1;
                    self.kernel
                        .coefficient(node, &self.tree.nodes[l.source() as usize], l, false)
                });
                row.push((a, k, c));
            };
        // Room for every entry the loops below may add, so that the row is not copied as it grows.
        let face_target = self.is_face_target(t);
        let mut room = descend.at(t).len();
        if renew {
            room += self.links.by_receiver[t as usize].len();
        }
        if leaf || face_target {
            let mut a = self.tree.parent[t as usize];
            while a != NONE {
                if below[a as usize].is_some() && (renew || self.cache.dirty[a as usize]) {
                    room += self.links.by_receiver[a as usize].len();
                }
                a = self.tree.parent[a as usize];
            }
        }
        row.reserve_exact(room);
        // Descending links of changed receivers above t that land on t.
        for &(_, a, k) in descend.at(t) {
            evaluate(
                &mut row,
                a,
                k,
                &self.links.by_receiver[a as usize][k as usize],
            );
        }
        if renew {
            for (k, l) in self.links.by_receiver[t as usize].iter().enumerate() {
                if l.overlap() {
                    continue;
                }
                let src = &self.tree.nodes[l.source() as usize];
                let here = match self.kernel.gather_at(node, src) {
                    GatherAt::Receiver => true,
                    GatherAt::Faces | GatherAt::Descend => within_face,
                    GatherAt::Leaves => leaf,
                };
                if here {
                    let c = find(t, l.source())
                        .unwrap_or_else(|| self.kernel.coefficient(node, src, l, true));
                    row.push((t, k as u32, c));
                }
            }
        }
        if leaf || face_target {
            let mut a = self.tree.parent[t as usize];
            while a != NONE {
                if let Some(modes) = &below[a as usize]
                    && (renew || self.cache.dirty[a as usize])
                {
                    let recv = &self.tree.nodes[a as usize];
                    for ((k, l), mode) in self.links.by_receiver[a as usize]
                        .iter()
                        .enumerate()
                        .zip(modes)
                    {
                        let here = !l.overlap()
                            && match mode {
                                GatherAt::Receiver | GatherAt::Descend => false,
                                GatherAt::Faces => face_target && recv.face().is_none(),
                                GatherAt::Leaves => leaf,
                            };
                        if here {
                            evaluate(&mut row, a, k as u32, l);
                        }
                    }
                }
                a = self.tree.parent[a as usize];
            }
        }
        // A fixed order whatever was kept: by receiver, then link.
        row.sort_unstable_by_key(|(r, k, _)| (*r, *k));
        row.shrink_to_fit();
        (row, evaluations)
    }

    /// The leaves below the source of `recv`'s link `l` with their normalised weights in what the link
    /// sends, w_y / Σ w (w_y the transport's [`Transport::source_leaf_weight`], for patches A_y F_{y→r}),
    /// and the number of kernel evaluations; empty when the source is a leaf, the link sends something
    /// else, a leaf cannot be weighed, or no leaf sees the receiver.
    fn source_row(&self, recv: u32, l: &T::Link) -> (Vec<SourceWeight>, u64) {
        if !self.may_need_source_row(recv, l) {
            return (Vec::new(), 0);
        }
        let r = &self.tree.nodes[recv as usize];
        let mut out = Vec::new();
        let mut stack = vec![l.source()];
        let (mut total, mut evaluations) = (0.0, 0);
        while let Some(j) = stack.pop() {
            let (first, count) = self.tree.children[j as usize];
            if count > 0 {
                stack.extend((first..first + count).rev());
                continue;
            }
            let Some(w) = self
                .kernel
                .source_leaf_weight(&self.tree.nodes[j as usize], r)
            else {
                return (Vec::new(), evaluations);
            };
            evaluations += 1;
            if w > 0.0 && w.is_finite() {
                total += w;
                out.push((j, w));
            }
        }
        if !(total > 0.0 && total.is_finite()) {
            return (Vec::new(), evaluations);
        }
        let row = out.into_iter().map(|(j, w)| (j, w / total)).collect();
        (row, evaluations)
    }

    /// Whether `recv`'s link `l` can have a source row: its source is an inner node and the transport
    /// weighs its leaves ([`Transport::weighs_source_leaves`]).
    fn may_need_source_row(&self, recv: u32, l: &T::Link) -> bool {
        !l.overlap()
            && self.tree.children[l.source() as usize].1 != 0
            && self
                .kernel
                .weighs_source_leaves(&self.tree.nodes[recv as usize], l)
    }

    /// Rebuilds the source rows of receivers whose links changed, and of links whose source's subtree
    /// (`grown`) was split since the last build. A receiver none of whose links can have one keeps no row
    /// at all rather than an empty one per link (readers take a missing row as an empty one): a cluster
    /// receiver's links never have one, and the empty rows alone were 24 bytes a link, about 1 GiB at 1e5
    /// faces under volume clusters. Such a receiver's rows are built afresh once one of its links can have
    /// one, which needs a changed link or a split source, both of which rebuild the row anyway.
    fn rebuild_source_rows(&mut self, grown: &[bool]) {
        let n = self.tree.nodes.len();
        let todo: Vec<u32> = (0..n as u32)
            .filter(|&r| {
                self.cache.dirty[r as usize]
                    || self.links.by_receiver[r as usize]
                        .iter()
                        .any(|l| grown[l.source() as usize])
            })
            .collect();
        let built: Vec<(Vec<Vec<SourceWeight>>, u64)> = todo
            .par_iter()
            .map(|&r| {
                if !self.links.by_receiver[r as usize]
                    .iter()
                    .any(|l| self.may_need_source_row(r, l))
                {
                    return (Vec::new(), 0);
                }
                let old = &self.cache.source_rows[r as usize];
                let renew = self.cache.dirty[r as usize]
                    || old.len() != self.links.by_receiver[r as usize].len();
                let mut evaluations = 0;
                let rows = self.links.by_receiver[r as usize]
                    .iter()
                    .enumerate()
                    .map(|(k, l)| {
                        if !renew && !grown[l.source() as usize] {
                            return old[k].clone();
                        }
                        let (w, e) = self.source_row(r, l);
                        evaluations += e;
                        w
                    })
                    .collect();
                (rows, evaluations)
            })
            .collect();
        for (r, (rows, evaluations)) in todo.into_iter().zip(built) {
            self.cache.source_rows[r as usize] = rows;
            self.form_factors += evaluations;
        }
    }

    /// Rebuilds the rows of targets whose path has a changed node; clears the marks.
    pub(crate) fn rebuild_rows(&mut self) {
        let n = self.tree.nodes.len();
        // Nodes below which a node was split since the last build, and (`regrown`) a node above the faces
        // (which may move where descending links from above it land).
        let mut grown = std::mem::take(&mut self.cache.split_since);
        let mut regrown: Vec<bool> = (0..n)
            .map(|i| grown[i] && self.tree.nodes[i].face().is_none())
            .collect();
        for i in (0..n).rev() {
            let p = self.tree.parent[i];
            if p != NONE {
                grown[p as usize] |= grown[i];
                regrown[p as usize] |= regrown[i];
            }
        }
        self.rebuild_source_rows(&grown);
        grown.iter_mut().for_each(|g| *g = false);
        self.cache.split_since = grown;
        // Where each link is evaluated, for the nodes with links evaluated below them (asked once per
        // rebuild, not at every target below).
        let below: Vec<Option<Vec<GatherAt>>> = (0..n)
            .into_par_iter()
            .map(|a| {
                let modes: Vec<GatherAt> = self.links.by_receiver[a]
                    .iter()
                    .map(|l| {
                        self.kernel
                            .gather_at(&self.tree.nodes[a], &self.tree.nodes[l.source() as usize])
                    })
                    .collect();
                let distributes = self.links.by_receiver[a]
                    .iter()
                    .zip(&modes)
                    .any(|(l, m)| !l.overlap() && *m != GatherAt::Receiver);
                distributes.then_some(modes)
            })
            .collect();
        // Only the descending links of a regrown node need their landings found again.
        for (a, r) in regrown.iter_mut().enumerate() {
            *r = *r
                && below[a].as_ref().is_some_and(|modes| {
                    self.links.by_receiver[a]
                        .iter()
                        .zip(modes)
                        .any(|(l, m)| !l.overlap() && *m == GatherAt::Descend)
                })
        }
        // A node is stale if it or an ancestor is dirty or regrown (parents precede children).
        let mut stale: Vec<bool> = (0..n).map(|i| self.cache.dirty[i] || regrown[i]).collect();
        for i in 0..n {
            let p = self.tree.parent[i];
            if p != NONE && stale[p as usize] {
                stale[i] = true;
            }
        }
        // Changed nodes whose old and new links can be told apart by source (a node's links have distinct
        // sources unless a transport links a pair twice; then its entries are evaluated again).
        let distinct = |s: &mut Vec<u32>| {
            s.sort_unstable();
            s.windows(2).all(|w| w[0] != w[1])
        };
        let reuse: Vec<bool> = (0..n)
            .into_par_iter()
            .map(|a| {
                let Some(prev) = self.cache.row_sources.get(a) else {
                    return false;
                };
                let mut now: Vec<u32> = self.links.by_receiver[a]
                    .iter()
                    .map(|l| l.source())
                    .collect();
                !self.cache.dirty[a] || (distinct(&mut prev.clone()) && distinct(&mut now))
            })
            .collect();
        // Where the descending links of changed receivers land.
        let mut landings: Vec<(u32, u32, u32)> = (0..n as u32)
            .into_par_iter()
            .filter(|&a| {
                (self.cache.dirty[a as usize] || regrown[a as usize])
                    && self.tree.nodes[a as usize].face().is_none()
            })
            .flat_map_iter(|a| {
                let mut out = Vec::new();
                if let Some(modes) = &below[a as usize] {
                    for ((k, l), mode) in self.links.by_receiver[a as usize]
                        .iter()
                        .enumerate()
                        .zip(modes)
                    {
                        if !l.overlap() && *mode == GatherAt::Descend {
                            self.landings(a, k as u32, l, &mut out);
                        }
                    }
                }
                out
            })
            .collect();
        landings.par_sort_unstable();
        let descend = Frontier { landings, regrown };
        let todo: Vec<u32> = (0..n as u32).filter(|&i| stale[i as usize]).collect();
        let built: Vec<(Vec<RowEntry<T::Coefficient>>, u64)> = todo
            .par_iter()
            .map(|&t| self.build_row(t, &self.cache.rows[t as usize], &below, &descend, &reuse))
            .collect();
        for (t, (row, evaluations)) in todo.into_iter().zip(built) {
            self.cache.rows[t as usize] = row;
            self.form_factors += evaluations;
        }
        self.cache.row_sources.resize(n, Vec::new());
        for a in 0..n {
            if self.cache.dirty[a] {
                self.cache.row_sources[a] = self.links.by_receiver[a]
                    .iter()
                    .map(|l| l.source())
                    .collect();
            }
        }
        self.cache.dirty.iter_mut().for_each(|d| *d = false);
    }
}

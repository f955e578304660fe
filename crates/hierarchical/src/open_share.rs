//! Open shares: leaves that straddle a contact (part of a floor element under a covering a millimetre above
//! it, part of a ceiling element behind a lamp mounted under it) receive and send light only on their open
//! part. Held as area means and sent from their whole area, they send into the covering's back, which absorbs
//! it, light that their open part should have sent: the light and shadow leaks of Baum, Mann, Smith & Winget
//! 1991 (who split surfaces along contacts instead). Here each leaf t has an open share o_t ∈ [0, 1]
//! ([`Transport::open_share`]: radlab-kernels' probe-ray estimate, 0 where no probe point sees anything but
//! the back of a face), and every leaf's radiosity and irradiance are those of its open part.
//!
//! A link l = r ← s has a visibility V sampled between the whole of r and the whole of s, so it carries both
//! ends' open shares. On the source side, s sends its leaves' open radiosity weighted by the open power each
//! sends toward r,
//!
//!   J_l = Σ_y o_y w_y B_y / Σ_y o_y w_y,   w_y = A_y F_{y→r}   (a leaf source y: J = B_y, or 0 if o_y = 0),
//!
//! and on the receiver side what the link delivers, A_r V F_rs J_l = Σ_t A_t c_{t,l} J_l (c_{t,l} = V F_{t→s}
//! its coefficient at leaf t), lands on the receiver's open part only: at leaf t the open-part irradiance
//! gains c_{t,l} J_l / ō_l, with
//!
//!   ō_l = Σ_t o_t A_t c_{t,l} / Σ_t A_t c_{t,l}
//!
//! the open share of r as the link's own coefficients weight it (for a link gathered at its receiver, the
//! receiver's share). The power delivered, Σ_t o_t A_t c_{t,l} J_l / ō_l, is unchanged; only sealed leaves no
//! longer take part of it. A leaf's radiosity is then B_t = E_t + ρ_t H'_t with H'_t = Σ_l c_{t,l} J_l / ō_l,
//! and it sends o_t A_t B_t. For a link between two leaves this is B = E + ρ H / o with H the area-mean
//! irradiance, the effective-area system o A B = o A E + ρ Σ A F B that matrix and progressive radiosity
//! solve; for a coarse link it does not divide one leaf's share of a smeared visibility by that leaf's own o
//! (a wholly sealed leaf under a coarse link receives V F J from it, which only the link's receiver as a
//! whole can be credited with).
//!
//! A coefficient that measured its target's own visibility of the source (rays that start on the target: a
//! leaf below a partly visible link's receiver with [`crate::LeafVisibility`] rays,
//! [`Transport::own_visibility`]) already leaves out the target's sealed part, c_{t,l} ≈ o_t v_t F_{t→s} with
//! v_t the visibility of its open part. Its open part's irradiance is then c_{t,l} J_l / o_t, the target's own
//! gain, and such entries take no part in ō_l. With the link's gain instead, the light the leaves' rays had
//! kept off a receiver's sealed parts was moved onto its open leaves a second time, their rows rose above one,
//! and a closed Cornell box at ρ = 0.5 gained 0.64% of its light under face clusters' coarse links (their
//! test `an_occluded_furnace_keeps_its_light`; volume clusters' +0.54%).
//!
//! The gains 1/ō can raise the row sum R'_t = Σ_l c_{t,l} / ō_l of a leaf that is itself partly sealed
//! (o_t < 1) above one where the probe estimate o and the visibility rays disagree (a leaf-to-leaf link whose
//! 16 rays see more than 16 probe points did); such a leaf's gathered irradiance is multiplied by 1/R'_t, so
//! that ρ R' ≤ ρ there (matrix radiosity's A max(o, r) is the same bound). A wholly open leaf's row is left as
//! it is, above one or not: a coarse link has one visibility for its whole receiver, so the leaves that see
//! its source better than the receiver as a whole get rows above one and the others rows below, by a few per
//! cent, the power the link delivers unchanged. Capping those rows too kept the deficits and dropped the
//! excesses: 1% of the light was lost in a closed Cornell box at ρ = 0.5 (the crate's test
//! `an_occluded_furnace_keeps_its_light`), and the hierarchical methods' answers on the Cornell box were biased
//! low by as much. Where every estimate is 1 nothing here is computed, and the solution is the plain one bit
//! for bit.

use radlab_scene::Rgb;
use rayon::prelude::*;

use crate::hierarchy::Engine;
use crate::node::NodeKind;
use crate::transport::{LinearState, LinkPayload, NodeView, SourceFlux, Transport};

impl<N: NodeKind, T: Transport<N>> Engine<N, T> {
    /// Estimates the open shares of leaves that have none yet (in parallel, each from its own random
    /// stream), pulls them up as area means, and sets each link's receiver gain 1/ō_l and each leaf's cap.
    /// The rows must be current.
    pub(crate) fn update_open_shares(&mut self) {
        let n = self.tree.nodes.len();
        let todo: Vec<u32> = (0..n as u32)
            .filter(|&i| {
                self.tree.children[i as usize].1 == 0 && self.solve.open_raw[i as usize].is_nan()
            })
            .collect();
        let found: Vec<f64> = todo
            .par_iter()
            .map(|&i| {
                let o = self
                    .kernel
                    .open_share(&self.tree.nodes[i as usize])
                    .unwrap_or(1.0);
                if (0.0..=1.0).contains(&o) { o } else { 1.0 }
            })
            .collect();
        for (i, o) in todo.into_iter().zip(found) {
            self.solve.open_raw[i as usize] = o;
        }
        self.solve.has_open =
            (0..n).any(|i| self.tree.children[i].1 == 0 && self.solve.open_raw[i] < 1.0);
        self.solve.link_gain.clear();
        self.solve.row_cap.clear();
        if !self.solve.has_open {
            self.solve.open.iter_mut().for_each(|o| *o = 1.0);
            return;
        }
        for i in (0..n).rev() {
            let (first, count) = self.tree.children[i];
            if count == 0 {
                self.solve.open[i] = self.solve.open_raw[i];
                continue;
            }
            let (mut sum, mut area) = (0.0, 0.0);
            for c in first..first + count {
                let a = self.tree.nodes[c as usize].area();
                sum += a * self.solve.open[c as usize];
                area += a;
            }
            self.solve.open[i] = if area > 0.0 { sum / area } else { 1.0 };
        }
        // ō_l from every row entry, in target order (sequential: the same sums on any thread count).
        let mut sums: Vec<Vec<(f64, f64)>> = self
            .links
            .by_receiver
            .iter()
            .map(|ls| vec![(0.0, 0.0); ls.len()])
            .collect();
        for (t, row) in self.cache.rows.iter().enumerate() {
            let a = self.tree.nodes[t].area();
            for (r, k, c) in row {
                if self.own_visibility(t, *r, *k) {
                    // Gained per target, by its own 1/o_t, in the gather.
                    continue;
                }
                let w = a * self.kernel.coefficient_weight(c);
                let s = &mut sums[*r as usize][*k as usize];
                s.0 += w * self.solve.open[t];
                s.1 += w;
            }
        }
        self.solve.link_gain = sums
            .into_iter()
            .map(|ls| {
                ls.into_iter()
                    .map(|(num, den)| {
                        if !(den > 0.0) {
                            1.0
                        } else if num > 0.0 {
                            den / num
                        } else {
                            0.0
                        }
                    })
                    .collect()
            })
            .collect();
        let rows = self.unit_gather(true);
        self.solve.row_cap = (0..n)
            .map(|i| {
                let m = rows[i].max_element();
                if self.tree.children[i].1 == 0 && m > 1.0 && self.solve.open[i] < 1.0 {
                    1.0 / m
                } else {
                    1.0
                }
            })
            .collect();
    }

    /// Whether row entry (receiver `r`, link `k`) of target `t` measured the target's own visibility
    /// ([`Transport::own_visibility`]).
    pub(crate) fn own_visibility(&self, t: usize, r: u32, k: u32) -> bool {
        let l = &self.links.by_receiver[r as usize][k as usize];
        self.kernel.own_visibility(
            &self.tree.nodes[t],
            &self.tree.nodes[l.source() as usize],
            l,
        )
    }

    /// What link `k` of receiver `r` delivers per unit coefficient with open shares: the source's open
    /// radiosity (weights o_y A_y F_{y→r} below an inner source), times the link's receiver gain 1/ō_l.
    pub(crate) fn open_flux(
        &self,
        view: &NodeView<'_, N>,
        b: &[Rgb],
        x: &[T::Exitance],
        r: usize,
        k: usize,
        l: &T::Link,
    ) -> T::Flux {
        let s = l.source() as usize;
        let j = match self.cache.source_rows[r].get(k) {
            Some(ws) if !ws.is_empty() => {
                let (sum, weight) = ws.iter().fold((Rgb::ZERO, 0.0), |(sum, d), (y, w)| {
                    let wo = *w * self.solve.open[*y as usize];
                    (sum + wo * b[*y as usize], d + wo)
                });
                T::Flux::from(if weight > 0.0 {
                    sum / weight
                } else {
                    Rgb::ZERO
                })
            }
            _ if self.solve.open[s] == 0.0 => T::Flux::default(),
            _ => self.kernel.emit(view, b, x, r as u32, l),
        };
        let gain = self
            .solve
            .link_gain
            .get(r)
            .and_then(|g| g.get(k))
            .copied()
            .unwrap_or(1.0);
        j.scaled(gain)
    }

    /// A leaf's radiosity and exitance from its gathered irradiance `h`, capped where it is partly sealed and
    /// its row sum with the gains exceeds one; a sealed leaf (o = 0) receives nothing and holds its emission only.
    pub(crate) fn reflect_leaf(
        &self,
        i: usize,
        node: &N,
        h: &T::Irradiance,
        with_emission: bool,
    ) -> (Rgb, T::Exitance) {
        if self.solve.has_open && self.solve.open[i] == 0.0 {
            return self
                .kernel
                .reflect(node, &T::Irradiance::default(), with_emission);
        }
        match self.solve.row_cap.get(i) {
            Some(&cap) if cap != 1.0 => {
                let mut scaled = T::Irradiance::default();
                scaled.add_scaled(Rgb::splat(cap), h);
                self.kernel.reflect(node, &scaled, with_emission)
            }
            _ => self.kernel.reflect(node, h, with_emission),
        }
    }

    /// [`Engine::pull`] with open shares: an inner node's radiosity is the mean of its children's over
    /// their open areas, Σ o_c A_c B_c / Σ o_c A_c (what it sends from its open part; the area mean where
    /// every child is sealed), its exitance by the transport's [`Transport::pull`].
    pub(crate) fn pull_open(&self, b: &mut [Rgb], x: &mut [T::Exitance]) {
        for i in (0..self.tree.nodes.len()).rev() {
            let (first, count) = self.tree.children[i];
            if count == 0 {
                continue;
            }
            let (mut open_sum, mut open_area) = (Rgb::ZERO, 0.0);
            let (mut sum, mut area) = (Rgb::ZERO, 0.0);
            for c in first..first + count {
                let c = c as usize;
                let a = self.tree.nodes[c].area();
                open_sum += a * self.solve.open[c] * b[c];
                open_area += a * self.solve.open[c];
                sum += a * b[c];
                area += a;
            }
            // The exitance (what a basis keeps beyond the mean) is pulled by the transport's own relation.
            let kids = first as usize..(first + count) as usize;
            let (_, xs) = self.kernel.pull(
                &self.tree.nodes[i],
                &self.tree.nodes[kids.clone()],
                &b[kids.clone()],
                &x[kids],
            );
            b[i] = if open_area > 0.0 {
                open_sum / open_area
            } else if area > 0.0 {
                sum / area
            } else {
                Rgb::ZERO
            };
            x[i] = xs;
        }
    }
}

//! One solution pass over the hierarchy: gather, push, pull (Hanrahan, Salzman & Aupperle 1991), each step
//! as the node kind's [`Transport`] defines it:
//!
//! - gather: every link's flux J_l = emit(l) (for a link r ← s from an inner node of patches that sends
//!   radiosity, J_l = Σ_y w_y B_y / Σ_y w_y over the leaves y below s, w_y = A_y F_{y→r}) is delivered at its
//!   gather targets' rows, h_t = Σ c_{t,l} ⊗ J_l (for patches H_r = Σ_{links r←s} V F_rs B_s), in parallel
//!   over targets;
//! - push: each node adds what its parent passes down (patches: the parent's irradiance), and a leaf's
//!   radiosity is B = E + ρ ⊙ H (the transport's reflect);
//! - pull: the transport's [`Transport::pull`]; by default an inner node's radiosity is the area mean of its
//!   children's, B_p = Σ_c A_c B_c / A_p, so the power a node sends is exactly the power of its leaves, and
//!   the transport's exitance state adds up (a higher-order basis pulls by its two-scale relation).
//!
//! Where some leaf is partly sealed (a transport's open shares, [`crate::open_share`]), radiosity and
//! irradiance are held over open parts: sources weight their leaves by o_y A_y F_{y→r}, a link's delivery is
//! divided by its receiver's open share, pull is the mean over open areas Σ o_c A_c B_c / Σ o_c A_c, and the
//! sums below weight a leaf by o A.
//!
//! This is one Jacobi sweep B ← E + M B of the hierarchical operator M = ρ ⊙ push ∘ gather ∘ pull. Close to
//! ρ = 1 a sweep shrinks the error's slowest mode (nearly uniform over the scene) only by about ρ, so each pass
//! adds a one-dimensional coarse correction along u = ρ (per channel, on the leaves light has reached, so a
//! closed unlit interior stays exactly dark), chosen so the area-weighted residual
//! vanishes: c = Σ A r / Σ A (u − M u), B ← E + M (B + c u) — the error of the furnace's dominant mode is removed
//! in one pass (a Petrov–Galerkin two-level step; it plays the role of Cohen et al.'s 1988 ambient term, but
//! inside the iteration). The pass's size, ‖ΔB‖/‖B‖ (area-weighted L1 over leaves), and the observed
//! contraction q between passes give the estimated remaining error ‖ΔB‖ q/(1 − q).
//!
//! Reductions are sequential in node order, so results are bit-identical for any thread count.

use radlab_method::SolveError;
use radlab_scene::Rgb;
use rayon::prelude::*;

use crate::hierarchy::{Engine, NONE};
use crate::node::NodeKind;
use crate::transport::{LinearState, LinkPayload, SourceFlux, Transport};

/// A per-node state of the solution: radiosity (area mean) and the transport's exitance.
pub(crate) type Field<X> = (Vec<Rgb>, Vec<X>);

/// Which links a partial gather goes through, given (receiver, source, link).
pub type LinkFilter<'f, N, L> = dyn Fn(&N, &N, &L) -> bool + Sync + 'f;

impl<N: NodeKind, T: Transport<N>> Engine<N, T> {
    /// Applies M (and adds E when `with_emission`) to a per-node radiosity `b` and exitance `x` whose inner
    /// nodes hold the pulled values of their children. Returns the new radiosity and exitance, inner nodes
    /// pulled, and every node's total irradiance after push.
    pub(crate) fn apply(
        &self,
        b: &[Rgb],
        x: &[T::Exitance],
        with_emission: bool,
    ) -> (Field<T::Exitance>, Vec<T::Irradiance>) {
        let h = self.gather_push(b, x, true);
        // Reflect at leaves.
        let (mut out_b, mut out_x): (Vec<Rgb>, Vec<T::Exitance>) = self
            .tree
            .nodes
            .par_iter()
            .zip(&self.tree.children)
            .zip(&h)
            .enumerate()
            .map(|(i, ((node, c), h))| {
                if c.1 == 0 {
                    self.reflect_leaf(i, node, h, with_emission)
                } else {
                    (Rgb::ZERO, T::Exitance::default())
                }
            })
            .unzip();
        self.pull(&mut out_b, &mut out_x);
        ((out_b, out_x), h)
    }

    /// Gather and push: every node's total irradiance when the nodes send `b` and `x`; leaves' irradiance
    /// multiplied by the row normalisation when `scaled` and it is on.
    fn gather_push(&self, b: &[Rgb], x: &[T::Exitance], scaled: bool) -> Vec<T::Irradiance> {
        self.gather_push_through(b, x, scaled, None)
    }

    /// Gather and push: every node's total irradiance when the nodes send `b` and `x`, through the links
    /// `keep` accepts (all of them when `None`); leaves' irradiance multiplied by the row normalisation when
    /// `scaled` and it is on.
    fn gather_push_through(
        &self,
        b: &[Rgb],
        x: &[T::Exitance],
        scaled: bool,
        keep: Option<&LinkFilter<'_, N, T::Link>>,
    ) -> Vec<T::Irradiance> {
        let view = self.view();
        // What each link sends.
        let flux: Vec<Vec<T::Flux>> = self
            .links
            .by_receiver
            .par_iter()
            .enumerate()
            .map(|(r, ls)| {
                ls.iter()
                    .enumerate()
                    .map(|(k, l)| {
                        if l.overlap() {
                            return T::Flux::default();
                        }
                        if keep.is_some_and(|f| {
                            !f(
                                &self.tree.nodes[r],
                                &self.tree.nodes[l.source() as usize],
                                l,
                            )
                        }) {
                            return T::Flux::default();
                        }
                        if self.solve.has_open {
                            return self.open_flux(&view, b, x, r, k, l);
                        }
                        match self.cache.source_rows[r].get(k) {
                            Some(ws) if !ws.is_empty() => T::Flux::from(
                                ws.iter()
                                    .fold(Rgb::ZERO, |s, (y, w)| s + *w * b[*y as usize]),
                            ),
                            _ => self.kernel.emit(&view, b, x, r as u32, l),
                        }
                    })
                    .collect()
            })
            .collect();
        // Gather at every target.
        let mut h: Vec<T::Irradiance> = self
            .cache
            .rows
            .par_iter()
            .enumerate()
            .map(|(t, row)| {
                let mut h = T::Irradiance::default();
                for (r, k, c) in row {
                    let mut f = flux[*r as usize][*k as usize];
                    if self.solve.has_open && self.own_visibility(t, *r, *k) {
                        // The coefficient already leaves out the target's sealed part: its open part's
                        // irradiance is the coefficient over the target's own open share.
                        let o = self.solve.open[t];
                        f = f.scaled(if o > 0.0 { 1.0 / o } else { 0.0 });
                    }
                    self.kernel.deliver(&mut h, c, f);
                }
                h
            })
            .collect();
        // Push: parents precede children in id order.
        for i in 0..self.tree.nodes.len() {
            let p = self.tree.parent[i];
            if p != NONE {
                let down = self.kernel.push(
                    &self.tree.nodes[p as usize],
                    &self.tree.nodes[i],
                    &h[p as usize],
                );
                h[i].add_scaled(Rgb::ONE, &down);
            }
        }
        if scaled && self.solve.row_scale.len() == h.len() {
            for (i, hi) in h.iter_mut().enumerate() {
                if self.tree.children[i].1 == 0 {
                    let mut t = T::Irradiance::default();
                    t.add_scaled(self.solve.row_scale[i], hi);
                    *hi = t;
                }
            }
        }
        h
    }

    /// Row sums of the discrete operator in use, per node and channel: the irradiance every leaf gathers
    /// (after push, and after the row normalisation if it is on) when every leaf sends B = 1 (the transport's
    /// `unit_response`); zero at inner nodes, and everywhere if the transport has no unit response. One in a
    /// closed scene if the links' coefficients were exact; a defect δ becomes δρ/(1 − ρ) in the furnace
    /// B = E/(1 − ρ). The rows must be current (after a step).
    pub fn row_sums(&self) -> Vec<Rgb> {
        self.unit_gather(true)
    }

    /// The part of each leaf's row sum (as [`Engine::row_sums`], before the row normalisation) that comes
    /// through the links `keep` accepts, given (receiver, source, link): the operator's rows split by kind
    /// of link or by source, to compare with the form factors the scene's geometry gives.
    pub fn row_sums_through(&self, keep: &LinkFilter<'_, N, T::Link>) -> Vec<Rgb> {
        self.unit_gather_through(false, Some(keep))
    }

    /// The scalar irradiance of every leaf when every leaf sends B = 1 (`scaled`: with the row
    /// normalisation applied). A leaf's scalar irradiance is read through its reflection, H = B/ρ per channel
    /// (zero where ρ is zero: such a leaf reflects nothing, whatever it receives).
    pub(crate) fn unit_gather(&self, scaled: bool) -> Vec<Rgb> {
        self.unit_gather_through(scaled, None)
    }

    /// [`Engine::unit_gather`] through the links `keep` accepts.
    fn unit_gather_through(
        &self,
        scaled: bool,
        keep: Option<&LinkFilter<'_, N, T::Link>>,
    ) -> Vec<Rgb> {
        let n = self.tree.nodes.len();
        let mut u = vec![Rgb::ZERO; n];
        let mut ux = vec![T::Exitance::default(); n];
        for i in 0..n {
            if self.tree.children[i].1 == 0 {
                match self.kernel.unit_response(&self.tree.nodes[i]) {
                    Some((b, x)) => (u[i], ux[i]) = (b, x),
                    None => return vec![Rgb::ZERO; n],
                }
            }
        }
        self.pull(&mut u, &mut ux);
        let h = self.gather_push_through(&u, &ux, scaled, keep);
        (0..n)
            .map(|i| {
                if self.tree.children[i].1 != 0 {
                    return Rgb::ZERO;
                }
                let node = &self.tree.nodes[i];
                let (b, _) = self.kernel.reflect(node, &h[i], false);
                let rho = node.reflectance();
                Rgb::new(
                    per_unit(b.x, rho.x),
                    per_unit(b.y, rho.y),
                    per_unit(b.z, rho.z),
                )
            })
            .collect()
    }

    /// Turns the row normalisation on or off. On, after every change of the links each leaf's gathered
    /// irradiance is multiplied, per channel, by 1/R_l, R_l its row sum ([`Engine::row_sums`] before
    /// normalisation), so every row sums to exactly one. Correct only for a closed scene, where the exact
    /// form factors from any point sum to one (the summation relation of an enclosure, Goral, Torrance,
    /// Greenberg & Battaile 1984): the caller decides that the scene is closed. A leaf that gathers nothing
    /// (R = 0: sealed off, or ρ = 0) is left alone. Needs the transport's `unit_response`; without it this
    /// does nothing.
    pub fn normalise_closed_rows(&mut self, on: bool) {
        self.solve.normalise_rows = on;
        self.solve.row_scale.clear();
        self.operator_changed();
    }

    /// Recomputes the row normalisation for the current rows.
    fn update_row_scale(&mut self) {
        self.solve.row_scale.clear();
        if !self.solve.normalise_rows {
            return;
        }
        let r = self.unit_gather(false);
        self.solve.row_scale = r
            .iter()
            .map(|r| Rgb::new(inverse(r.x), inverse(r.y), inverse(r.z)))
            .collect();
    }

    /// Sets every inner node's radiosity and exitance from its children's by the transport's
    /// [`Transport::pull`] (by default the area mean and the sum; children follow parents in id order); with
    /// open shares, to the mean over their open areas ([`Engine::pull_open`]).
    pub(crate) fn pull(&self, b: &mut [Rgb], x: &mut [T::Exitance]) {
        if self.solve.has_open {
            return self.pull_open(b, x);
        }
        for i in (0..self.tree.nodes.len()).rev() {
            let (first, count) = self.tree.children[i];
            if count == 0 {
                continue;
            }
            let kids = first as usize..(first + count) as usize;
            (b[i], x[i]) = self.kernel.pull(
                &self.tree.nodes[i],
                &self.tree.nodes[kids.clone()],
                &b[kids.clone()],
                &x[kids],
            );
        }
    }

    /// The leaves' responses to a unit irradiance from all around (zero at leaves `keep` rejects), pulled.
    fn uniform_field(&self, keep: impl Fn(usize) -> bool) -> Field<T::Exitance> {
        let (mut u, mut ux): Field<T::Exitance> = (0..self.tree.nodes.len())
            .map(|i| {
                if self.tree.children[i].1 == 0 && keep(i) {
                    self.kernel.uniform_response(&self.tree.nodes[i])
                } else {
                    (Rgb::ZERO, T::Exitance::default())
                }
            })
            .unzip();
        self.pull(&mut u, &mut ux);
        (u, ux)
    }

    /// Sum over leaves of a per-node radiosity times the area it is held over, o A (o the open share, 1
    /// without open shares), per channel, in node order: the power it sends.
    fn leaf_sum(&self, v: &[Rgb]) -> Rgb {
        let mut s = Rgb::ZERO;
        for (((node, c), x), o) in self
            .tree
            .nodes
            .iter()
            .zip(&self.tree.children)
            .zip(v)
            .zip(&self.solve.open)
        {
            if c.1 == 0 {
                s += node.area() * *o * *x;
            }
        }
        s
    }

    /// One gather/push-pull pass with the coarse correction. Returns the estimated remaining relative error
    /// (infinite until two passes have run on the current links).
    pub(crate) fn solve_pass(&mut self) -> Result<f64, SolveError> {
        // The sources' radiosity changes: every link's light weight with it.
        self.links.settled_epsilon = None;
        if self.cache.dirty.iter().any(|&d| d) {
            self.rebuild_rows();
            self.update_row_scale();
            self.update_open_shares();
        } else if self.solve.normalise_rows && self.solve.row_scale.len() != self.tree.nodes.len() {
            self.update_row_scale();
        }
        // The coarse mode lives on the leaves light has reached: a closed interior that no light can enter
        // stays exactly dark (its leaves may still link to each other).
        let support = (0..self.tree.nodes.len())
            .filter(|&i| {
                self.tree.children[i].1 == 0 && self.solve.radiosity[i].max_element() > 0.0
            })
            .count();
        if self.solve.coarse_mu.is_none() || self.solve.coarse_support != support {
            // The furnace mode: every lit leaf's response to a unit irradiance from all around.
            let (u, ux) = self.uniform_field(|i| self.solve.radiosity[i].max_element() > 0.0);
            let ((mu, mux), _) = self.apply(&u, &ux, false);
            let denom = self.leaf_sum(&u) - self.leaf_sum(&mu);
            self.solve.coarse_mu = Some((mu, mux));
            self.solve.coarse_denominator = denom;
            self.solve.coarse_support = support;
        }
        let b = std::mem::take(&mut self.solve.radiosity);
        let ((mut next, mut next_x), h) = self.apply(&b, &self.solve.exitance, true);
        let residual = self.leaf_sum(&next) - self.leaf_sum(&b);
        let denom = self.solve.coarse_denominator;
        let scale = self
            .leaf_sum(&next)
            .abs()
            .max_element()
            .max(f64::MIN_POSITIVE);
        let mut c = Rgb::ZERO;
        for k in 0..3 {
            // Only where the correction is well defined (u − M u carries weight).
            if denom[k] > 1e-12 * scale.max(1.0) && denom[k].is_finite() {
                c[k] = residual[k] / denom[k];
            }
        }
        if let Some((mu, mux)) = &self.solve.coarse_mu
            && c != Rgb::ZERO
        {
            for (x, m) in next.iter_mut().zip(mu) {
                *x += c * *m;
            }
            for (x, m) in next_x.iter_mut().zip(mux) {
                x.add_scaled(c, m);
            }
        }
        // Size of the pass.
        let mut diff = 0.0;
        let mut norm = 0.0;
        for i in 0..self.tree.nodes.len() {
            if self.tree.children[i].1 == 0 {
                let a = self.tree.nodes[i].area();
                diff += a * (next[i] - b[i]).abs().element_sum();
                norm += a * next[i].abs().element_sum();
            }
        }
        if !(diff.is_finite() && norm.is_finite()) {
            self.solve.radiosity = b;
            return Err(SolveError::Numerical(
                "the hierarchical solution became non-finite: the discrete operator's gain exceeds one \
                 (with gather=link close to rho = 1 the per-link means overestimate form-factor sums; \
                 use gather=leaf; with clusters, lower epsilon)"
                    .into(),
            ));
        }
        let step = if norm > 0.0 { diff / norm } else { 0.0 };
        // A fixed operator whose gain exceeds one: each pass changes the solution (in power, Σ A |ΔB|) at
        // least as much as the one before, and the solution grows without bound, slowly enough near ρ = 1 to
        // stay finite for 10⁵ passes. (The relative change diff/norm shrinks either way.)
        self.solve.growing_passes = match self.solve.last_diff {
            Some(prev) if self.solve.passes_since_change >= 1 && diff > 0.0 && diff >= prev => {
                self.solve.growing_passes + 1
            }
            _ => 0,
        };
        self.solve.last_diff = Some(diff);
        if self.solve.growing_passes >= DIVERGING_PASSES {
            self.solve.radiosity = b;
            return Err(SolveError::Numerical(format!(
                "the hierarchical solution diverges: {DIVERGING_PASSES} passes in a row, with the links \
                 unchanged, each changed it at least as much as the one before (relative change {step:.3e}, \
                 solution norm {norm:.3e}), \
                 so the discrete operator's gain exceeds one: its rows sum above 1/rho somewhere (close to \
                 rho = 1 a small excess of the clusters' point transfers is enough); lower epsilon, or \
                 lower the reflectance"
            )));
        }
        self.solve.radiosity = next;
        self.solve.exitance = next_x;
        self.solve.irradiance = h;
        self.solve.passes_since_change += 1;
        let estimate = match self.solve.last_norm {
            Some(prev) if self.solve.passes_since_change >= 2 => {
                if step == 0.0 {
                    0.0
                } else if prev > 0.0 {
                    let q = (step / prev).clamp(0.05, 0.9999);
                    step * q / (1.0 - q)
                } else {
                    step
                }
            }
            _ => f64::INFINITY,
        };
        self.solve.last_norm = Some(step);
        self.solve.residual = Some(if estimate.is_finite() { estimate } else { step });
        self.solve.converged = estimate < self.params.tolerance;
        Ok(estimate)
    }
}

/// Passes in a row, under one operator, each changing the solution at least as much as the one before, after
/// which the iteration is declared divergent. A contraction's changes shrink by its gain every pass (by
/// 0.999 per pass in a furnace at ρ = 0.999), so even one such pass is rare; fifty in a row is growth.
pub(crate) const DIVERGING_PASSES: u32 = 50;

/// b/ρ: the irradiance H behind a leaf's reflected b = ρ H, zero where ρ is zero.
fn per_unit(b: f64, rho: f64) -> f64 {
    if rho > 0.0 { b / rho } else { 0.0 }
}

/// 1/r, or 1 where r is not a positive row sum (nothing gathered: nothing to rescale).
fn inverse(r: f64) -> f64 {
    if r > 0.0 && r.is_finite() {
        1.0 / r
    } else {
        1.0
    }
}

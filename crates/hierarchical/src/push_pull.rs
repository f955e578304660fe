//! One solution pass over the hierarchy: gather, push, pull (survey 2.4.2; HSA91):
//!
//! - gather: H_r = Σ_{links r←s} K_rs B_s at every node with links (in parallel over receivers);
//! - push: a leaf's irradiance is the sum of the gathered H over itself and its ancestors, and its radiosity
//!   B = E + ρ ⊙ H;
//! - pull: an inner node's radiosity is the area mean of its children's, B_p = Σ_c A_c B_c / A_p, so the
//!   power a node sends is exactly the power of its leaves.
//!
//! This is one Jacobi sweep B ← E + M B of the hierarchical operator M = ρ ⊙ push ∘ gather ∘ pull. Close to
//! ρ = 1 a sweep shrinks the error's slowest mode (nearly uniform over the scene) only by about ρ, so each pass
//! adds a one-dimensional coarse correction along u = ρ (per channel), chosen so the area-weighted residual
//! vanishes: c = Σ A r / Σ A (u − M u), B ← E + M (B + c u) — the error of the furnace's dominant mode is removed
//! in one pass (a Petrov–Galerkin two-level step; it plays the role of Cohen et al.'s 1988 ambient term, but
//! inside the iteration). The pass's size, ‖ΔB‖/‖B‖ (area-weighted L1 over leaves), and the observed
//! contraction q between passes give the estimated remaining error ‖ΔB‖ q/(1 − q).
//!
//! Reductions are sequential in node order, so results are bit-identical for any thread count.

use radlab_scene::{Rgb, SolveError};
use rayon::prelude::*;

use crate::hierarchy::{Engine, NONE};
use crate::link::Kernel;
use crate::node::NodeKind;
use crate::params::Gather;

impl<N: NodeKind, K: Kernel<N>> Engine<N, K> {
    /// Applies M (and adds E when `with_emission`) to a per-node radiosity `b` whose inner nodes hold the area
    /// means of their children. Returns the new per-node radiosity, inner nodes pulled.
    pub(crate) fn apply(&self, b: &[Rgb], with_emission: bool) -> Vec<Rgb> {
        if self.params.gather == Gather::Leaf {
            let mut out: Vec<Rgb> = self
                .rows
                .par_iter()
                .enumerate()
                .map(|(i, row)| {
                    if self.children[i].1 != 0 {
                        return Rgb::ZERO;
                    }
                    let mut h = Rgb::ZERO;
                    for &(s, c) in row {
                        h += c * b[s as usize];
                    }
                    let node = &self.nodes[i];
                    let e = if with_emission {
                        node.emission()
                    } else {
                        Rgb::ZERO
                    };
                    e + node.reflectance() * h
                })
                .collect();
            self.pull(&mut out);
            return out;
        }
        // Gather.
        let gathered: Vec<Rgb> = self
            .links
            .par_iter()
            .map(|ls| {
                let mut h = Rgb::ZERO;
                for l in ls {
                    h += l.coefficient * b[l.source as usize];
                }
                h
            })
            .collect();
        // Push: parents precede children in id order.
        let n = self.nodes.len();
        let mut acc = gathered;
        for i in 0..n {
            let p = self.parent[i];
            if p != NONE {
                let up = acc[p as usize];
                acc[i] += up;
            }
        }
        let mut out = vec![Rgb::ZERO; n];
        for i in 0..n {
            if self.children[i].1 == 0 {
                let node = &self.nodes[i];
                let e = if with_emission {
                    node.emission()
                } else {
                    Rgb::ZERO
                };
                out[i] = e + node.reflectance() * acc[i];
            }
        }
        self.pull(&mut out);
        out
    }

    /// Sets every inner node to the area mean of its children (children follow parents in id order).
    pub(crate) fn pull(&self, b: &mut [Rgb]) {
        for i in (0..self.nodes.len()).rev() {
            let (first, count) = self.children[i];
            if count == 0 {
                continue;
            }
            let mut sum = Rgb::ZERO;
            let mut area = 0.0;
            for c in first..first + count {
                let a = self.nodes[c as usize].area();
                sum += a * b[c as usize];
                area += a;
            }
            b[i] = if area > 0.0 { sum / area } else { Rgb::ZERO };
        }
    }

    /// Area-weighted sum over leaves of a per-node vector (per channel), in node order.
    fn leaf_sum(&self, v: &[Rgb]) -> Rgb {
        let mut s = Rgb::ZERO;
        for ((node, c), x) in self.nodes.iter().zip(&self.children).zip(v) {
            if c.1 == 0 {
                s += node.area() * *x;
            }
        }
        s
    }

    /// One gather/push-pull pass with the coarse correction. Returns the estimated remaining relative error
    /// (infinite until two passes have run on the current links).
    pub(crate) fn solve_pass(&mut self) -> Result<f64, SolveError> {
        if self.params.gather == Gather::Leaf && self.dirty.iter().any(|&d| d) {
            self.rebuild_rows();
        }
        if self.coarse_mu.is_none() {
            let mut u: Vec<Rgb> = (0..self.nodes.len())
                .map(|i| {
                    if self.children[i].1 == 0 {
                        self.nodes[i].reflectance()
                    } else {
                        Rgb::ZERO
                    }
                })
                .collect();
            self.pull(&mut u);
            let mu = self.apply(&u, false);
            let denom = self.leaf_sum(&u) - self.leaf_sum(&mu);
            self.coarse_mu = Some(mu);
            self.coarse_denominator = denom;
        }
        let b = std::mem::take(&mut self.radiosity);
        let mut next = self.apply(&b, true);
        let residual = self.leaf_sum(&next) - self.leaf_sum(&b);
        let denom = self.coarse_denominator;
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
        if let Some(mu) = &self.coarse_mu
            && c != Rgb::ZERO
        {
            for (x, m) in next.iter_mut().zip(mu) {
                *x += c * *m;
            }
        }
        // Size of the pass.
        let mut diff = 0.0;
        let mut norm = 0.0;
        for i in 0..self.nodes.len() {
            if self.children[i].1 == 0 {
                let a = self.nodes[i].area();
                diff += a * (next[i] - b[i]).abs().element_sum();
                norm += a * next[i].abs().element_sum();
            }
        }
        if !(diff.is_finite() && norm.is_finite()) {
            self.radiosity = b;
            return Err(SolveError::Numerical(
                "the hierarchical solution became non-finite: the discrete operator's gain exceeds one \
                 (with gather=link close to rho = 1 the per-link means overestimate form-factor sums; \
                 use gather=leaf)"
                    .into(),
            ));
        }
        self.radiosity = next;
        let step = if norm > 0.0 { diff / norm } else { 0.0 };
        self.passes_since_change += 1;
        let estimate = match self.last_norm {
            Some(prev) if self.passes_since_change >= 2 => {
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
        self.last_norm = Some(step);
        self.residual = Some(if estimate.is_finite() { estimate } else { step });
        self.converged = estimate < self.params.tolerance;
        Ok(estimate)
    }
}

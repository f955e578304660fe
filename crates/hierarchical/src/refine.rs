//! Link creation and refinement (Hanrahan, Salzman & Aupperle 1991).
//!
//! Initial links join every ordered pair of roots that can exchange light (for patches: input faces each
//! partly in front of the other, with a non-zero transfer): the O(k²) start of classic hierarchical radiosity.
//! Never a self-link between patches. With lazy linking (Holzschuch, Sillion & Drettakis 1994) the links from a
//! root as a source are only made once it carries light.
//!
//! A refinement pass asks the oracle about every link once ([`crate::oracle::decide`]), splits the elements it
//! names (lazily: a node gets its children the first time a link needs them), and replaces each refined link by
//! the links between the children and the other end. Decisions and the new links' transfers run in parallel;
//! the new nodes are numbered in a fixed order, and each link's rays come from a stream hashed from its two
//! node ids, so the hierarchy is the same for any thread count.

use radlab_method::SolveError;
use rayon::prelude::*;

use crate::hierarchy::Engine;
use crate::node::NodeKind;
use crate::oracle::{Action, decide, light_weight};
use crate::params::ErrorNorm;
use crate::transport::{LinkPayload, SourceLight, Transport};

impl<N: NodeKind, T: Transport<N>> Engine<N, T> {
    /// Whether root `r` carries light now (emits, or has received some).
    pub(crate) fn root_is_lit(&self, r: u32) -> bool {
        self.solve.radiosity[r as usize].max_element() > 0.0
            || self.tree.nodes[r as usize].emission().max_element() > 0.0
    }

    /// Creates the initial links from every root in `new_sources` (as sources) to every root that can receive
    /// from it, then marks them linked. Returns the number of links made.
    pub(crate) fn link_roots(&mut self, new_sources: &[u32]) -> Result<usize, SolveError> {
        let k = self.tree.roots.len();
        let mut is_new = vec![false; k];
        for &s in new_sources {
            is_new[s as usize] = true;
        }
        // Count candidate pairs first, so an impossible k² is refused before it is built.
        let candidates: usize = (0..k)
            .into_par_iter()
            .map(|r| {
                (0..k)
                    .filter(|&s| {
                        s != r
                            && is_new[s]
                            && self.kernel.may_interact(
                                &self.tree.nodes[self.tree.roots[r] as usize],
                                &self.tree.nodes[self.tree.roots[s] as usize],
                            )
                    })
                    .count()
            })
            .collect::<Vec<_>>()
            .into_iter()
            .sum();
        self.check_budget(candidates, 0)?;
        let made: Vec<Vec<T::Link>> = (0..k)
            .into_par_iter()
            .map(|r| {
                let rid = self.tree.roots[r];
                let recv = &self.tree.nodes[rid as usize];
                (0..k)
                    .filter(|&s| s != r && is_new[s])
                    .filter_map(|s| {
                        let sid = self.tree.roots[s];
                        let src = &self.tree.nodes[sid as usize];
                        if self.kernel.may_interact(recv, src) {
                            self.kernel.link(recv, rid, src, sid)
                        } else {
                            None
                        }
                    })
                    .collect()
            })
            .collect();
        let mut count = 0;
        for (r, ls) in made.into_iter().enumerate() {
            count += ls.len();
            if !ls.is_empty() {
                self.cache.dirty[self.tree.roots[r] as usize] = true;
            }
            self.links.by_receiver[self.tree.roots[r] as usize].extend(ls);
        }
        self.form_factors += candidates as u64;
        for &s in new_sources {
            self.links.linked[s as usize] = true;
        }
        if count > 0 {
            self.operator_changed();
        }
        Ok(count)
    }

    /// Adds the link `recv ← src` computed by the transport (a volume-cluster method starts from its root's
    /// self-link). Returns whether a link was made (the transport may find nothing to transfer).
    pub fn add_link(&mut self, recv: u32, src: u32) -> Result<bool, SolveError> {
        let n = self.tree.nodes.len() as u32;
        if recv >= n || src >= n {
            return Err(SolveError::param(
                "link",
                format!("node {recv} or {src} does not exist ({n} nodes)"),
            ));
        }
        self.check_budget(1, 0)?;
        self.form_factors += 1;
        let l = self.kernel.link(
            &self.tree.nodes[recv as usize],
            recv,
            &self.tree.nodes[src as usize],
            src,
        );
        let made = l.is_some();
        if let Some(l) = l {
            self.links.by_receiver[recv as usize].push(l);
            self.cache.dirty[recv as usize] = true;
            self.operator_changed();
        }
        Ok(made)
    }

    /// Marks every root as linked, so the schedule creates no initial links of its own (for methods that
    /// start from links they add themselves).
    pub fn skip_initial_links(&mut self) {
        self.links.linked.iter_mut().for_each(|l| *l = true);
    }

    /// Roots that are lit but not yet linked as sources (all unlinked roots when `lazy` is false).
    pub(crate) fn pending_sources(&self, lazy: bool) -> Vec<u32> {
        (0..self.tree.roots.len() as u32)
            .filter(|&r| {
                !self.links.linked[r as usize]
                    && (!lazy || self.root_is_lit(self.tree.roots[r as usize]))
            })
            .collect()
    }

    /// The area-mean radiosity of the scene (max channel; each root's open-part radiosity over its open
    /// area): the BF and variation oracles' scale.
    pub(crate) fn radiosity_scale(&self) -> f64 {
        let (mut sum, mut area) = (radlab_scene::Rgb::ZERO, 0.0);
        for &r in &self.tree.roots {
            let a = self.tree.nodes[r as usize].area();
            sum += a * self.solve.open[r as usize] * self.solve.radiosity[r as usize];
            area += a;
        }
        if area > 0.0 {
            (sum / area).max_element()
        } else {
            0.0
        }
    }

    /// One refinement pass at threshold `epsilon`: each link is examined once. Returns the number of links
    /// replaced.
    ///
    /// A decision reads only the link, its two ends, the source's radiosity and the scene's mean radiosity,
    /// none of which a refinement pass changes for the links it keeps: so when the last pass ran at the same
    /// threshold and no solve pass came between (a stage of the scheduled schedule refining until nothing
    /// changes), the links it kept are kept again without asking the oracle, and only the links made since
    /// are examined. A stage's passes then cost its links once, not once per level the stage descends.
    pub(crate) fn refine_pass(&mut self, epsilon: f64) -> Result<usize, SolveError> {
        // Per receiver, its first link the oracle is asked about (those before it are kept).
        let open_from: Vec<usize> = if self.links.settled_epsilon == Some(epsilon) {
            self.links.settled.iter().map(|&n| n as usize).collect()
        } else {
            vec![0; self.links.by_receiver.len()]
        };
        let oracle = self.params.oracle;
        let min_size = self.min_size;
        let scale = self.radiosity_scale();
        let total_area: f64 = self
            .tree
            .roots
            .iter()
            .map(|&r| self.tree.nodes[r as usize].area())
            .sum();
        let power_norm = self.params.error_norm == ErrorNorm::Power && total_area > 0.0;
        let decisions: Vec<Vec<Action>> = self
            .links
            .by_receiver
            .par_iter()
            .enumerate()
            .map(|(r, ls)| {
                let recv = &self.tree.nodes[r];
                ls[open_from[r]..]
                    .iter()
                    .map(|l| {
                        let src = &self.tree.nodes[l.source() as usize];
                        let w = light_weight(
                            recv.reflectance(),
                            self.solve.radiosity[l.source() as usize],
                            scale,
                        );
                        let error = (!l.overlap()).then(|| {
                            let (first, count) = self.tree.children[l.source() as usize];
                            let kids = first as usize..(first + count) as usize;
                            let light = SourceLight {
                                oracle,
                                weight: w,
                                radiosity: self.solve.radiosity[l.source() as usize],
                                exitance: &self.solve.exitance[l.source() as usize],
                                scale,
                                children: &self.tree.nodes[kids.clone()],
                                child_radiosity: &self.solve.radiosity[kids.clone()],
                                child_exitance: &self.solve.exitance[kids],
                            };
                            self.kernel.link_error(recv, src, l, &light)
                        });
                        decide(
                            epsilon,
                            min_size,
                            recv,
                            src,
                            r as u32 == l.source(),
                            error,
                            if power_norm {
                                recv.area() / total_area
                            } else {
                                1.0
                            },
                        )
                    })
                    .collect()
            })
            .collect();
        // `decisions[r]` covers the links of receiver r from `open_from[r]` on.
        // Elements to split, in id order.
        let mut to_split = Vec::new();
        for (r, (ls, ds)) in self.links.by_receiver.iter().zip(&decisions).enumerate() {
            for (l, d) in ls[open_from[r]..].iter().zip(ds) {
                if matches!(d, Action::SplitReceiver | Action::SplitBoth) {
                    to_split.push(r as u32);
                }
                if matches!(d, Action::SplitSource | Action::SplitBoth) {
                    to_split.push(l.source());
                }
            }
        }
        to_split.sort_unstable();
        to_split.dedup();
        to_split.retain(|&i| self.is_leaf(i));
        // What this pass keeps is settled at this threshold (a receiver's kept links stay first, and the
        // links made below are appended after them).
        let mut replaced = 0;
        for (r, ds) in decisions.iter().enumerate() {
            let changed = ds.iter().filter(|d| **d != Action::Keep).count();
            replaced += changed;
            self.links.decisions += ds.len() as u64;
            self.links.settled[r] = (open_from[r] + ds.len() - changed) as u32;
        }
        self.links.settled_epsilon = Some(epsilon);
        if replaced == 0 {
            return Ok(0);
        }
        if let Err(e) = self.check_budget(replaced * 16, to_split.len() * 4) {
            // The links are not yet reordered as the settled counts assume.
            self.links.settled_epsilon = None;
            return Err(e);
        }
        for i in to_split {
            self.split_node(i);
        }
        // Replace refined links by links between children, in a fixed order.
        let mut specs: Vec<(u32, u32)> = Vec::new();
        for (r, ds) in decisions.iter().enumerate() {
            if ds.iter().all(|d| *d == Action::Keep) {
                continue;
            }
            let mut old = std::mem::take(&mut self.links.by_receiver[r]).into_iter();
            let mut kept = Vec::with_capacity(old.len());
            kept.extend(old.by_ref().take(open_from[r]));
            for (l, d) in old.zip(ds) {
                let s = l.source();
                match d {
                    Action::Keep => kept.push(l),
                    Action::SplitReceiver => {
                        for c in self.children(r as u32) {
                            specs.push((c, s));
                        }
                    }
                    Action::SplitSource => {
                        for c in self.children(s) {
                            specs.push((r as u32, c));
                        }
                    }
                    Action::SplitBoth => {
                        for a in self.children(r as u32) {
                            for b in self.children(s) {
                                specs.push((a, b));
                            }
                        }
                    }
                }
            }
            self.links.by_receiver[r] = kept;
            self.cache.dirty[r] = true;
        }
        self.check_budget(specs.len(), 0)?;
        let made: Vec<Option<T::Link>> = specs
            .par_iter()
            .map(|&(r, s)| {
                self.kernel.link(
                    &self.tree.nodes[r as usize],
                    r,
                    &self.tree.nodes[s as usize],
                    s,
                )
            })
            .collect();
        self.form_factors += specs.len() as u64;
        for ((r, _), l) in specs.into_iter().zip(made) {
            if let Some(l) = l {
                self.links.by_receiver[r as usize].push(l);
                self.cache.dirty[r as usize] = true;
            }
        }
        self.operator_changed();
        Ok(replaced)
    }

    /// Forget what the solver knew about the old operator.
    pub(crate) fn operator_changed(&mut self) {
        self.solve.coarse_mu = None;
        self.solve.passes_since_change = 0;
        self.solve.growing_passes = 0;
        self.solve.last_diff = None;
        self.solve.last_norm = None;
        self.solve.converged = false;
    }
}

#[cfg(test)]
mod tests {
    use radlab_scene::{Scene, builtin};
    use radlab_visibility::Accel;

    use crate::HierarchicalSolver;
    use crate::params::HierarchicalParams;

    /// The Cornell box's initial links refined at one threshold until a pass changes nothing, forgetting the
    /// settled links before every pass when `forget`: the solver, the links replaced over all passes, and the
    /// links there were at the start of each pass.
    fn refine_to_rest<'a>(
        scene: &'a Scene,
        accel: &'a Accel,
        forget: bool,
    ) -> (HierarchicalSolver<'a>, u64, u64) {
        let mut s = HierarchicalSolver::new(scene, accel, HierarchicalParams::default(), 3)
            .expect("solver");
        let e = s.engine_mut();
        let all = e.pending_sources(false);
        e.link_roots(&all).expect("links");
        let (mut replaced, mut at_start) = (0, 0);
        loop {
            if forget {
                e.links.settled_epsilon = None;
            }
            at_start += e.link_count() as u64;
            let r = e.refine_pass(1e-2).expect("refine") as u64;
            if r == 0 {
                break;
            }
            replaced += r;
        }
        (s, replaced, at_start)
    }

    #[test]
    fn refinement_passes_at_one_threshold_ask_only_about_new_links() {
        let scene = builtin("cornell").expect("cornell");
        let accel = Accel::new(&scene);
        let (settled, replaced, _) = refine_to_rest(&scene, &accel, false);
        let (fresh, _, at_start) = refine_to_rest(&scene, &accel, true);
        let (settled, fresh) = (settled.engine(), fresh.engine());
        // The same hierarchy and links, in the same order.
        assert_eq!(settled.tree.nodes.len(), fresh.tree.nodes.len());
        assert_eq!(settled.form_factors, fresh.form_factors);
        for (a, b) in settled
            .links
            .by_receiver
            .iter()
            .zip(&fresh.links.by_receiver)
        {
            let (sa, sb): (Vec<u32>, Vec<u32>) = (
                a.iter().map(|l| l.source).collect(),
                b.iter().map(|l| l.source).collect(),
            );
            assert_eq!(sa, sb);
        }
        // Settled: each link that ever existed was asked about once (those replaced, and those left).
        // Afresh: every link at every pass it was there for.
        assert_eq!(
            settled.links.decisions,
            settled.link_count() as u64 + replaced
        );
        assert_eq!(fresh.links.decisions, at_start);
        assert!(fresh.links.decisions > settled.links.decisions);
    }
}

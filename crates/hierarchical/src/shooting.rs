//! Linkless shooting (Stamminger, Schirmacher, Slusallek & Seidel 1998, "Getting rid of links in hierarchical
//! radiosity", CGF 17(3)): the hierarchical system B = E + M B solved without storing links. Each step is a
//! sweep that shoots, in root order, the unshot radiosity R of every input face that is lit or whose unshot
//! power Σ A |R| is at least [`SHOOT_SHARE`] of the largest. A shot from root s refines the pairs (r, s) top
//! down from every root r that may receive from s, with the same oracle and ε as the linked engine, the
//! oracle weighing each link by the source's *unshot* radiosity; the links the oracle keeps are held until
//! the shot's refinement is done, then deliver ΔH_t = c_{t,l} ⊗ emit(R) at their gather targets (as
//! [`crate::Transport::gather_at`] says; the leaves the shot leaves) and are dropped. ΔH is pushed down,
//! every leaf adds ρ ΔH to its unshot radiosity and to its radiosity, and the source's unshot radiosity is
//! zero.
//!
//! The state is the solution B (what the engine shows: E + ρ H at the leaves, H all irradiance received,
//! pulled above) and the residual R = E + M B_s − B_s of what has been shot, B_s = B − R: B_s +
//! (I − M)⁻¹ R is the discrete solution after every shot (a Southwell iteration, as Gortler, Cohen &
//! Slusallek 1994 read progressive radiosity). R is held per leaf as shares of the leaf's emission and of
//! its uniform response (per channel) and an irradiance not yet shot, so a split hands it to the children
//! by the transport's push.
//!
//! Near ρ = 1 a sweep shrinks R only by about ρ. Each sweep therefore also sends u, every lit leaf's
//! response to unit irradiance (ρ for a patch), through the same links, which gives M u at no extra link;
//! then B_s += c u, R −= c (u − M u) keeps the invariant exactly, and c = Σ A R / Σ A (u − M u) per channel
//! makes the area-weighted residual vanish: the engine's coarse correction (the `push_pull` module). It is
//! taken only after a sweep that split no element: links made while elements were being split delivered to
//! elements since split, and c (about 1/(1 − ρ)) would magnify that. In the furnace the first such sweep
//! removes R up to the discretisation. Converged when the remaining error estimate Σ A |R| / Σ A |B| /
//! (1 − q), q = Σ A M u / Σ A u, falls below the tolerance.
//!
//! An optional cache ([`LinkCache`]) keeps computed links and their coefficients at the gather targets, keyed
//! by (receiver, source) node pair, up to a byte bound, evicting the least recently used (by shot counter;
//! ties by key): a later shot from the same source reuses them, with the same numbers (a link is a pure
//! function of its two ends and the seed), so results are bit-identical with and without the cache. Every
//! link and coefficient computed is counted as a kernel evaluation each time it is computed, and every ray
//! through the accelerator; the bytes held are the elements, the shooting state, the cache and the largest
//! set of transient links (one refinement level, or the links one shot keeps, with their coefficients).
//!
//! Limits: an element split after it received light holds that light pushed from its parent (the
//! receiver gather's approximation, within the oracle's ε for the link that delivered it), where the linked
//! leaf gather re-integrates it at the new leaves; so linkless answers differ from linked ones by about ε.
//! Links whose transport weighs source leaves ([`crate::Transport::weighs_source_leaves`]) send their
//! [`crate::Transport::emit`] instead, and open shares are not estimated (every leaf open): the wavelet
//! transport needs neither.

use std::collections::{BTreeSet, HashMap};

use radlab_method::SolveError;
use radlab_scene::Rgb;
use rayon::prelude::*;

use crate::hierarchy::{Engine, NONE};
use crate::node::NodeKind;
use crate::oracle::{Action, decide, light_weight};
use crate::params::ErrorNorm;
use crate::transport::{GatherAt, LinearState, LinkPayload, SourceLight, Transport};

/// A root shoots in a sweep when its unshot power is at least this share of the largest root's.
pub const SHOOT_SHARE: f64 = 0.1;

/// Kept links whose coefficients are computed and delivered together (one chunk's coefficients are the
/// transient memory of a shot's delivery, besides its kept links).
const DELIVERY_CHUNK: usize = 64;

/// Bytes a cache entry costs beyond its link and coefficients (key in the map and in the recency order).
const ENTRY_OVERHEAD: usize = 48;

/// A link's coefficients at its gather targets, the number computed, and whether they differ from the
/// cached ones.
type Delivery<C> = (Vec<(u32, C)>, u64, bool);

/// A cached link and its coefficients at the gather targets it was delivered to (by target id).
#[derive(Debug)]
struct CacheEntry<L, C> {
    link: L,
    coefficients: Vec<(u32, C)>,
    last_used: u64,
}

/// A bounded cache of computed links keyed by (receiver, source) node pair; least recently used evicted
/// first (by shot counter, ties by key).
#[derive(Debug)]
pub struct LinkCache<L, C> {
    capacity: usize,
    held: usize,
    map: HashMap<(u32, u32), CacheEntry<L, C>>,
    order: BTreeSet<(u64, (u32, u32))>,
    /// Links found in the cache.
    pub hits: u64,
    /// Links not found (computed).
    pub misses: u64,
    /// Entries evicted.
    pub evictions: u64,
}

impl<L, C> LinkCache<L, C> {
    fn new(capacity: usize) -> Self {
        Self {
            capacity,
            held: 0,
            map: HashMap::new(),
            order: BTreeSet::new(),
            hits: 0,
            misses: 0,
            evictions: 0,
        }
    }

    fn entry_bytes(n: usize) -> usize {
        size_of::<L>() + n * size_of::<(u32, C)>() + ENTRY_OVERHEAD
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.held
    }

    fn get(&self, key: (u32, u32)) -> Option<&CacheEntry<L, C>> {
        self.map.get(&key)
    }

    fn touch(&mut self, key: (u32, u32), now: u64) {
        if let Some(e) = self.map.get_mut(&key) {
            self.order.remove(&(e.last_used, key));
            e.last_used = now;
            self.order.insert((now, key));
        }
    }

    /// Inserts (or replaces) an entry, evicting the least recently used until it fits; an entry larger
    /// than the whole cache is not kept.
    fn insert(&mut self, key: (u32, u32), link: L, coefficients: Vec<(u32, C)>, now: u64) {
        if let Some(old) = self.map.remove(&key) {
            self.order.remove(&(old.last_used, key));
            self.held -= Self::entry_bytes(old.coefficients.len());
        }
        let need = Self::entry_bytes(coefficients.len());
        if need > self.capacity {
            return;
        }
        while self.held + need > self.capacity {
            let Some(&(t, k)) = self.order.iter().next() else {
                break;
            };
            self.order.remove(&(t, k));
            if let Some(e) = self.map.remove(&k) {
                self.held -= Self::entry_bytes(e.coefficients.len());
                self.evictions += 1;
            }
        }
        self.held += need;
        self.order.insert((now, key));
        self.map.insert(
            key,
            CacheEntry {
                link,
                coefficients,
                last_used: now,
            },
        );
    }
}

/// The state of linkless shooting (see the module documentation).
#[derive(Debug)]
pub(crate) struct ShootState<I, L, C> {
    /// Per node (leaves meaningful): the unshot shares of the emission and of the uniform response (the
    /// coarse correction's direction), per channel.
    unshot_e: Vec<(Rgb, Rgb)>,
    /// Per node (leaves meaningful): the irradiance received and not yet shot.
    unshot_h: Vec<I>,
    /// Per node: what it shot in its face's last shot (shares and irradiance), which a source node split
    /// during its own shot hands to its children.
    shot_e: Vec<(Rgb, Rgb)>,
    shot_h: Vec<I>,
    /// Per node: the irradiance the coarse direction u (ρ on the lit leaves) delivered this sweep, M u.
    sweep_h: Vec<I>,
    cache: Option<LinkCache<L, C>>,
    /// The returned share q = Σ A M u / Σ A u of the last sweep (per channel).
    last_share: Rgb,
    shots: u64,
    sweeps: u64,
    corrections: u64,
    /// Whether an element was split during the current sweep (the operator changed under it).
    split_in_sweep: bool,
    links_made: u64,
    peak_transient: usize,
}

impl<I: LinearState, L, C> ShootState<I, L, C> {
    fn bytes(&self) -> usize {
        self.unshot_e.capacity() * size_of::<(Rgb, Rgb)>() * 2
            + (self.unshot_h.capacity() + self.shot_h.capacity() + self.sweep_h.capacity())
                * size_of::<I>()
            + self.cache.as_ref().map_or(0, |c| c.bytes())
            + self.peak_transient
    }
}

/// The unshot (or shot) radiosity of a leaf from its emission share and irradiance.
fn leaf_radiosity<N: NodeKind, T: Transport<N>>(
    kernel: &T,
    leaf: &N,
    (e, w): (Rgb, Rgb),
    h: &T::Irradiance,
) -> (Rgb, T::Exitance) {
    let (b, mut x) = kernel.reflect(leaf, h, false);
    let mut b = b + e * leaf.emission();
    if w != Rgb::ZERO {
        let (ub, ux) = kernel.uniform_response(leaf);
        b += w * ub;
        x.add_scaled(w, &ux);
    }
    (b, x)
}

impl<N: NodeKind, T: Transport<N>> Engine<N, T> {
    /// Switches the engine to linkless shooting (before its first step), with a cache of computed links of
    /// at most `cache_bytes` (0: none). The schedule, stages and lazy linking are then not used; ε, the
    /// oracle, the minimum element, the tolerance and the step cap are.
    pub fn set_linkless(&mut self, cache_bytes: usize) {
        let n = self.tree.nodes.len();
        self.shooting = Some(ShootState {
            unshot_e: vec![(Rgb::ONE, Rgb::ZERO); n],
            unshot_h: vec![T::Irradiance::default(); n],
            shot_e: vec![(Rgb::ZERO, Rgb::ZERO); n],
            shot_h: vec![T::Irradiance::default(); n],
            sweep_h: vec![T::Irradiance::default(); n],
            cache: (cache_bytes > 0).then(|| LinkCache::new(cache_bytes)),
            last_share: Rgb::ZERO,
            shots: 0,
            sweeps: 0,
            corrections: 0,
            split_in_sweep: false,
            links_made: 0,
            peak_transient: 0,
        });
    }

    /// Whether the engine shoots without links ([`Engine::set_linkless`]).
    pub fn is_linkless(&self) -> bool {
        self.shooting.is_some()
    }

    /// Linkless shooting's counters by name (empty for the linked engine): shots, sweeps, sweep
    /// corrections, links made (computed or found in the cache, all dropped after their transfer), cache
    /// hits, misses and evictions, and the peak bytes of one refinement level's transient links.
    pub fn shooting_counters(&self) -> Vec<(&'static str, u64)> {
        let Some(s) = &self.shooting else {
            return Vec::new();
        };
        let (h, m, e) = s
            .cache
            .as_ref()
            .map_or((0, 0, 0), |c| (c.hits, c.misses, c.evictions));
        vec![
            ("shots", s.shots),
            ("sweeps", s.sweeps),
            ("sweep_corrections", s.corrections),
            ("transient_links", s.links_made),
            ("link_cache_hits", h),
            ("link_cache_misses", m),
            ("link_cache_evictions", e),
            ("peak_transient_bytes", s.peak_transient as u64),
        ]
    }

    /// Bytes of the shooting state, its cache and the peak transient links (0 for the linked engine).
    pub(crate) fn shooting_bytes(&self) -> usize {
        self.shooting.as_ref().map_or(0, |s| s.bytes())
    }

    /// The unshot radiosity of every leaf and, pulled, of every inner node.
    fn unshot_field(&self) -> (Vec<Rgb>, Vec<T::Exitance>) {
        let s = self.shooting.as_ref().expect("linkless");
        let (mut b, mut x): (Vec<Rgb>, Vec<T::Exitance>) = (0..self.tree.nodes.len())
            .map(|i| {
                if self.tree.children[i].1 == 0 {
                    leaf_radiosity(
                        &self.kernel,
                        &self.tree.nodes[i],
                        s.unshot_e[i],
                        &s.unshot_h[i],
                    )
                } else {
                    (Rgb::ZERO, T::Exitance::default())
                }
            })
            .unzip();
        self.pull(&mut b, &mut x);
        (b, x)
    }

    /// The leaves below node `i` (itself if a leaf), in id order of the walk.
    fn leaves_below(&self, i: u32, out: &mut Vec<u32>) {
        let mut stack = vec![i];
        while let Some(j) = stack.pop() {
            let (first, count) = self.tree.children[j as usize];
            if count == 0 {
                out.push(j);
            } else {
                stack.extend((first..first + count).rev());
            }
        }
    }

    /// Splits leaf `i` during shooting: the children inherit the parent's shooting state and this shot's
    /// irradiance so far (`dh`: from the unshot radiosity and from the coarse direction) by the
    /// transport's push.
    fn shoot_split(&mut self, i: u32, dh: &mut [Vec<T::Irradiance>; 2]) {
        self.split_node(i);
        let p = &self.tree.nodes[i as usize];
        let s = self.shooting.as_mut().expect("linkless");
        let (ue, se) = (s.unshot_e[i as usize], s.shot_e[i as usize]);
        let (uh, sh, wh, d, du) = (
            s.unshot_h[i as usize],
            s.shot_h[i as usize],
            s.sweep_h[i as usize],
            dh[0][i as usize],
            dh[1][i as usize],
        );
        let (first, count) = self.tree.children[i as usize];
        for c in first..first + count {
            let child = &self.tree.nodes[c as usize];
            s.unshot_e.push(ue);
            s.shot_e.push(se);
            s.unshot_h.push(self.kernel.push(p, child, &uh));
            s.shot_h.push(self.kernel.push(p, child, &sh));
            s.sweep_h.push(self.kernel.push(p, child, &wh));
            dh[0].push(self.kernel.push(p, child, &d));
            dh[1].push(self.kernel.push(p, child, &du));
        }
        dh[0][i as usize] = T::Irradiance::default();
        dh[1][i as usize] = T::Irradiance::default();
    }

    /// Unshot power per root, Σ A |R| (max channel) over its leaves.
    fn unshot_power(&self) -> Vec<f64> {
        let s = self.shooting.as_ref().expect("linkless");
        let mut leaves = Vec::new();
        self.tree
            .roots
            .iter()
            .map(|&r| {
                leaves.clear();
                self.leaves_below(r, &mut leaves);
                let mut p = Rgb::ZERO;
                for &l in &leaves {
                    let node = &self.tree.nodes[l as usize];
                    let (b, _) = leaf_radiosity(
                        &self.kernel,
                        node,
                        s.unshot_e[l as usize],
                        &s.unshot_h[l as usize],
                    );
                    p += node.area() * b.abs();
                }
                p.max_element()
            })
            .collect()
    }

    /// One sweep of linkless shooting; see the module documentation.
    pub(crate) fn shoot_sweep(&mut self) -> Result<(), SolveError> {
        {
            let s = self.shooting.as_mut().expect("linkless");
            s.sweep_h
                .iter_mut()
                .for_each(|h| *h = T::Irradiance::default());
            s.sweeps += 1;
            s.split_in_sweep = false;
        }
        // The coarse direction u: each lit leaf's response to unit irradiance from all around, pulled.
        let n = self.tree.nodes.len();
        let mut support: Vec<bool> = (0..n)
            .map(|i| self.tree.children[i].1 == 0 && self.solve.radiosity[i].max_element() > 0.0)
            .collect();
        let (mut ub, mut ux): (Vec<Rgb>, Vec<T::Exitance>) = (0..n)
            .map(|i| {
                if support[i] {
                    self.kernel.uniform_response(&self.tree.nodes[i])
                } else {
                    (Rgb::ZERO, T::Exitance::default())
                }
            })
            .unzip();
        self.pull(&mut ub, &mut ux);
        let mut lit = vec![false; self.tree.roots.len()];
        let mut leaves = Vec::new();
        for (k, &r) in self.tree.roots.iter().enumerate() {
            leaves.clear();
            self.leaves_below(r, &mut leaves);
            lit[k] = leaves.iter().any(|&l| support[l as usize]);
        }
        let power = self.unshot_power();
        let most = power.iter().copied().fold(0.0, f64::max);
        let sources: Vec<u32> = (0..power.len())
            .filter(|&r| lit[r] || (power[r] > 0.0 && power[r] >= SHOOT_SHARE * most))
            .map(|r| self.tree.roots[r])
            .collect();
        for s in sources {
            self.shoot(s, &mut support, &mut ub, &mut ux)?;
        }
        self.correct_sweep(&support, &ub);
        self.update_display();
        Ok(())
    }

    /// Shoots the unshot radiosity of root `src_root` to every root that may receive from it.
    fn shoot(
        &mut self,
        src_root: u32,
        support: &mut Vec<bool>,
        ub: &mut Vec<Rgb>,
        ux: &mut Vec<T::Exitance>,
    ) -> Result<(), SolveError> {
        let (mut rb, mut rx) = self.unshot_field();
        // The source's leaves: what they hold unshot is shot now.
        let mut src_leaves = Vec::new();
        self.leaves_below(src_root, &mut src_leaves);
        {
            let s = self.shooting.as_mut().expect("linkless");
            for &l in &src_leaves {
                let l = l as usize;
                let (e, h) = (s.unshot_e[l], s.unshot_h[l]);
                s.shot_e[l] = e;
                s.shot_h[l] = h;
                s.unshot_e[l] = (Rgb::ZERO, Rgb::ZERO);
                s.unshot_h[l] = T::Irradiance::default();
            }
            s.shots += 1;
        }
        let now = self.shooting.as_ref().map_or(0, |s| s.shots);
        let mut dh = [
            vec![T::Irradiance::default(); self.tree.nodes.len()],
            vec![T::Irradiance::default(); self.tree.nodes.len()],
        ];
        let scale = self.radiosity_scale();
        let total_area: f64 = self
            .tree
            .roots
            .iter()
            .map(|&r| self.tree.nodes[r as usize].area())
            .sum();
        let power_norm = self.params.error_norm == ErrorNorm::Power && total_area > 0.0;
        let (epsilon, min_size, oracle) = (self.params.epsilon, self.min_size, self.params.oracle);
        let mut frontier: Vec<(u32, u32)> = self
            .tree
            .roots
            .iter()
            .filter(|&&r| {
                r != src_root
                    && self.kernel.may_interact(
                        &self.tree.nodes[r as usize],
                        &self.tree.nodes[src_root as usize],
                    )
            })
            .map(|&r| (r, src_root))
            .collect();
        let mut held: Vec<((u32, u32), T::Link)> = Vec::new();
        while !frontier.is_empty() {
            // The links of this level: from the cache, or computed (in parallel, each a pure function of
            // its two ends).
            let links: Vec<(Option<T::Link>, bool)> = frontier
                .par_iter()
                .map(|&(r, s)| {
                    let cached = self
                        .shooting
                        .as_ref()
                        .and_then(|st| st.cache.as_ref())
                        .and_then(|c| c.get((r, s)).map(|e| e.link.clone()));
                    match cached {
                        Some(l) => (Some(l), true),
                        None => (
                            self.kernel.link(
                                &self.tree.nodes[r as usize],
                                r,
                                &self.tree.nodes[s as usize],
                                s,
                            ),
                            false,
                        ),
                    }
                })
                .collect();
            let computed = links.iter().filter(|(_, hit)| !hit).count();
            self.form_factors += computed as u64;
            // Decisions, weighed by the source's unshot radiosity.
            let actions: Vec<Action> = frontier
                .par_iter()
                .zip(&links)
                .map(|(&(r, s), (l, _))| {
                    let Some(l) = l else {
                        return Action::Keep;
                    };
                    let (recv, src) = (&self.tree.nodes[r as usize], &self.tree.nodes[s as usize]);
                    let light_b = rb[s as usize].abs();
                    let error = (!l.overlap()).then(|| {
                        let light = SourceLight {
                            oracle,
                            weight: light_weight(recv.reflectance(), light_b, scale),
                            radiosity: light_b,
                            exitance: &rx[s as usize],
                            scale,
                            children: &[],
                            child_radiosity: &[],
                            child_exitance: &[],
                        };
                        self.kernel.link_error(recv, src, l, &light)
                    });
                    decide(
                        epsilon,
                        min_size,
                        recv,
                        src,
                        false,
                        error,
                        if power_norm {
                            recv.area() / total_area
                        } else {
                            1.0
                        },
                    )
                })
                .collect();
            // Kept links are held until the shot's refinement is done, so that they are evaluated at the
            // leaves this shot leaves (a leaf split by a later pair of the same shot would otherwise
            // inherit the parent's delivery pushed, the classic receiver gather's approximation).
            {
                let st = self.shooting.as_mut().expect("linkless");
                st.links_made += links.iter().filter(|(l, _)| l.is_some()).count() as u64;
                let level_bytes =
                    links.iter().filter(|(l, _)| l.is_some()).count() * size_of::<T::Link>();
                st.peak_transient = st
                    .peak_transient
                    .max(level_bytes + held.len() * size_of::<T::Link>());
                if let Some(cache) = st.cache.as_mut() {
                    cache.hits += (links.len() - computed) as u64;
                    cache.misses += computed as u64;
                    // Refined links are cached without coefficients (their tensor is reused when the same
                    // pair is asked again); kept ones after delivery, with theirs.
                    for ((&(r, s), (l, _)), a) in frontier.iter().zip(&links).zip(&actions) {
                        let Some(l) = l else { continue };
                        if *a == Action::Keep {
                            continue;
                        }
                        if cache.get((r, s)).is_some() {
                            cache.touch((r, s), now);
                        } else {
                            cache.insert((r, s), l.clone(), Vec::new(), now);
                        }
                    }
                }
            }
            for ((&pair, (l, _)), a) in frontier.iter().zip(links).zip(&actions) {
                if *a == Action::Keep
                    && let Some(l) = l
                {
                    held.push((pair, l));
                }
            }
            // Splits, in id order, then the next level's pairs in a fixed order.
            let mut to_split: Vec<u32> = Vec::new();
            for (&(r, s), a) in frontier.iter().zip(&actions) {
                if matches!(a, Action::SplitReceiver | Action::SplitBoth) {
                    to_split.push(r);
                }
                if matches!(a, Action::SplitSource | Action::SplitBoth) {
                    to_split.push(s);
                }
            }
            to_split.sort_unstable();
            to_split.dedup();
            to_split.retain(|&i| self.is_leaf(i));
            self.check_budget(0, to_split.len() * 4)?;
            if !to_split.is_empty() {
                self.shooting.as_mut().expect("linkless").split_in_sweep = true;
            }
            for &i in &to_split {
                let first_new = self.tree.nodes.len();
                self.shoot_split(i, &mut dh);
                // A split node of the source: its children send the parent's unshot radiosity restricted.
                let st = self.shooting.as_ref().expect("linkless");
                for c in first_new..self.tree.nodes.len() {
                    let node = &self.tree.nodes[c];
                    let in_source = self.below(c as u32, src_root);
                    let (e, h) = if in_source {
                        (st.shot_e[c], &st.shot_h[c])
                    } else {
                        (st.unshot_e[c], &st.unshot_h[c])
                    };
                    let (b, x) = leaf_radiosity(&self.kernel, node, e, h);
                    rb.push(b);
                    rx.push(x);
                    let on = support[i as usize];
                    support.push(on);
                    let (b, x) = if on {
                        self.kernel.uniform_response(node)
                    } else {
                        (Rgb::ZERO, T::Exitance::default())
                    };
                    ub.push(b);
                    ux.push(x);
                }
            }
            let mut next = Vec::new();
            for (&(r, s), a) in frontier.iter().zip(&actions) {
                match a {
                    Action::Keep => {}
                    Action::SplitReceiver => next.extend(self.children(r).map(|c| (c, s))),
                    Action::SplitSource => next.extend(self.children(s).map(|c| (r, c))),
                    Action::SplitBoth => {
                        for a in self.children(r) {
                            next.extend(self.children(s).map(|b| (a, b)));
                        }
                    }
                }
            }
            frontier = next;
        }
        self.deliver_held(&held, &rb, &rx, ub, ux, &mut dh, now);
        // Push this shot's irradiance down and hand it to the leaves.
        for d in dh.iter_mut() {
            for i in 0..self.tree.nodes.len() {
                let p = self.tree.parent[i];
                if p != NONE {
                    let down = self.kernel.push(
                        &self.tree.nodes[p as usize],
                        &self.tree.nodes[i],
                        &d[p as usize],
                    );
                    d[i].add_scaled(Rgb::ONE, &down);
                }
            }
        }
        let st = self.shooting.as_mut().expect("linkless");
        for (i, (d, du)) in dh[0].iter().zip(&dh[1]).enumerate() {
            self.solve.irradiance[i].add_scaled(Rgb::ONE, d);
            st.sweep_h[i].add_scaled(Rgb::ONE, du);
            if self.tree.children[i].1 == 0 {
                st.unshot_h[i].add_scaled(Rgb::ONE, d);
            }
        }
        self.update_display();
        Ok(())
    }

    /// Delivers the shot's kept links `held` (unshot radiosity `rb`, `rx`; coarse direction `ub`, `ux`) at
    /// their gather targets into `dh`, coefficients from the cache or computed (and counted), then caches
    /// them.
    #[allow(clippy::too_many_arguments)]
    fn deliver_held(
        &mut self,
        held: &[((u32, u32), T::Link)],
        rb: &[Rgb],
        rx: &[T::Exitance],
        ub: &[Rgb],
        ux: &[T::Exitance],
        dh: &mut [Vec<T::Irradiance>; 2],
        now: u64,
    ) {
        // In chunks of links, so that one chunk's coefficients are held at a time (the order of delivery, and
        // so every sum, is the same as in one piece).
        for chunk in held.chunks(DELIVERY_CHUNK) {
            let delivered: Vec<Delivery<T::Coefficient>> = chunk
                .par_iter()
                .map(|&((r, s), ref l)| {
                    let cached = self
                        .shooting
                        .as_ref()
                        .and_then(|st| st.cache.as_ref())
                        .and_then(|c| c.get((r, s)));
                    self.targets_of(r, s, l, cached.map(|e| e.coefficients.as_slice()))
                })
                .collect();
            let view = self.view();
            for (((r, _), l), (coeffs, _, _)) in chunk.iter().zip(&delivered) {
                if l.overlap() {
                    continue;
                }
                let flux = self.kernel.emit(&view, rb, rx, *r, l);
                let flux_u = self.kernel.emit(&view, ub, ux, *r, l);
                for (t, c) in coeffs {
                    self.kernel.deliver(&mut dh[0][*t as usize], c, flux);
                    self.kernel.deliver(&mut dh[1][*t as usize], c, flux_u);
                }
            }
            let evaluations: u64 = delivered.iter().map(|d| d.1).sum();
            self.form_factors += evaluations;
            let coefficient_bytes: usize = delivered
                .iter()
                .map(|(c, _, _)| c.len() * size_of::<(u32, T::Coefficient)>())
                .sum();
            let st = self.shooting.as_mut().expect("linkless");
            st.peak_transient = st
                .peak_transient
                .max(held.len() * size_of::<T::Link>() + coefficient_bytes);
            if let Some(cache) = st.cache.as_mut() {
                for ((key, l), (c, _, changed)) in chunk.iter().zip(delivered) {
                    if changed {
                        cache.insert(*key, l.clone(), c, now);
                    } else {
                        cache.touch(*key, now);
                    }
                }
            }
        }
    }

    /// Whether node `i` is `root` or lies below it.
    fn below(&self, mut i: u32, root: u32) -> bool {
        while i != NONE {
            if i == root {
                return true;
            }
            i = self.tree.parent[i as usize];
        }
        false
    }

    /// Link `l` (receiver `r`, source `s`)'s coefficients at its gather targets, reusing `cached` ones of
    /// targets still present; with the number of coefficients computed and whether the list differs from
    /// the cached one.
    fn targets_of(
        &self,
        r: u32,
        s: u32,
        l: &T::Link,
        cached: Option<&[(u32, T::Coefficient)]>,
    ) -> Delivery<T::Coefficient> {
        let recv = &self.tree.nodes[r as usize];
        let src = &self.tree.nodes[s as usize];
        let mut targets = Vec::new();
        let at_receiver = match self.kernel.gather_at(recv, src) {
            GatherAt::Receiver => true,
            GatherAt::Leaves => {
                self.leaves_below(r, &mut targets);
                self.is_leaf(r)
            }
            GatherAt::Faces | GatherAt::Descend => {
                if recv.face().is_some() {
                    true
                } else {
                    self.view().faces_below(r, &mut targets);
                    false
                }
            }
        };
        if at_receiver {
            let c = self.kernel.coefficient(recv, src, l, true);
            let changed = cached.is_none_or(|c| c.len() != 1 || c[0].0 != r);
            return (vec![(r, c)], 0, changed);
        }
        targets.sort_unstable();
        let mut evaluations = 0;
        let mut changed = false;
        let out = targets
            .iter()
            .map(|&t| {
                let found =
                    cached.and_then(|c| c.binary_search_by_key(&t, |e| e.0).ok().map(|k| c[k].1));
                let c = found.unwrap_or_else(|| {
                    evaluations += 1;
                    changed = true;
                    self.kernel
                        .coefficient(&self.tree.nodes[t as usize], src, l, false)
                });
                (t, c)
            })
            .collect::<Vec<_>>();
        if cached.is_none_or(|c| c.len() != out.len()) {
            changed = true;
        }
        (out, evaluations, changed)
    }

    /// The solution shown: B = E + ρ H at every leaf from all irradiance received, pulled.
    fn update_display(&mut self) {
        let (mut b, mut x): (Vec<Rgb>, Vec<T::Exitance>) = (0..self.tree.nodes.len())
            .map(|i| {
                if self.tree.children[i].1 == 0 {
                    self.kernel
                        .reflect(&self.tree.nodes[i], &self.solve.irradiance[i], true)
                } else {
                    (Rgb::ZERO, T::Exitance::default())
                }
            })
            .unzip();
        self.pull(&mut b, &mut x);
        self.solve.radiosity = b;
        self.solve.exitance = x;
    }

    /// After a sweep: the coarse correction along u (the lit leaves' uniform response, `support`, `ub`)
    /// with M u delivered by the sweep's own links, and the convergence estimate.
    fn correct_sweep(&mut self, support: &[bool], ub: &[Rgb]) {
        let st = self.shooting.as_ref().expect("linkless");
        // Per channel: Σ A u, Σ A M u, Σ A R (unshot now), over the leaves.
        let (mut u, mut mu, mut rest) = (Rgb::ZERO, Rgb::ZERO, Rgb::ZERO);
        for (i, ui) in ub.iter().enumerate() {
            if self.tree.children[i].1 != 0 {
                continue;
            }
            let node = &self.tree.nodes[i];
            let a = node.area();
            u += a * *ui;
            mu += a * self.kernel.reflect(node, &st.sweep_h[i], false).0;
            rest += a * leaf_radiosity(&self.kernel, node, st.unshot_e[i], &st.unshot_h[i]).0;
        }
        let mut share = Rgb::ZERO;
        let mut c = Rgb::ZERO;
        for k in 0..3 {
            if u[k] > 0.0 {
                share[k] = mu[k] / u[k];
            }
            let d = u[k] - mu[k];
            if d > 1e-12 * u[k].max(rest[k].abs()) && d.is_finite() {
                c[k] = rest[k] / d;
            }
        }
        let st = self.shooting.as_mut().expect("linkless");
        st.last_share = share;
        // Only under an operator the sweep did not change: M u from links made while elements were being
        // split holds deliveries to elements since split, and c (about 1/(1 − ρ)) would magnify them.
        if st.split_in_sweep {
            c = Rgb::ZERO;
        }
        if c != Rgb::ZERO {
            st.corrections += 1;
            for (i, &lit) in support.iter().enumerate() {
                let w = st.sweep_h[i];
                self.solve.irradiance[i].add_scaled(c, &w);
                if self.tree.children[i].1 == 0 {
                    st.unshot_h[i].add_scaled(c, &w);
                    if lit {
                        st.unshot_e[i].1 -= c;
                    }
                }
            }
        }
        // The remaining error: the unshot radiosity, amplified by the bounces still to come.
        let (mut r, mut b) = (0.0, 0.0);
        for i in 0..self.tree.nodes.len() {
            if self.tree.children[i].1 != 0 {
                continue;
            }
            let node = &self.tree.nodes[i];
            let a = node.area();
            r += a * leaf_radiosity(&self.kernel, node, st.unshot_e[i], &st.unshot_h[i])
                .0
                .abs()
                .element_sum();
            let (bi, _) = self.kernel.reflect(node, &self.solve.irradiance[i], true);
            b += a * bi.abs().element_sum();
        }
        let q = share.max_element().clamp(0.0, 0.9999);
        let estimate = if b > 0.0 { r / b / (1.0 - q) } else { 0.0 };
        self.solve.residual = Some(estimate);
        self.solve.converged = estimate < self.params.tolerance;
    }
}

//! Progressive refinement by shooting (Cohen, Chen, Wallace & Greenberg 1988, "A progressive refinement
//! approach to fast radiosity image generation"; Southwell relaxation of B = E + ρ F B).
//!
//! Each patch p keeps its unshot radiosity ΔB_p. A shot takes the patch j with the largest unshot power
//! A_j |ΔB_j| and distributes it: every receiving element e gathers (Cohen et al. 1988, with the form factor
//! taken from the receiver's side as in Wallace, Elmquist & Haines 1989)
//!
//! ΔB_e = ρ_e ΔB_j F_{e→j} / o_e,   B_e += ΔB_e,   ΔB_{p(e)} += ΔB_e o_e A_e / (o A)_{p(e)},   then ΔB_j = 0,
//!
//! (o_e the element's open share and (o A)_p the patch's open area, [`crate::substructuring`]; 1 and A where
//! nothing is sealed)
//! where F_{e→j} is the mean over m × m receiver points of the exact unoccluded point-to-polygon factor toward
//! the shooting patch, times a visibility fraction from rays between the two
//! ([`radlab_kernels::form_factor::polygon_polygon`], the same kernel the matrix method uses). The ray count
//! depends on the shooter only: `visibility` toward patches that emit (direct light casts the sharp shadows),
//! `indirect_visibility` toward the rest. F is evaluated
//! from the receiver's points, so the answer is exact for unoccluded point receivers and the n² matrix is never
//! stored: one column of it is recomputed per shot, O(n) memory. The random stream of F_{e→j} is a function of
//! (seed, e, j) only, so every shot of j gives e the same factor: progressive radiosity converges to the
//! solution of one fixed linear system, whatever the order of shots or the thread count.
//!
//! **Overshooting** (Feda & Purgathofer 1992; Gortler, Cohen & Slusallek 1993 analyse it as over-relaxation
//! of Southwell's iteration). At high reflectance almost all of the work of plain shooting goes into one slow
//! mode: every patch receives back, round after round, a fraction ρ of what the scene shot, so the unshot power
//! falls only by a factor ρ per round and about N ln(1/ε)/(1 − ρ) shots are needed. With overshooting a patch
//! light has reached sends its unshot radiosity plus an estimate of what it will still receive,
//!
//! s_j = ΔB_j + ρ_j B_amb,   B_amb = R · Σ_{p lit} A_p ΔB_p / Σ_{p lit} A_p,   R = 1 / (1 − ĝ),
//!
//! the ambient radiosity of Cohen et al. (1988) over the patches light has reached, with the interreflection
//! factor R taken from ĝ, the measured fraction of the power shot so far that came back as unshot power
//! (Σ|returned| / Σ|shot| per channel, capped at the largest reflectance). In a closed furnace of reflectance ρ,
//! ĝ = ρ and the first shot of every patch already sends its exact radiosity E/(1 − ρ); where light escapes ĝ
//! is smaller than the area-mean reflectance Cohen et al. use, so open scenes are not over-driven. The shot is
//! booked as any other, S_j += s_j, ΔB_j −= s_j and every receiver gains ρ_e F_{e→j} s_j, so the invariant
//! B_p = S_p + ΔB_p and the relation B_e = E_e + ρ_e Σ_j F_{e→j} S_j hold after every shot, ΔB_j may go
//! negative (a later shot of j sends the correction), and the unshot radiosity is exactly the residual
//! E + ρ F S − S of the linear system: shooting stops at the same fixed point as plain shooting, and the
//! stopping rule on Σ_p A_p |ΔB_p| bounds the error in the same way (in a closed scene of reflectance ρ, a
//! relative error of the total radiosity power of at most ρ times the unshot fraction, whatever the signs).
//! The shooter is the patch with the largest power A_j |s_j| it would send. A patch no light has reached
//! (ΔB = 0, never received) never overshoots, so no light enters a closed unlit interior.
//!
//! Power is compared across channels by each channel's share of that channel's emitted power, Σ_c A |ΔB_c| /
//! Φ_c, so a dim channel is not ignored; the unshot fraction is the worst channel's Σ_p A_p |ΔB_p,c| / Φ_c.

use radlab_kernels::form_factor::{
    VisibilitySampling, polygon_polygon_unoccluded, visibility_fraction,
};
use radlab_scene::{Rgb, Scene, facing_away};
use radlab_visibility::Accel;
use rayon::prelude::*;

use crate::substructuring::{Element, Mesh, Patch};

/// How form factors are evaluated.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Kernel {
    /// m: m × m receiver points.
    pub quadrature: u32,
    /// Visibility estimate toward emitting patches.
    pub visibility: VisibilitySampling,
    /// Visibility estimate toward patches that do not emit.
    pub indirect_visibility: VisibilitySampling,
    /// Seed of every random stream.
    pub seed: u64,
}

/// Counters of form-factor work.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Work {
    /// Form factors evaluated (a culled pair does not count).
    pub form_factors: u64,
    /// Rays requested for visibility.
    pub rays: u64,
}

impl std::ops::AddAssign for Work {
    fn add_assign(&mut self, o: Self) {
        self.form_factors += o.form_factors;
        self.rays += o.rays;
    }
}

/// Receivers below this count are gathered on the calling thread (rayon's overhead would dominate); so are all
/// receivers when rayon has one thread.
const PARALLEL_MIN_RECEIVERS: usize = 256;

/// Fewest leaves in a run of a shot's gather (see [`run_len`]).
const MIN_RUN_LEN: usize = 8;

/// Length of the next run of a shot's gather, `remaining` leaves left, on `threads` threads: guided
/// self-scheduling (Polychronopoulos & Kuck 1987), a share 1/(2 · threads) of what is left but at least
/// [`MIN_RUN_LEN`]. Threads take runs in order as they run out of work, so the first runs are long (few
/// hand-outs) and the last ones short (a thread waits at most one short run at the end of the shot). Measured
/// at 2 threads on Cornell's defaults against runs of 16 leaves handed out by rayon's recursive halving: the
/// 2-thread solve 3-4 % faster; rayon's own adaptive splitting of the leaves had left one thread idle about
/// 120 µs at the end of each shot.
fn run_len(remaining: usize, threads: usize) -> usize {
    (remaining / (2 * threads)).max(MIN_RUN_LEN)
}

/// F_{e→j}: form factor from element `e` (index `ei`) toward patch `j` (index `pj`), with the work done.
/// Zero, without work, for pairs on one face and pairs that face away from each other.
pub(crate) fn element_patch_factor(
    scene: &Scene,
    accel: &Accel,
    kernel: &Kernel,
    e: &Element,
    ei: u32,
    j: &Patch,
    pj: u32,
) -> (f64, Work) {
    if e.face == j.face {
        return (0.0, Work::default());
    }
    let ne = scene.faces[e.face as usize].normal;
    let nj = scene.faces[j.face as usize].normal;
    // Back-face culling: point_polygon would give 0 at every receiver point.
    if facing_away(
        &e.polygon,
        e.polygon.vertices()[0],
        ne,
        &j.polygon,
        j.polygon.vertices()[0],
        nj,
    ) {
        return (0.0, Work::default());
    }
    let f = polygon_polygon_unoccluded(&e.polygon, &j.polygon, kernel.quadrature);
    let mut work = Work {
        form_factors: 1,
        rays: 0,
    };
    if f.is_nan() || f <= 0.0 {
        return (0.0, work);
    }
    let how = if j.emits {
        kernel.visibility
    } else {
        kernel.indirect_visibility
    };
    let v = match how {
        VisibilitySampling::Unoccluded => 1.0,
        how => {
            work.rays = how.rays() as u64;
            visibility_fraction(
                accel,
                &e.polygon,
                e.face as usize,
                &j.polygon,
                j.face as usize,
                how,
                kernel.seed,
                pair_stream(ei, pj),
            )
        }
    };
    (f * v, work)
}

/// The random stream of the pair (element, patch).
pub(crate) fn pair_stream(element: u32, patch: u32) -> u64 {
    (u64::from(element) << 32) | u64::from(patch)
}

/// Per-channel weights 1/Φ_c (zero for channels that emit nothing).
pub(crate) fn channel_weights(emitted: Rgb) -> Rgb {
    Rgb::from_array(
        emitted
            .to_array()
            .map(|p| if p > 0.0 { 1.0 / p } else { 0.0 }),
    )
}

/// The overshooting state: power shot and power returned so far, for the measured interreflection factor.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Interreflection {
    /// Σ over shots of A_j |s_j| per channel.
    pub shot: Rgb,
    /// Σ over shots of |Σ_e A_e ΔB_e| per channel: the power that came back as unshot power.
    pub returned: Rgb,
    /// Largest reflectance in the scene per channel: no interreflection ratio can exceed it.
    pub cap: Rgb,
}

impl Interreflection {
    pub fn new(scene: &Scene) -> Self {
        let cap = (0..scene.face_count())
            .map(|f| scene.reflectance(f))
            .fold(Rgb::ZERO, Rgb::max);
        Self {
            shot: Rgb::ZERO,
            returned: Rgb::ZERO,
            cap,
        }
    }

    /// Books one shot that sent `sent` (A_j s_j per channel) and brought back `returned` (Σ_e A_e ΔB_e).
    pub fn record(&mut self, sent: Rgb, returned: Rgb) {
        self.shot += sent.abs();
        self.returned += returned.abs();
    }

    /// R = 1 / (1 − ĝ) per channel, ĝ the measured return ratio capped at the largest reflectance (1 before the
    /// first shot).
    pub fn factor(&self) -> Rgb {
        let g = Rgb::from_array(std::array::from_fn(|c| {
            if self.shot[c] > 0.0 {
                (self.returned[c] / self.shot[c]).min(self.cap[c])
            } else {
                0.0
            }
        }));
        Rgb::ONE / (Rgb::ONE - g)
    }
}

/// The ambient radiosity over the patches light has reached, R · Σ_lit A ΔB / Σ_lit A (signed; zero if none).
pub(crate) fn lit_ambient(patches: &[Patch], interreflection: Rgb) -> Rgb {
    let (mut area, mut unshot) = (0.0, Rgb::ZERO);
    for p in patches.iter().filter(|p| p.lit) {
        area += p.open_area;
        unshot += p.open_area * p.unshot;
    }
    if area > 0.0 {
        interreflection * unshot / area
    } else {
        Rgb::ZERO
    }
}

/// The radiosity patch `p` sends when shot: ΔB_p, plus ρ_p `ambient` if light has reached it.
fn amount(scene: &Scene, p: &Patch, ambient: Option<Rgb>) -> Rgb {
    match ambient {
        Some(a) if p.lit => p.unshot + scene.reflectance(p.face as usize) * a,
        _ => p.unshot,
    }
}

/// Relative difference below which two shooters' powers tie ([`select_shooter`]).
const TIE: f64 = 1e-9;

/// The patch that would send the largest power Σ_c w_c A |s_c| (lowest index on ties) and what it sends, if
/// any would send anything. `ambient` is the overshooting estimate B_amb, `None` for plain shooting. Powers
/// within a relative [`TIE`] of each other tie: equal patches (a lamp's elements) differ in area by rounding,
/// which differs with the scene's scale, and the first shot must not depend on it.
pub(crate) fn select_shooter(
    scene: &Scene,
    patches: &[Patch],
    weights: Rgb,
    ambient: Option<Rgb>,
) -> Option<(usize, Rgb)> {
    let mut best = None;
    let mut best_power = 0.0;
    for (i, p) in patches.iter().enumerate() {
        let s = amount(scene, p, ambient);
        let power = p.open_area * s.abs().dot(weights);
        if power > best_power * (1.0 + TIE) {
            best_power = power;
            best = Some((i, s));
        }
    }
    best
}

/// Unshot power per channel, Σ_p A_p |ΔB_p|.
pub(crate) fn unshot_power(patches: &[Patch]) -> Rgb {
    patches.iter().map(|p| p.open_area * p.unshot.abs()).sum()
}

/// Unshot power as a fraction of emitted power, worst channel (0 when nothing is emitted).
pub(crate) fn unshot_fraction(patches: &[Patch], weights: Rgb) -> f64 {
    (unshot_power(patches) * weights).max_element()
}

/// A run of consecutive leaves on one rayon task: the leaves, and the radiosities of the elements they span
/// (`first ..`, interior elements between leaves included) and their factors, borrowed apart from every
/// other run's.
struct Run<'a> {
    leaves: &'a [u32],
    first: u32,
    radiosity: &'a mut [Rgb],
    factors: &'a mut [f64],
}

/// Cuts `leaves` (ascending element indices) into runs, each `next_len(leaves left)` long, each with the
/// disjoint part of `radiosity` (indexed by element) that its elements span and its part of `factors` (indexed
/// by leaf position).
fn runs<'a>(
    mut leaves_left: &'a [u32],
    mut radiosity: &'a mut [Rgb],
    mut factors_left: &'a mut [f64],
    next_len: impl Fn(usize) -> usize,
) -> Vec<Run<'a>> {
    let mut out = Vec::new();
    let mut offset = 0;
    while !leaves_left.is_empty() {
        let len = next_len(leaves_left.len()).clamp(1, leaves_left.len());
        let (leaves, rest) = leaves_left.split_at(len);
        leaves_left = rest;
        let (factors, rest) = std::mem::take(&mut factors_left).split_at_mut(len);
        factors_left = rest;
        let (Some(&first), Some(&last)) = (leaves.first(), leaves.last()) else {
            continue;
        };
        let rest = std::mem::take(&mut radiosity);
        let (_, rest) = rest.split_at_mut(first as usize - offset);
        let (mine, rest) = rest.split_at_mut((last - first) as usize + 1);
        radiosity = rest;
        offset = last as usize + 1;
        out.push(Run {
            leaves,
            first,
            radiosity: mine,
            factors,
        });
    }
    out
}

/// ΔB_e = ρ_e F s / o_e: the radiosity element `el` gains over its open part from a shot of `amount` with
/// factor F = `f` (F was sampled from all of the element, its sealed points included).
fn gain(scene: &Scene, el: &Element, amount: Rgb, f: f64) -> Rgb {
    scene.reflectance(el.face as usize) * amount * f / el.open
}

/// Shoots radiosity `amount` from patch `j` to every leaf element (`amount` = its unshot radiosity for plain
/// shooting), books it on patch j and adds every leaf's gain to its radiosity; returns the work. The leaves'
/// factors are left in `factors` for [`book`], which must follow before anything else reads the patches.
///
/// Each leaf evaluates its factor and adds its own gain on a rayon task (each element is written by exactly one
/// task, and only its factor goes back: 8 bytes a leaf crossing between cores).
pub(crate) fn shoot(
    scene: &Scene,
    accel: &Accel,
    kernel: &Kernel,
    mesh: &mut Mesh,
    j: usize,
    amount: Rgb,
    factors: &mut Vec<f64>,
) -> Work {
    let shooter = mesh.patches[j];
    mesh.patches[j].shot += amount;
    mesh.patches[j].unshot -= amount;
    let elements = &mesh.elements;
    let gather = |run: Run| {
        let mut work = Work::default();
        for (&e, f_out) in run.leaves.iter().zip(run.factors) {
            let el = &elements[e as usize];
            if scene.reflectance(el.face as usize) == Rgb::ZERO {
                *f_out = 0.0;
                continue;
            }
            let (f, w) = element_patch_factor(scene, accel, kernel, el, e, &shooter, j as u32);
            work += w;
            *f_out = f;
            if f > 0.0 {
                run.radiosity[(e - run.first) as usize] += gain(scene, el, amount, f);
            }
        }
        work
    };
    factors.clear();
    factors.resize(mesh.leaves.len(), 0.0);
    let threads = rayon::current_num_threads();
    if mesh.leaves.len() < PARALLEL_MIN_RECEIVERS || threads == 1 {
        runs(&mesh.leaves, &mut mesh.radiosity, factors, |n| n)
            .into_iter()
            .map(gather)
            .fold(Work::default(), |mut a, b| {
                a += b;
                a
            })
    } else {
        // par_bridge hands the runs out in order, one at a time, to whichever thread asks.
        runs(&mesh.leaves, &mut mesh.radiosity, factors, |n| {
            run_len(n, threads)
        })
        .into_iter()
        .par_bridge()
        .map(gather)
        .reduce(Work::default, |mut a, b| {
            a += b;
            a
        })
    }
}

/// The rest of a shot of `amount` ([`shoot`]): adds each leaf's gain, from its factor in `factors`, to its
/// patch's unshot radiosity, in leaf order on one thread (so the sums are the same for any thread count), and
/// returns the power that came back as unshot power, Σ_e A_e ΔB_e.
pub(crate) fn book(
    scene: &Scene,
    patches: &mut [Patch],
    elements: &[Element],
    leaves: &[u32],
    factors: &[f64],
    amount: Rgb,
) -> Rgb {
    let mut returned = Rgb::ZERO;
    for (&e, &f) in leaves.iter().zip(factors) {
        let el = &elements[e as usize];
        // A sealed element (no open area) gains nothing its patch sends on.
        if f > 0.0 && el.open_area() > 0.0 {
            let gain = gain(scene, el, amount, f);
            returned += el.open_area() * gain;
            let patch = &mut patches[el.patch as usize];
            patch.unshot += gain * (el.open_area() / patch.open_area);
            patch.lit |= gain != Rgb::ZERO;
        }
    }
    returned
}

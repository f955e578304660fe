//! Progressive refinement by shooting (Cohen, Chen, Wallace & Greenberg 1988, "A progressive refinement
//! approach to fast radiosity image generation"; Southwell relaxation of B = E + ρ F B).
//!
//! Each patch p keeps its unshot radiosity ΔB_p. A shot takes the patch j with the largest unshot power
//! A_j |ΔB_j| and distributes it: every receiving element e gathers (Cohen et al. 1988, with the form factor
//! taken from the receiver's side as in Wallace, Elmquist & Haines 1989)
//!
//! ΔB_e = ρ_e ΔB_j F_{e→j},   B_e += ΔB_e,   ΔB_{p(e)} += ΔB_e A_e / A_{p(e)},   then ΔB_j = 0,
//!
//! where F_{e→j} is the mean over m × m receiver points of the exact unoccluded point-to-polygon factor toward
//! the shooting patch, times a visibility fraction from rays between the two
//! ([`radlab_scene::form_factor::polygon_polygon`], the same kernel the matrix method uses). The ray count
//! depends on the shooter only: `visibility` toward patches that emit (direct light casts the sharp shadows),
//! `indirect_visibility` toward the rest. F is evaluated
//! from the receiver's points, so the answer is exact for unoccluded point receivers and the n² matrix is never
//! stored: one column of it is recomputed per shot, O(n) memory. The random stream of F_{e→j} is a function of
//! (seed, e, j) only, so every shot of j gives e the same factor: progressive radiosity converges to the
//! solution of one fixed linear system, whatever the order of shots or the thread count.
//!
//! Power is compared across channels by each channel's share of that channel's emitted power, Σ_c A |ΔB_c| /
//! Φ_c, so a dim channel is not ignored; the unshot fraction is the worst channel's Σ_p A_p |ΔB_p,c| / Φ_c.

use radlab_scene::form_factor::{
    VisibilitySampling, polygon_polygon_unoccluded, visibility_fraction,
};
use radlab_scene::{Accel, Polygon, Rgb, Scene};
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

/// Receivers below this count are gathered on the calling thread (rayon's overhead would dominate).
const PARALLEL_MIN_RECEIVERS: usize = 256;

/// Whether every vertex of `poly` lies on or behind the plane through `origin` with normal `n`.
fn behind(poly: &Polygon, origin: glam::DVec3, n: glam::DVec3) -> bool {
    poly.vertices().iter().all(|&v| (v - origin).dot(n) <= 0.0)
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
    if behind(&j.polygon, e.polygon.vertices()[0], ne)
        || behind(&e.polygon, j.polygon.vertices()[0], nj)
    {
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

/// The patch with the largest unshot power Σ_c w_c A |ΔB_c| (lowest index on ties), if any is nonzero.
pub(crate) fn select_shooter(patches: &[Patch], weights: Rgb) -> Option<usize> {
    let mut best = None;
    let mut best_power = 0.0;
    for (i, p) in patches.iter().enumerate() {
        let power = p.area * p.unshot.abs().dot(weights);
        if power > best_power {
            best_power = power;
            best = Some(i);
        }
    }
    best
}

/// Unshot power per channel, Σ_p A_p |ΔB_p|.
pub(crate) fn unshot_power(patches: &[Patch]) -> Rgb {
    patches.iter().map(|p| p.area * p.unshot.abs()).sum()
}

/// Unshot power as a fraction of emitted power, worst channel (0 when nothing is emitted).
pub(crate) fn unshot_fraction(patches: &[Patch], weights: Rgb) -> f64 {
    (unshot_power(patches) * weights).max_element()
}

/// Shoots patch `j`'s unshot radiosity to every leaf element. `factors` is scratch space.
pub(crate) fn shoot(
    scene: &Scene,
    accel: &Accel,
    kernel: &Kernel,
    mesh: &mut Mesh,
    j: usize,
    factors: &mut Vec<(f64, Work)>,
) -> Work {
    let shooter = mesh.patches[j];
    let delta = shooter.unshot;
    mesh.patches[j].shot += delta;
    mesh.patches[j].unshot = Rgb::ZERO;
    let elements = &mesh.elements;
    let gather = |&e: &u32| {
        let el = &elements[e as usize];
        if scene.reflectance(el.face as usize) == Rgb::ZERO {
            return (0.0, Work::default());
        }
        element_patch_factor(scene, accel, kernel, el, e, &shooter, j as u32)
    };
    factors.clear();
    if mesh.leaves.len() < PARALLEL_MIN_RECEIVERS {
        factors.extend(mesh.leaves.iter().map(gather));
    } else {
        mesh.leaves
            .par_iter()
            .with_min_len(64)
            .map(gather)
            .collect_into_vec(factors);
    }
    // Apply in leaf order on one thread: sums are the same for any thread count.
    let mut work = Work::default();
    for (&e, &(f, w)) in mesh.leaves.iter().zip(factors.iter()) {
        work += w;
        if f > 0.0 {
            let el = &mut mesh.elements[e as usize];
            let gain = scene.reflectance(el.face as usize) * delta * f;
            el.radiosity += gain;
            let patch = &mut mesh.patches[el.patch as usize];
            patch.unshot += gain * (el.area / patch.area);
        }
    }
    work
}

//! A block standing on the floor of the closed unit room ([`crate::room`]): five outward faces and no
//! bottom, as the Cornell box's blocks are modelled, so the floor under it sees only the backs of the
//! block's faces. Floor points under the block receive nothing (every ray leaving them meets a back, which
//! absorbs), so their exact radiosity is 0; points beside it are lit and shadowed by it. Shared by the
//! tests of the methods that must answer 0 there (wavelet radiosity's open shares, face clusters' sealed
//! points).

use glam::{DVec3, dvec3};
use radlab_scene::{FaceId, Rgb, Scene};

use crate::{box_sides, material, room};

/// The block's footprint on the floor, [lo, hi]² (m).
pub const BLOCK_LO: f64 = 0.3;
/// See [`BLOCK_LO`].
pub const BLOCK_HI: f64 = 0.7;
/// The block's height (m).
pub const BLOCK_HEIGHT: f64 = 0.3;

/// The unit room with the block on its floor (reflectance 0.6, no bottom face).
pub fn block_on_floor() -> Scene {
    room("a block on the floor", &|b| {
        let m = material(b, "block", 0.6, 0.0);
        let lo = dvec3(BLOCK_LO, BLOCK_LO, 0.0);
        let hi = dvec3(BLOCK_HI, BLOCK_HI, BLOCK_HEIGHT);
        // Side 0 is the bottom (z = lo): left out.
        for (o, u, v) in box_sides(lo, hi, true).into_iter().skip(1) {
            b.add_polygon_points(&[o, o + u, o + u + v, o + v], m, "block")
                .expect("block face");
        }
    })
}

/// The floor face (z = 0, facing up) holding `(x, y)`, and the point on it.
fn on_floor(scene: &Scene, x: f64, y: f64) -> (FaceId, DVec3) {
    let p = dvec3(x, y, 0.0);
    let face = (0..scene.face_count())
        .filter(|&f| {
            let c = scene.faces[f].centroid;
            scene.faces[f].normal.z > 0.9 && c.z.abs() < 1e-9
        })
        .min_by(|&a, &b| {
            let d = |f: FaceId| (scene.faces[f].centroid - p).truncate().abs().max_element();
            d(a).total_cmp(&d(b))
        })
        .expect("the room has a floor");
    (face, p)
}

/// Floor points under the block (a 4 × 4 grid over its footprint, inset by a tenth of it): exact answer 0.
pub fn sealed_points(scene: &Scene) -> Vec<(FaceId, DVec3)> {
    let w = BLOCK_HI - BLOCK_LO;
    let mut out = Vec::new();
    for j in 0..4 {
        for i in 0..4 {
            let s = |k: usize| BLOCK_LO + w * (0.1 + 0.8 * k as f64 / 3.0);
            out.push(on_floor(scene, s(i), s(j)));
        }
    }
    out
}

/// Floor points beside the block, a tenth of a metre from each side (three per side): lit, and in the
/// block's penumbra from the ceiling light.
pub fn beside_points(scene: &Scene) -> Vec<(FaceId, DVec3)> {
    let (a, b) = (BLOCK_LO - 0.1, BLOCK_HI + 0.1);
    let mut out = Vec::new();
    for t in [0.35, 0.5, 0.65] {
        out.push(on_floor(scene, a, t));
        out.push(on_floor(scene, b, t));
        out.push(on_floor(scene, t, a));
        out.push(on_floor(scene, t, b));
    }
    out
}

/// An independent reference at points of a scene's faces: for each, the mean radiosity and its standard error
/// (e.g. the path tracer's `estimate_points`, which testkit cannot call: it is a dependency of the path
/// tracer's tests).
pub type Reference<'a> = dyn Fn(&Scene, &[(FaceId, DVec3)]) -> Vec<(Rgb, Rgb)> + 'a;

/// [`block_on_floor`] with its reference beside the block: what a method's answers there are judged against.
pub struct SealedCase {
    /// The scene.
    pub scene: Scene,
    sealed: Vec<(FaceId, DVec3)>,
    beside: Vec<(FaceId, DVec3)>,
    reference: Vec<(Rgb, Rgb)>,
}

impl SealedCase {
    /// The case, with `reference` evaluated beside the block. Panics if the reference lights a sealed point
    /// (a path tracer must answer exactly 0 there, with zero variance: every ray meets a back).
    pub fn new(reference: &Reference) -> Self {
        let scene = block_on_floor();
        let (sealed, beside) = (sealed_points(&scene), beside_points(&scene));
        for (mean, _) in reference(&scene, &sealed) {
            assert_eq!(
                mean.max_element(),
                0.0,
                "the reference lights a sealed point"
            );
        }
        let reference = reference(&scene, &beside);
        Self {
            scene,
            sealed,
            beside,
            reference,
        }
    }

    /// The failures of a method's `answer` (radiosity at a point of a face): a sealed point answering more
    /// than 1e-3 of the mean radiosity beside the block; and, when the answer `resolves_shadows` (a final
    /// gather), a relative L1 difference beside the block above twice the reference's summed standard
    /// errors (a difference that is the reference's noise alone averages E|N(0, σ)| ≈ 0.8 σ a point).
    /// Prints the figures under `label`.
    pub fn judge(
        &self,
        label: &str,
        answer: &dyn Fn(FaceId, DVec3) -> Rgb,
        resolves_shadows: bool,
    ) -> Vec<String> {
        let lit = self
            .reference
            .iter()
            .map(|(m, _)| m.element_sum())
            .sum::<f64>()
            / (3.0 * self.reference.len() as f64);
        let worst_sealed = self
            .sealed
            .iter()
            .map(|&(f, p)| answer(f, p).max_element())
            .fold(0.0, f64::max);
        let (mut diff, mut sum, mut se) = (0.0, 0.0, 0.0);
        for (&(f, p), (mean, std_error)) in self.beside.iter().zip(&self.reference) {
            diff += (answer(f, p) - *mean).abs().element_sum();
            sum += mean.element_sum();
            se += std_error.element_sum();
        }
        eprintln!(
            "{label}: worst sealed point {worst_sealed:.4} (beside mean {lit:.4}); beside: relative L1 \
             {:.4}, reference standard error {:.5}",
            diff / sum,
            se / sum
        );
        let mut failures = Vec::new();
        if resolves_shadows && diff > 2.0 * se {
            failures.push(format!("{label} beside the block: L1 {diff} > 2 × {se}"));
        }
        if worst_sealed > 1e-3 * lit {
            failures.push(format!("{label}: a sealed point answers {worst_sealed}"));
        }
        failures
    }
}

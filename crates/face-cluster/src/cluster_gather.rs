//! Final gather over the face-cluster tree: the radiosity at a query point x (normal n) recomputed by one more
//! application of the radiosity equation (Lischinski, Tampieri & Greenberg 1993; Cohen & Wallace 1993,
//! ch. 9),
//!
//!   B(x) = E(x) + ρ(x) Σ_j F_{x→j} V_xj B_j,
//!
//! where the sum over the k input faces j is taken through the tree as Barnes & Hut (1986) take a sum of
//! forces: a node N whose bounding sphere (radius R, centre at distance r from x) satisfies R < θ r, with θ
//! the opening ([`DEFAULT_OPENING`]), is gathered whole by the point transfer of its power vector
//! p_N = Σ_{i∈N} B_i A_i n_i (Willmott, Heckbert & Garland 1999, eq. 4), the irradiance at x being
//!
//!   V max(0, a Σ B_i A_i + b p_N·d) max(0, n·(−d)) / (π r_c²),
//!
//! with d the unit direction from N's area-weighted centroid to x at distance r_c, and a + b c the
//! least-squares line of max(0, c) over the spread of N's faces' cosines toward x, from its normal moments
//! within the range its normal cone allows (exactly c when every face of N faces x:
//! [`crate::clamped_irradiance::CosineFit::of_node`]). Other nodes are opened; a face is gathered
//! exactly, by its point-to-polygon factor (Baum, Rushmeier & Winget 1989, eq. 3) and the shared final
//! gather's visibility rays ([`radlab_answer::final_gather::GatherSettings::visible_share`]: 16 jittered rays
//! toward an emitter, one toward another face's centroid). Nodes holding an emitter are always opened, so
//! direct light is the flat gather's, exact up to its visibility estimate; nodes wholly behind x's plane, or
//! whose faces all turn away from x, are skipped. A far node's visibility is one ray from x to one of its
//! sample points y_s, drawn from the query's random stream with probability proportional to the point
//! kernel max(0, n_s·(x − y_s)) max(0, n·(y_s − x)) / |x − y_s|⁴ (any of them where every weight is 0), so
//! its expectation is the kernel-weighted visibility Σ w_s V_s / Σ w_s. On rough ground the parts of a node
//! turned toward x are both the better seen and the brighter in x's kernel; a sample drawn evenly among those
//! facing x gave the mean visibility without that covariance, and the tree gather read low (measured on the
//! 10⁵-face terrain at opening 0.1, ε = 1e-5: signed −0.040%, L1 0.070%; kernel-weighted −0.015%, 0.059%).
//! A query point beside a gap (its seal test open only after a closed ray; the caller says so) opens every
//! node and measures every face's visible share with the 16 kernel-weighted rays: light reaches it through a
//! slit, which one ray per node or face finds or misses whole (radlab-answer's final gather does the same).
//! At θ = 0 every node is opened and the gather is the flat one over every face; the error of a far node's point transfer is of order θ², and the number of
//! nodes a query opens grows as log k for a surface seen from a point on it, so the cost per query is
//! sub-linear in k where the flat gather's is linear.
//!
//! The face values B_j are the solution's constant answers (E + ρ max(0, n·e) from the deepest cluster
//! above face j, or the patch leaves where the refinement split it), computed with the power vectors of
//! every node in one pass over the faces after each step: the one part linear in k, as output is. A near face
//! is gathered with its mean value (gathering near faces as 4 × 4 sub-polygons with their Gouraud values was
//! tried and moved the error on the 10⁵-face bumpy sphere and terrain by less than 0.002%). At θ = 0,
//! [`NearField::SubPolygons`] hands the same values to the shared final gather instead, whose near field
//! re-gathers each near face's sub-polygons at their own points (see there), with the far part of those
//! re-gathers from this tree gather ([`TreeFarField`]).
//!
//! Near values (`near_values = "regathered"`, radlab-answer's parameter; face clusters' default). A face value
//! carries the solution's error: the light a cluster's irradiance vector hands a face by its orientation alone,
//! or a link's one visibility fraction. Far from the query point that error is damped by the gather's small
//! factors, but a face the gather reaches one by one near the point passes it on whole: the floor under a
//! scanned dragon or a ball, which sees mostly their undersides, answered 27% and 22% dark where those faces
//! held too little of the floor's light (14% and 12% with near values). So [`ClusterGather::with_near_values`]
//! gathers a non-emitting face or patch leaf it reaches one by one, seen from the point with a factor of at
//! least [`radlab_answer::final_gather::NEAR_VALUES_MIN_FACTOR`], with its value re-gathered over the tree at
//! its centroid from the gather's values, E + ρ Σ F V B (its own direct light and visibility, one more
//! bounce), computed once, at its first use, and kept: two bounces near the point and one far from it, a local
//! form of the Jacobi iteration below, for a gather per face some query comes near rather than per face of
//! the scene (over gathered values, below, one more gather of those). The re-gather reads a split
//! emitter whole, with kernel-weighted rays. A centroid the seal test finds sealed, or open only after a
//! closed ray (beside a gap, where a gather measures every source with 16 rays), keeps the solution's value,
//! and so does a patch leaf with a sealed part (its value is its open part's mean).
//!
//! With [`GatherValues::Gathered`] the values themselves come from a gather first: each face's value (and each
//! patch leaf's) is this same gather over the solution's values at its centroid, at a coarser opening, and the
//! final gather reads those, so a point's answer is two more applications of the radiosity equation, one
//! Jacobi iteration of it (Cohen & Wallace 1993, ch. 5) before the final gather, instead of one. The error a
//! link-based face value carries (its direct light from links' visibility fractions, its indirect light from
//! the solution) then reaches a point only after being multiplied by ρ F once more, while each value's
//! direct light becomes the gather's, exact up to its visibility rays. The values' gather is k more queries
//! (and one per patch leaf), linear in k as the values' pass is, once per solution. It gathers an emitter
//! whole, with its 16 jittered rays (the refinement may have split it into hundreds of patches, each of
//! which would cost 16 rays at each of the k queries), and so weights each ray by the point kernel it stands
//! for ([`radlab_answer::final_gather::GatherSettings::kernel_weighted_share`]): F V then estimates the light
//! that gets through, where the share of the light's area that is seen, times F, undercounts a large light
//! whose fainter far side is hidden first (faces in valleys near the 10⁵-face terrain's border, seeing its
//! 4 × 4 light past a ridge, took about 2% too little, 0.7% elsewhere, and passed it on to the answers).

use std::collections::HashMap;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicU64, Ordering};

use glam::DVec3;
use radlab_answer::NearValues;
use radlab_answer::final_gather::{FarField, GatherSettings, NEAR_VALUES_MIN_FACTOR};
use radlab_answer::gouraud::ElementValue;
use radlab_kernels::form_factor::point_polygon;
use radlab_kernels::open_fraction::{POINT_SEAL_RAYS, point_key, point_sealed};
use radlab_scene::sampling::{self, mix64};
use radlab_scene::{FaceId, Rgb, Scene};
use radlab_visibility::Accel;
use rayon::prelude::*;

use serde::{Deserialize, Serialize};

use crate::bounds::angle_between;
use crate::clamped_irradiance::CosineFit;
use crate::face_node::FaceContext;

/// Default opening θ: a node is gathered whole when its bounding radius is below θ times its distance from
/// the query point. Chosen by measurement (docs/methods.md, "Final gather over the tree").
pub const DEFAULT_OPENING: f64 = 0.25;

/// Default opening of the values' gather under [`GatherValues::Gathered`]: coarser than the final gather's,
/// since its error reaches a point only after one more bounce. Chosen by measurement (docs/methods.md).
pub const DEFAULT_VALUES_OPENING: f64 = 0.5;

/// Where the final gather's face values come from (parameter `gather_values`).
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum GatherValues {
    /// The solution's constant answers, once per solution (one bounce), with the faces near the point
    /// re-gathered as `near_values` asks ([`ClusterGather::with_near_values`]). The default.
    #[default]
    Solution,
    /// Every face's and every patch leaf's value gathered first over the tree at its centroid from the
    /// solution's answers, at opening `values_opening` (two bounces; k more queries a solution).
    Gathered,
}

impl GatherValues {
    /// The name used in parameters.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Solution => "solution",
            Self::Gathered => "gathered",
        }
    }
}

/// How the flat final gather (`gather_opening = 0`) treats faces near the query point (parameter
/// `near_field`).
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum NearField {
    /// Every face by its exact point-to-polygon factor and its one value (this module's gather). The default.
    #[default]
    Off,
    /// Through radlab-answer's shared final gather over the same values ([`radlab_answer::final_gather`], the
    /// gather every finite-element method answers with): a face nearer the point than its diameter is
    /// gathered as 4 × 4 sub-polygons, each with its own visibility ray and a radiosity re-gathered at it
    /// (Lischinski, Tampieri & Greenberg 1993), so light moves within the face toward its lit side. The far
    /// part of those values comes from this module's tree gather at [`DEFAULT_OPENING`] ([`TreeFarField`]), so
    /// the first time a face is near some query it costs one tree gather at its centroid and its near set's
    /// 64 points, not a pass over every face; each query is still the flat gather, O(k).
    SubPolygons,
}

impl NearField {
    /// The name used in parameters.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Off => "off",
            Self::SubPolygons => "sub-polygons",
        }
    }
}

/// The solution's values as the tree gather reads them: each face's radiosity and each node's sums.
#[derive(Debug)]
pub struct ClusterGather {
    /// Per scene face: its constant answer.
    face_radiosity: Vec<Rgb>,
    /// Faces the refinement split into patches: their patch leaves with values, gathered instead.
    patches: HashMap<FaceId, Vec<ElementValue>>,
    /// Per tree node and channel: p = Σ B_i A_i n_i.
    power: Vec<[DVec3; 3]>,
    /// Per tree node: Σ B_i A_i per channel.
    flux: Vec<Rgb>,
    /// Per tree node: whether it holds an emitting face (always opened).
    emits: Vec<bool>,

    opening: f64,
    settings: GatherSettings,
    /// Whole emitting faces' rays weighted by the point kernel ([`GatherSettings::kernel_weighted_share`]):
    /// the values' gather of [`GatherValues::Gathered`], which gathers emitters whole.
    kernel_weighted_emitters: bool,
    /// Re-gathered values of faces and patch leaves near query points (`near_values = "regathered"`), `None` for
    /// the solution's values alone.
    near: Option<RegatheredValues>,
    rays: AtomicU64,
    kernels: AtomicU64,
}

impl ClusterGather {
    /// The gather of a solution whose face `f` has constant answer `face_radiosity[f]`, and whose faces in
    /// `patches` are answered by their patch leaves; sums every node's power vector (one pass over the
    /// faces, children before parents).
    pub fn new(
        ctx: &FaceContext<'_>,
        face_radiosity: Vec<Rgb>,
        patches: HashMap<FaceId, Vec<ElementValue>>,
        opening: f64,
        seed: u64,
    ) -> Self {
        let (tree, scene) = (&ctx.tree, ctx.scene);
        let n = tree.nodes().len();
        let mut power = vec![[DVec3::ZERO; 3]; n];
        let mut flux = vec![Rgb::ZERO; n];
        let mut emits = vec![false; n];
        // Children follow parents (breadth-first), so a reverse walk sums children first.
        for i in (0..n).rev() {
            let node = tree.node(i);
            if node.is_leaf() {
                let f = tree.faces_of(i)[0] as usize;
                let face = &scene.faces[f];
                let b = face_radiosity[f];
                power[i] = std::array::from_fn(|k| face.normal * (b[k] * face.area));
                flux[i] = b * face.area;
                emits[i] = scene.material(f).is_emitter();
            } else {
                for c in node.children() {
                    let (p, fl, em) = (power[c], flux[c], emits[c]);
                    for k in 0..3 {
                        power[i][k] += p[k];
                    }
                    flux[i] += fl;
                    emits[i] |= em;
                }
            }
        }
        Self {
            face_radiosity,
            patches,
            power,
            flux,
            emits,
            opening,
            settings: GatherSettings::with_seed(seed),
            kernel_weighted_emitters: false,
            near: None,
            rays: AtomicU64::new(0),
            kernels: AtomicU64::new(0),
        }
    }

    /// The same gather over values that are themselves this gather's answers at every face's centroid (and,
    /// where the refinement split a face, at every patch leaf's centroid): [`GatherValues::Gathered`]. The
    /// values' gather, at `values_opening`, reads split faces by their leaves and emitters whole; its rays and
    /// kernel evaluations are charged to the new gather. Each query draws from its own stream (seed, point),
    /// so the values do not depend on the number of threads.
    pub fn regathered(
        ctx: &FaceContext<'_>,
        accel: &Accel,
        face_radiosity: Vec<Rgb>,
        patches: HashMap<FaceId, Vec<ElementValue>>,
        (opening, values_opening): (f64, f64),
        seed: u64,
    ) -> Self {
        let scene = ctx.scene;
        // Split faces are gathered by their leaves, each with its own visibility ray (a large wall behind an
        // occluder is not one ray's all or nothing), except emitters, gathered whole: their 16 jittered rays
        // already sample the whole face, weighted by the point kernel, and at every leaf they would cost 16
        // rays a leaf at each of k queries.
        let first_patches: HashMap<FaceId, Vec<ElementValue>> = patches
            .iter()
            .filter(|(f, _)| !scene.material(**f).is_emitter())
            .map(|(f, leaves)| (*f, leaves.clone()))
            .collect();
        let mut first = Self::new(
            ctx,
            face_radiosity,
            first_patches,
            values_opening,
            mix64(seed ^ 0x5ec0_d0b0_0a7c_e5a1),
        );
        first.kernel_weighted_emitters = true;
        let mut keys: Vec<FaceId> = patches.keys().copied().collect();
        keys.sort_unstable();
        let patches: HashMap<FaceId, Vec<ElementValue>> = keys
            .into_par_iter()
            .map(|f| {
                let leaves = patches[&f]
                    .iter()
                    .map(|l| ElementValue {
                        radiosity: first.radiosity_at(ctx, accel, f, l.polygon.centroid(), false),
                        ..*l
                    })
                    .collect();
                (f, leaves)
            })
            .collect();
        // A split face's value (its share of its ancestors' power vectors) is its leaves' area mean.
        let values: Vec<Rgb> = (0..scene.face_count())
            .into_par_iter()
            .map(|f| match patches.get(&f) {
                Some(leaves) => area_mean(leaves),
                None => first.radiosity_at(ctx, accel, f, scene.faces[f].centroid, false),
            })
            .collect();
        let gather = Self::new(ctx, values, patches, opening, seed);
        gather.rays.store(first.rays(), Ordering::Relaxed);
        gather
            .kernels
            .store(first.kernel_evaluations(), Ordering::Relaxed);
        gather
    }

    /// The same gather reading near faces and patch leaves as `near` asks: with [`NearValues::Regathered`], at
    /// values re-gathered at their centroids (module documentation).
    pub fn with_near_values(mut self, near: NearValues) -> Self {
        self.near = (near == NearValues::Regathered).then(|| RegatheredValues {
            faces: (0..self.face_radiosity.len())
                .map(|_| OnceLock::new())
                .collect(),
            leaves: self
                .patches
                .iter()
                .map(|(f, leaves)| (*f, leaves.iter().map(|_| OnceLock::new()).collect()))
                .collect(),
        });
        self
    }

    /// Rays cast by all queries so far.
    pub fn rays(&self) -> u64 {
        self.rays.load(Ordering::Relaxed)
    }

    /// Kernel evaluations (point-to-polygon factors, far nodes' point transfers and the point kernels that
    /// weigh their visibility samples) of all queries so far.
    pub fn kernel_evaluations(&self) -> u64 {
        self.kernels.load(Ordering::Relaxed)
    }

    /// Approximate heap bytes held.
    pub fn bytes(&self) -> usize {
        self.face_radiosity.capacity() * size_of::<Rgb>()
            + self.power.capacity() * size_of::<[DVec3; 3]>()
            + self.flux.capacity() * size_of::<Rgb>()
            + self.emits.capacity()
            + self
                .patches
                .values()
                .map(|v| v.capacity() * size_of::<ElementValue>() + 32)
                .sum::<usize>()
            + self.near.as_ref().map_or(0, |near| {
                near.faces.capacity() * size_of::<OnceLock<Rgb>>()
                    + near
                        .leaves
                        .values()
                        .map(|v| v.capacity() * size_of::<OnceLock<Rgb>>() + 32)
                        .sum::<usize>()
            })
    }

    /// B(x) at `point` on `face` of the scene of `ctx` (the context these values were made for; see the
    /// module documentation).
    pub fn radiosity_at(
        &self,
        ctx: &FaceContext<'_>,
        accel: &Accel,
        face: FaceId,
        point: DVec3,
        in_gap: bool,
    ) -> Rgb {
        self.radiosity_over(ctx, accel, face, point, in_gap, Pass::Answer)
    }

    /// [`ClusterGather::radiosity_at`] in `pass`: E + ρ times [`ClusterGather::irradiance_over`].
    fn radiosity_over(
        &self,
        ctx: &FaceContext<'_>,
        accel: &Accel,
        face: FaceId,
        point: DVec3,
        in_gap: bool,
        pass: Pass,
    ) -> Rgb {
        let scene = ctx.scene;
        let (rho, e) = (scene.reflectance(face), scene.emission(face));
        if rho.max_element() <= 0.0 {
            return e;
        }
        e + rho * self.irradiance_over(ctx, accel, face, point, in_gap, pass)
    }

    /// Σ_j F V B_j at `point` on `face` in `pass` (see [`Pass`]): what [`ClusterGather::radiosity_at`] multiplies
    /// by ρ. `in_gap`: the point lies in or beside a gap (its seal test found it open only after a closed ray),
    /// and every node is opened and every face's visible share measured by the kernel-weighted `direct` rays
    /// (module documentation).
    fn irradiance_over(
        &self,
        ctx: &FaceContext<'_>,
        accel: &Accel,
        face: FaceId,
        point: DVec3,
        in_gap: bool,
        pass: Pass,
    ) -> Rgb {
        let (tree, scene, centroid) = (&ctx.tree, ctx.scene, &ctx.centroid);
        let n = scene.faces[face].normal;
        let key = point_key(scene, face, point);
        let mut r = sampling::rng(self.settings.seed, key ^ mix64(u64::MAX));
        let (mut rays, mut kernels) = (0u64, 0u64);
        let mut sum = Rgb::ZERO;
        let mut stack: Vec<usize> = tree.roots().collect();
        while let Some(m) = stack.pop() {
            let node = tree.node(m);
            let s = &node.sphere;
            // Wholly behind (or in) the query's plane: nothing of it reaches x.
            if n.dot(s.centre - point) <= -s.radius {
                continue;
            }
            if node.is_leaf() {
                let f = tree.faces_of(m)[0] as usize;
                if f != face {
                    sum += self.gather_face(
                        ctx,
                        accel,
                        pass,
                        (face, point, n, in_gap),
                        key,
                        f,
                        &mut rays,
                        &mut kernels,
                    );
                }
                continue;
            }
            let to_x = point - s.centre;
            let dist = to_x.length();
            if self.emits[m] || in_gap || !(s.radius < self.opening * dist) {
                stack.extend(node.children());
                continue;
            }
            // A far node: nothing of it faces x when its faces' cosines toward x, within
            // [cos(α + θ), cos(α − θ)], are all negative.
            let (alpha, theta) = (angle_between(node.cone.axis, to_x), node.cone.half_angle);
            if alpha - theta >= std::f64::consts::FRAC_PI_2 {
                continue;
            }
            let fit = CosineFit::of_node(node, to_x / dist);
            let c = centroid[m];
            let v = point - c;
            let r2 = v.length_squared();
            let d = v / r2.sqrt();
            let cos_x = n.dot(-d);
            kernels += 1;
            if !(cos_x > 0.0 && r2 > 0.0) {
                continue;
            }
            let sent = fit.sent(&self.power[m], self.flux[m], d);
            if sent.max_element() <= 0.0 {
                continue;
            }
            // A sample drawn by its point kernel, so never one whose face turns away from x (unless all do):
            // the fit already gives such faces nothing, and a ray from behind them must not count that again
            // as occlusion. The weights are kernel evaluations too.
            kernels += tree.samples(m).len() as u64;
            let y = tree.sample_toward(m, point, n, sampling::uniform(&mut r));
            rays += 1;
            if accel.visible_between(point, face, y, usize::MAX) {
                sum += sent * (cos_x / (std::f64::consts::PI * r2));
            }
        }
        self.rays.fetch_add(rays, Ordering::Relaxed);
        self.kernels.fetch_add(kernels, Ordering::Relaxed);
        sum
    }

    /// F V B of input face `f` (or of its patch leaves) at `point` on `face`, exactly; in an answer with near
    /// values, each near one's value re-gathered ([`ClusterGather::near_value`]).
    #[allow(clippy::too_many_arguments)]
    fn gather_face(
        &self,
        ctx: &FaceContext<'_>,
        accel: &Accel,
        pass: Pass,
        (face, point, n, in_gap): (FaceId, DVec3, DVec3, bool),
        key: u64,
        f: FaceId,
        rays: &mut u64,
        kernels: &mut u64,
    ) -> Rgb {
        let scene = ctx.scene;
        let emits = scene.material(f).is_emitter();
        // Near values: of a non-emitting element wholly open (a leaf with a sealed part keeps its open part's
        // mean, which a value at its centroid would not give).
        let near = self
            .near
            .as_ref()
            .filter(|_| pass == Pass::Answer && !emits);
        // A re-gather reads an emitter whole, as the values' gather of gathered values does.
        let whole_emitter = emits && (self.kernel_weighted_emitters || pass == Pass::NearValue);
        // F V B of `el`, its value re-gathered (`cache`) where its factor reaches the bound and it is seen; the
        // factor and the rays come first, so an element behind the point or hidden from it is not re-gathered.
        let one = |el: &ElementValue,
                   cache: Option<&OnceLock<Rgb>>,
                   stream: u64,
                   rays: &mut u64,
                   kernels: &mut u64| {
            let cache = cache.filter(|_| el.open >= 1.0);
            if cache.is_none() && el.radiosity.max_element() <= 0.0 {
                return Rgb::ZERO;
            }
            *kernels += 1;
            let ff = point_polygon(point, n, &el.polygon);
            if !(ff > 0.0) {
                return Rgb::ZERO;
            }
            let v = if in_gap || whole_emitter {
                self.settings.kernel_weighted_share(
                    accel,
                    face,
                    point,
                    n,
                    key,
                    stream,
                    el,
                    emits || in_gap,
                    rays,
                    kernels,
                )
            } else {
                self.settings
                    .visible_share(accel, face, point, n, key, stream, el, emits, rays)
            };
            let b = match cache {
                Some(c) if ff >= NEAR_VALUES_MIN_FACTOR && v > 0.0 => {
                    *c.get_or_init(|| self.near_value(ctx, accel, el))
                }
                _ => el.radiosity,
            };
            (ff * v) * b
        };
        match self.patches.get(&f).filter(|_| !whole_emitter) {
            Some(leaves) => leaves
                .iter()
                .enumerate()
                .map(|(i, el)| {
                    let cache = near.map(|values| &values.leaves[&f][i]);
                    one(el, cache, mix64(f as u64) ^ i as u64, rays, kernels)
                })
                .fold(Rgb::ZERO, |a, b| a + b),
            None => {
                let cache = near.map(|values| &values.faces[f]);
                one(&self.whole_face(scene, f), cache, f as u64, rays, kernels)
            }
        }
    }

    /// The re-gathered value of element `el` (`near_values = "regathered"`): E + ρ Σ F V B at its centroid over the
    /// solution's values, or its own value when the centroid is sealed (the seal test the solver makes of a
    /// query point, [`point_sealed`]: under a block standing on a floor, where a gather would read the light
    /// the solution sent into the gap) or open only after a closed ray (beside a gap, where a gather would
    /// measure every source with 16 rays). Its rays and kernel evaluations are the gather's.
    fn near_value(&self, ctx: &FaceContext<'_>, accel: &Accel, el: &ElementValue) -> Rgb {
        let scene = ctx.scene;
        let (f, c) = (el.face, el.polygon.centroid());
        // A face that reflects nothing answers its emission, its value already.
        if scene.reflectance(f).max_element() <= 0.0 {
            return el.radiosity;
        }
        let (sealed, seal_rays) = point_sealed(
            scene,
            accel,
            f,
            c,
            POINT_SEAL_RAYS,
            self.settings.seed,
            point_key(scene, f, c),
        );
        self.rays.fetch_add(seal_rays, Ordering::Relaxed);
        if sealed || seal_rays > 1 {
            return el.radiosity;
        }
        self.radiosity_over(ctx, accel, f, c, false, Pass::NearValue)
    }

    /// Input face `f` as one source element with its value.
    fn whole_face(&self, scene: &Scene, f: FaceId) -> ElementValue {
        ElementValue {
            face: f,
            polygon: scene.polygon(f),
            radiosity: self.face_radiosity[f],
            open: 1.0,
        }
    }

    /// The values as a flat list of source elements, in face order: each input face with its value, or its
    /// patch leaves where the refinement split it (what [`NearField::SubPolygons`] gathers).
    pub fn elements(&self, scene: &Scene) -> Vec<ElementValue> {
        let mut out = Vec::with_capacity(self.face_radiosity.len());
        for f in 0..self.face_radiosity.len() {
            match self.patches.get(&f) {
                Some(leaves) => out.extend_from_slice(leaves),
                None => out.push(self.whole_face(scene, f)),
            }
        }
        out
    }
}

/// Which gather over the tree a query is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Pass {
    /// A point's answer: near faces at their re-gathered values where the gather has them.
    Answer,
    /// The far part the shared final gather's near field asks for: the solution's values.
    Far,
    /// A near value's re-gather: the solution's values, split emitters read whole with kernel-weighted rays
    /// (a lamp the refinement split into hundreds of patches would cost 16 rays a patch at each re-gather).
    NearValue,
}

/// Values re-gathered at their first use, per face and per patch leaf of a split face (`near_values = "regathered"`).
#[derive(Debug)]
struct RegatheredValues {
    faces: Vec<OnceLock<Rgb>>,
    leaves: HashMap<FaceId, Vec<OnceLock<Rgb>>>,
}

/// This gather as the far part of the shared final gather's near field ([`NearField::SubPolygons`]).
pub struct TreeFarField<'g, 'a> {
    /// The gather over the tree (its opening, its values).
    pub gather: &'g ClusterGather,
    /// The tree and scene the values were made for.
    pub ctx: &'g FaceContext<'a>,
    /// The scene's rays.
    pub accel: &'g Accel,
}

impl FarField for TreeFarField<'_, '_> {
    fn irradiance(&self, face: FaceId, point: DVec3) -> Rgb {
        self.gather
            .irradiance_over(self.ctx, self.accel, face, point, false, Pass::Far)
    }
}

/// The area mean of `leaves`' radiosities (zero for no area).
pub fn area_mean(leaves: &[ElementValue]) -> Rgb {
    let area: f64 = leaves.iter().map(|l| l.polygon.area()).sum();
    let sum = leaves
        .iter()
        .fold(Rgb::ZERO, |s, l| s + l.radiosity * l.polygon.area());
    if area > 0.0 { sum / area } else { Rgb::ZERO }
}

//! The wavelet transport on radlab-hierarchical's engine (Gortler, Schröder, Cohen & Hanrahan 1993): quadtree
//! elements of the input faces carry M² coefficients per channel, links the M⁴ tensor of
//! [`crate::link_tensor`], and one pass of the engine is
//!
//!   h^R_α += Σ_β T_αβ b^S_β                 (gather, at each link's receiver),
//!   h^c_β += Σ_α H^c_αβ h^p_α               (push: the parent's irradiance restricted to child c),
//!   b_α = E δ_α0 + ρ h_α                    (reflect, at each leaf),
//!   b^p_α = ¼ Σ_c Σ_β H^c_αβ b^c_β          (pull: the children's radiosity projected on the parent),
//!
//! with H the basis' two-scale relation ([`crate::basis::TwoScale`]). The engine keeps b_0, the mean, as each
//! node's radiosity; the transport's exitance holds the rest (index 0 unused). Elements that are not
//! parallelograms (triangles, general quads) hold their mean only ([`crate::link_tensor::holds_tensor`]).
//!
//! Open shares (Baum, Mann, Smith & Winget 1991's light and shadow leaks at contacts): with
//! [`WaveletTransport::with_open_shares`] each leaf gets an open share o ∈ [0, 1], estimated at its
//! receiver quadrature nodes, where its tensors sample visibility: the quadrature-weighted share of nodes
//! that radlab-kernels' probe finds open (8 cosine rays, a node sealed when every ray meets a back), so that
//! for a leaf-to-leaf link with per-pair rays o matches what the tensor's mean saw. The engine
//! (radlab-hierarchical's `open_share` module) holds the leaf's coefficients over its open part. The share
//! enters per leaf, not per quadrature node: a link's receiver gain 1/ō_l, ō_l = Σ_t o_t A_t T^t_00 /
//! Σ_t A_t T^t_00 weighted by each target's mean-to-mean entry T_00 = V F ([`Transport::coefficient_weight`]),
//! scales all M² coefficients it delivers, a wholly sealed leaf (o = 0) receives and sends nothing, and any
//! other source sends its M² coefficients as they are (its tensor already carries its sealed nodes'
//! visibility). So the power
//! delivered is unchanged and a leaf under a coarse link, whose tensor is re-integrated with the link's one
//! visibility fraction, no longer takes light its sealed part cannot receive. Per leaf because the gain is
//! the engine's, one number per (link, target): it scales the shape of a straddling leaf's irradiance with
//! its mean, which for a leaf-to-leaf link with per-pair rays (the shape already near 0 at sealed nodes)
//! overstates the open part's variation by 1/o; a point answer inside a leaf with o < 1 first tests the
//! point itself ([`radlab_kernels::open_fraction::point_sealed`]).
//!
//! Below a partly visible link's receiver, a leaf scales its re-integrated tensor by its own visibility of the
//! source (rays between the leaf and the source, [`LeafVisibility`]; the link's one share spread the shadow of
//! an occluder near the receiver over the whole receiver). Such a tensor already leaves out the leaf's sealed
//! part, so the engine gains it by the leaf's own 1/o, not by the link's 1/ō_l.
//!
//! Refinement reads [`WaveletOracle`]: Bekaert & Willems 1996's estimate from the link's residuals at the
//! receiver nodes with a source-side term,
//!
//!   e = ρ_R max_channel (Σ_β |b^S_β| e_β + V F_RS d_S) / B̄,   d_S = max_c Σ_β |b^c_β − (H^c b^S)_β|,
//!
//! (B̄ the scene's mean radiosity, so ε is dimensionless), or HSA91's F and BF on the link's form factors.
//! The residuals see how well the link reproduces the kernel at its receiver; d_S, the misfit of an inner
//! source's children to its own function restricted to each (the two-scale relation; 0 for a leaf), sees how
//! well the coefficients the link sends stand for what lies below the source. Without it the estimate accepted
//! links from coarse sources whose pulled coefficients misrepresent their leaves, and a closed box lit by its
//! lamp lost 0.54% of its power in M2 at the defaults (0.26% with it; crates/wavelet/tests/furnace.rs).

use glam::DVec3;
use radlab_hierarchical::{
    GatherAt, LeafVisibility, LinearState, LinkError, LinkPayload, NodeKind, NodeView, Oracle,
    Patch, SourceFlux, SourceLight, Transport, link_stream, pair_visibility,
};
use radlab_kernels::form_factor::VisibilitySampling;
use radlab_kernels::open_fraction::{DEFAULT_OPEN_RAYS, point_sealed};
use radlab_scene::sampling::mix64;
use radlab_scene::{Rgb, Scene};
use radlab_visibility::Accel;

use crate::basis::{Basis, CHILD_CELLS, TwoScale};
use crate::link_tensor::{ElementRule, TensorSetup, Visibility, holds_tensor, link_tensor};

/// K coefficients per channel: irradiance, radiosity flux or (index 0 unused) exitance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coeffs<const K: usize>(pub [Rgb; K]);

impl<const K: usize> Default for Coeffs<K> {
    fn default() -> Self {
        Self([Rgb::ZERO; K])
    }
}

impl<const K: usize> LinearState for Coeffs<K> {
    fn add_scaled(&mut self, c: Rgb, x: &Self) {
        for (a, b) in self.0.iter_mut().zip(&x.0) {
            *a += c * *b;
        }
    }
}

/// A source of uniform radiosity B sends (B, 0, …).
impl<const K: usize> From<Rgb> for Coeffs<K> {
    fn from(b: Rgb) -> Self {
        let mut c = Self::default();
        c.0[0] = b;
        c
    }
}

impl<const K: usize> SourceFlux for Coeffs<K> {
    fn scaled(self, s: f64) -> Self {
        Self(self.0.map(|x| x * s))
    }
}

/// How a link's error is estimated.
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum WaveletOracle {
    /// Bekaert & Willems 1996: the link's reproduction at the receiver's quadrature nodes against the
    /// point-to-element kernel, weighted by the source's coefficients and ρ_R, over the mean radiosity; plus
    /// a source-side term, V F_RS times the misfit of the source's children to its own function.
    #[default]
    BekaertWillems,
    /// Form factor max(F_RS, F_SR) (Hanrahan, Salzman & Aupperle 1991): geometry only.
    F,
    /// ρ_R B_S max(F_RS, F_SR) / B̄ (Hanrahan, Salzman & Aupperle 1991).
    Bf,
}

/// Where a link's tensor is evaluated.
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum WaveletGather {
    /// At each leaf below the receiver, the tensor re-integrated over the leaf (exact point-to-polygon
    /// factors at its nodes, the link's visibility): the mean's rows are exact form-factor sums, so the
    /// furnace holds at any ρ. Memory M⁴ per (leaf, link above it).
    #[default]
    Leaf,
    /// At the receiver, pushed to the leaves by the two-scale relation (Gortler et al. 1993): M⁴ per link
    /// only, but where links meet a leaf at several levels its rows sum to one only up to the basis'
    /// approximation of each link's kernel, an error magnified by 1/(1 − ρ).
    Receiver,
}

/// A link of the wavelet transport: its source and tensor.
#[derive(Clone, Debug)]
pub struct WaveletLink<const K: usize> {
    /// Source node id.
    pub source: u32,
    /// T_αβ, receiver α per unit source coefficient β ([`crate::link_tensor`]).
    pub t: [[f32; K]; K],
    /// Bekaert & Willems residual per source function.
    pub residual: [f32; K],
    /// Unoccluded F_RS.
    pub f_recv: f32,
    /// Unoccluded F_SR = F_RS A_R / A_S.
    pub f_src: f32,
    /// The link's visibility (per-link fraction or the kernel-weighted share of per-pair rays).
    pub visibility: f32,
}

impl<const K: usize> LinkPayload for WaveletLink<K> {
    fn source(&self) -> u32 {
        self.source
    }

    /// The form-factor oracles (the engine's default reading; the transport's own is
    /// [`Transport::link_error`]).
    fn error(&self, oracle: Oracle, weight: f64) -> LinkError {
        let f = self.f_recv.max(self.f_src) as f64;
        let m = self.f_recv.min(self.f_src) as f64;
        let w = if oracle == Oracle::F { 1.0 } else { weight };
        LinkError {
            estimate: f * w,
            each_end: Some(m * w),
        }
    }
}

/// The wavelet transport: M² coefficients per element, M⁴ per link (K = M²).
#[derive(Debug)]
pub struct WaveletTransport<'a, const K: usize> {
    accel: &'a Accel,
    basis: Basis,
    points: usize,
    visibility: Visibility,
    oracle: WaveletOracle,
    gather: WaveletGather,
    seed: u64,
    two_scale: TwoScale,
    /// Rays of a leaf's own visibility below a partly visible link's receiver; `None`: the link's share.
    leaf_visibility: Option<VisibilitySampling>,
    /// The scene whose leaves' open shares are estimated ([`WaveletTransport::with_open_shares`]), if any.
    open_shares: Option<&'a Scene>,
}

impl<'a, const K: usize> WaveletTransport<'a, K> {
    /// A transport in `basis` (whose M² must be K) with `points` Gauss points per cell and side.
    ///
    /// # Panics
    /// If K is not `basis.len()` (a programming error of the caller, which picks K from the basis).
    pub fn new(
        accel: &'a Accel,
        basis: Basis,
        points: usize,
        visibility: Visibility,
        oracle: WaveletOracle,
        gather: WaveletGather,
        seed: u64,
    ) -> Self {
        assert_eq!(K, basis.len(), "K must be the basis' M²");
        Self {
            accel,
            basis,
            points,
            visibility,
            oracle,
            gather,
            seed,
            two_scale: TwoScale::new(basis),
            leaf_visibility: None,
            open_shares: None,
        }
    }

    /// The same transport scaling the tensor re-integrated at a leaf below a partly visible link's receiver
    /// by the leaf's own visibility of the link's source ([`LeafVisibility`]), not the link's share.
    pub fn with_leaf_visibility(mut self, leaf: LeafVisibility) -> Self {
        self.leaf_visibility = leaf.sampling();
        self
    }

    /// Whether `link`'s tensors below its receiver carry each leaf's own visibility: leaf rays on, gathered
    /// at leaves, and the link partly visible.
    fn leaves_see_for_themselves(&self, link: &WaveletLink<K>) -> bool {
        self.leaf_visibility.is_some()
            && self.gather == WaveletGather::Leaf
            && link.visibility > 0.0
            && link.visibility < 1.0
    }

    /// The same transport estimating every leaf's open share in `scene` (the scene the accelerator was built
    /// from): the quadrature-weighted share of its receiver nodes that radlab-kernels' [`point_sealed`] finds
    /// open (8 cosine rays a node through the counted accelerator, the stream keyed by the leaf and node). The engine then holds each leaf's coefficients over its
    /// open part, per leaf (the crate's `transport` module).
    pub fn with_open_shares(mut self, scene: &'a Scene) -> Self {
        self.open_shares = Some(scene);
        self
    }

    /// The basis.
    pub fn basis(&self) -> Basis {
        self.basis
    }

    /// The link `recv ← src` (None when nothing is transferred): its tensor by [`link_tensor`].
    pub fn make_link(&self, recv: &Patch, src: &Patch, src_id: u32) -> Option<WaveletLink<K>> {
        if recv.face == src.face {
            return None;
        }
        let rr = ElementRule::<K>::new(recv, self.basis, self.points);
        let rs = ElementRule::<K>::new(src, self.basis, self.points);
        let setup = TensorSetup {
            accel: self.accel,
            visibility: self.visibility,
            seed: self.seed,
            stream: link_stream(recv.key(), src.key()),
            given: None,
        };
        let t = link_tensor(&setup, recv, &rr, src, &rs)?;
        Some(WaveletLink {
            source: src_id,
            t: t.t,
            residual: t.residual,
            f_recv: t.f_rs as f32,
            f_src: (t.f_rs * recv.area / src.area) as f32,
            visibility: t.visibility as f32,
        })
    }

    /// The quadtree child index (0..4, [`CHILD_CELLS`]) of `child` in `parent`, from their lattice corners.
    fn child_index(parent: &Patch, child: &Patch) -> usize {
        let cs = (child.uv[0][0] > parent.uv[0][0]) as usize;
        let ct = (child.uv[0][1] > parent.uv[0][1]) as usize;
        CHILD_CELLS.iter().position(|&c| c == (cs, ct)).unwrap_or(0)
    }

    /// Per channel, how far a source's own coefficients `b` are from its children's: the largest over the
    /// children of Σ_β |b^c_β − (H^c b)_β|, the children's coefficients less the source's function restricted
    /// to each ([`Transport::push`]'s two-scale relation). Zero for a leaf.
    fn source_detail(
        &self,
        src: &Patch,
        b: &Coeffs<K>,
        light: &SourceLight<'_, Patch, Coeffs<K>>,
    ) -> [f64; 3] {
        let mut d = [0.0f64; 3];
        for (k, child) in light.children.iter().enumerate() {
            let pred = self.push(src, child, b);
            let actual = Self::full(light.child_radiosity[k], &light.child_exitance[k]);
            for (ch, dc) in d.iter_mut().enumerate() {
                let s: f64 = (0..K)
                    .map(|j| (actual.0[j][ch] - pred.0[j][ch]).abs())
                    .sum();
                *dc = dc.max(s);
            }
        }
        d
    }

    /// The coefficients of a node from its mean and exitance.
    fn full(b: Rgb, x: &Coeffs<K>) -> Coeffs<K> {
        let mut c = *x;
        c.0[0] = b;
        c
    }
}

/// Per channel, the K coefficients as numbers.
fn channel<const K: usize>(c: &Coeffs<K>, ch: usize) -> [f64; K] {
    c.0.map(|x| x[ch])
}

impl<const K: usize> Transport<Patch> for WaveletTransport<'_, K> {
    type Irradiance = Coeffs<K>;
    type Exitance = Coeffs<K>;
    type Coefficient = [[f32; K]; K];
    type Link = WaveletLink<K>;
    type Flux = Coeffs<K>;

    fn may_interact(&self, recv: &Patch, src: &Patch) -> bool {
        radlab_hierarchical::PatchKernel::patches_interact(recv, src)
    }

    fn link(&self, recv: &Patch, _recv_id: u32, src: &Patch, src_id: u32) -> Option<Self::Link> {
        self.make_link(recv, src, src_id)
    }

    fn link_error(
        &self,
        recv: &Patch,
        src: &Patch,
        link: &Self::Link,
        light: &SourceLight<'_, Patch, Self::Exitance>,
    ) -> LinkError {
        match self.oracle {
            WaveletOracle::F => link.error(Oracle::F, 1.0),
            WaveletOracle::Bf => link.error(Oracle::Bf, light.weight),
            WaveletOracle::BekaertWillems => {
                if !(light.scale > 0.0) {
                    return LinkError {
                        estimate: 0.0,
                        each_end: None,
                    };
                }
                let b = Self::full(light.radiosity, light.exitance);
                let detail = self.source_detail(src, &b, light);
                let f = (link.f_recv * link.visibility) as f64;
                let mut worst: f64 = 0.0;
                for (ch, d) in detail.iter().enumerate() {
                    let s: f64 = (0..K)
                        .map(|j| b.0[j][ch].abs() * link.residual[j] as f64)
                        .sum();
                    worst = worst.max(recv.reflectance[ch] * (s + f * d));
                }
                LinkError {
                    estimate: worst / light.scale,
                    each_end: None,
                }
            }
        }
    }

    fn gather_at(&self, _recv: &Patch, _src: &Patch) -> GatherAt {
        match self.gather {
            WaveletGather::Leaf => GatherAt::Leaves,
            WaveletGather::Receiver => GatherAt::Receiver,
        }
    }

    /// The link's own tensor at its receiver; below it, the tensor re-integrated over the target with the
    /// link's visibility (one kernel evaluation, counted by the engine), or, where that is partial and
    /// leaves cast their own rays, the target's visibility of the source.
    fn coefficient(
        &self,
        target: &Patch,
        src: &Patch,
        link: &Self::Link,
        at_receiver: bool,
    ) -> Self::Coefficient {
        if at_receiver {
            return link.t;
        }
        let rr = ElementRule::<K>::new(target, self.basis, self.points);
        let rs = ElementRule::<K>::new(src, self.basis, self.points);
        let v = match self.leaf_visibility {
            Some(sampling) if self.leaves_see_for_themselves(link) => {
                // The rays a patch link between the leaf and the source would cast.
                let own = pair_visibility(self.accel, target, src, sampling, self.seed);
                if own.is_nan() {
                    link.visibility as f64
                } else {
                    own
                }
            }
            _ => link.visibility as f64,
        };
        let setup = TensorSetup {
            accel: self.accel,
            visibility: self.visibility,
            seed: self.seed,
            stream: 0,
            given: Some(v),
        };
        link_tensor(&setup, target, &rr, src, &rs)
            .map(|t| t.t)
            .unwrap_or([[0.0; K]; K])
    }

    fn emit(
        &self,
        _view: &NodeView<'_, Patch>,
        b: &[Rgb],
        x: &[Self::Exitance],
        _recv: u32,
        link: &Self::Link,
    ) -> Self::Flux {
        let s = link.source as usize;
        Self::full(b[s], &x[s])
    }

    /// The quadrature-weighted share of the leaf's receiver nodes (its [`ElementRule`], where its tensors
    /// sample visibility) that are open: [`point_sealed`] with 8 cosine rays at each node.
    fn open_share(&self, leaf: &Patch) -> Option<f64> {
        let scene = self.open_shares?;
        let rule = ElementRule::<K>::new(leaf, self.basis, self.points);
        let (mut open, mut total) = (0.0, 0.0);
        for (k, (y, w, _)) in rule.nodes.iter().enumerate() {
            let key = mix64(leaf.key() ^ mix64(k as u64));
            let (sealed, _rays) = point_sealed(
                scene,
                self.accel,
                leaf.face,
                *y,
                DEFAULT_OPEN_RAYS,
                self.seed,
                key,
            );
            total += w;
            if !sealed {
                open += w;
            }
        }
        Some(if total > 0.0 { open / total } else { 1.0 })
    }

    /// The mean-to-mean entry T_00 (the link's form factor at the target, V F), as a patch's V F.
    fn own_visibility(&self, _target: &Patch, _src: &Patch, link: &Self::Link) -> bool {
        self.leaves_see_for_themselves(link)
    }

    fn coefficient_weight(&self, c: &Self::Coefficient) -> f64 {
        (c[0][0] as f64).max(0.0)
    }

    fn deliver(&self, h: &mut Self::Irradiance, c: &Self::Coefficient, flux: Self::Flux) {
        for (a, ha) in h.0.iter_mut().enumerate() {
            for (b, fb) in flux.0.iter().enumerate() {
                *ha += c[a][b] as f64 * *fb;
            }
        }
    }

    fn push(&self, parent: &Patch, child: &Patch, h: &Self::Irradiance) -> Self::Irradiance {
        if !(holds_tensor(parent) && holds_tensor(child)) {
            return Coeffs::from(h.0[0]);
        }
        let c = Self::child_index(parent, child);
        let mut out = Coeffs::<K>::default();
        for ch in 0..3 {
            let p = channel(h, ch);
            let mut q = [0.0; K];
            self.two_scale.push(c, &p, &mut q);
            for (o, v) in out.0.iter_mut().zip(q) {
                o[ch] = v;
            }
        }
        out
    }

    fn reflect(
        &self,
        leaf: &Patch,
        h: &Self::Irradiance,
        with_emission: bool,
    ) -> (Rgb, Self::Exitance) {
        let e = if with_emission {
            leaf.emission
        } else {
            Rgb::ZERO
        };
        let mut x = Coeffs::<K>::default();
        for a in 1..K {
            x.0[a] = leaf.reflectance * h.0[a];
        }
        (e + leaf.reflectance * h.0[0], x)
    }

    fn pull(
        &self,
        parent: &Patch,
        children: &[Patch],
        b: &[Rgb],
        x: &[Self::Exitance],
    ) -> (Rgb, Self::Exitance) {
        let tensor =
            children.len() == 4 && holds_tensor(parent) && children.iter().all(holds_tensor);
        if !tensor {
            let mut sum = Rgb::ZERO;
            let mut area = 0.0;
            for (c, bc) in children.iter().zip(b) {
                sum += c.area * *bc;
                area += c.area;
            }
            let mean = if area > 0.0 { sum / area } else { Rgb::ZERO };
            return (mean, Coeffs::default());
        }
        // Children in quadtree order, whatever order the engine holds them in.
        let mut kids = [[[0.0; K]; 4]; 3];
        for (i, c) in children.iter().enumerate() {
            let q = Self::child_index(parent, c);
            let full = Self::full(b[i], &x[i]);
            for (ch, kid) in kids.iter_mut().enumerate() {
                kid[q] = channel(&full, ch);
            }
        }
        let mut out = Coeffs::<K>::default();
        for (ch, kid) in kids.iter().enumerate() {
            let mut p = [0.0; K];
            self.two_scale
                .pull([&kid[0], &kid[1], &kid[2], &kid[3]], &mut p);
            for (o, v) in out.0.iter_mut().zip(p) {
                o[ch] = v;
            }
        }
        // The mean as the children's area mean (exact power; the same as the relation's ¼ Σ on a
        // parallelogram, and exact on a slightly twisted quad too).
        let area: f64 = children.iter().map(|c| c.area).sum();
        let mean = if area > 0.0 {
            children
                .iter()
                .zip(b)
                .map(|(c, bc)| c.area * *bc)
                .sum::<Rgb>()
                / area
        } else {
            out.0[0]
        };
        out.0[0] = Rgb::ZERO;
        (mean, out)
    }

    /// Σ_α b_α φ_α(s, t) at the point's parameters on the leaf, clamped at zero.
    fn radiosity_at(&self, leaf: &Patch, b: Rgb, x: &Self::Exitance, point: DVec3) -> Rgb {
        if K == 1 || !holds_tensor(leaf) {
            return b;
        }
        let st = leaf.polygon.param_coords(point);
        let (s, t) = (st.x.clamp(0.0, 1.0), st.y.clamp(0.0, 1.0));
        let mut f = [0.0; K];
        self.basis.eval(s, t, &mut f);
        let mut v = b;
        for (fa, xa) in f.iter().zip(&x.0).skip(1) {
            v += *fa * *xa;
        }
        // Polynomials ring across shadow edges and contacts and can dip below zero there (Zatz 1993); a
        // radiosity is never negative, so the point answer is clamped (the coefficients are not).
        v.max(Rgb::ZERO)
    }

    fn uniform_response(&self, leaf: &Patch) -> (Rgb, Self::Exitance) {
        (leaf.reflectance, Coeffs::default())
    }

    fn unit_response(&self, _leaf: &Patch) -> Option<(Rgb, Self::Exitance)> {
        Some((Rgb::ONE, Coeffs::default()))
    }
}

//! The patch-to-patch transport (Hanrahan, Salzman & Aupperle 1991): how light moves between quadtree
//! elements of input faces.
//!
//! A link from source s to receiver r carries the transfer coefficient of the gather H_r += K_rs B_s: for
//! patches K_rs = V_rs F_rs, with
//!
//! F_rs = Σ_k w_k F_{dA(x_k)→s},  x_k the receiver's Gauss points (weights w_k summing to 1; radlab-kernels'
//! [`receiver_points`], the rule matrix and progressive radiosity integrate with),
//!
//! the receiver-side quadrature of the exact point-to-polygon factor (Lambert's contour integral, clipped to
//! the receiver's horizon; Baum, Rushmeier & Winget 1989, eq. 3), and V_rs the fraction of unobstructed rays
//! between the two (1, 4, 16 or 64 rays; Wallace, Elmquist & Haines 1989 split kernel and visibility the same
//! way). Each link also keeps what the refinement oracles read ([`crate::Link`]).
//!
//! A leaf below a link's receiver (gather = leaf) re-integrates the kernel over itself, F_{leaf→s}, and, where
//! the link is partly visible (0 < V_rs < 1), measures its own visibility V_{leaf,s} with rays between the
//! leaf and the source ([`crate::LeafVisibility`]): the link's one fraction would spread a shadow cast near the
//! receiver over all of it.
//!
//! Where a link's source is an inner node, what it sends is the mean of its leaves' radiosity weighted by how
//! much each sees the receiver, w_y = A_y F_{y→r} by y's own Gauss points ([`PatchKernel::source_weight`];
//! the crate's `gather_rows` module), and a leaf reflects B = E + ρ H ([`reflect_scalar`]).

use radlab_kernels::form_factor::{
    VisibilitySampling, point_polygon, receiver_points, visibility_fraction,
};
use radlab_scene::facing_away;
use radlab_visibility::Accel;

use radlab_kernels::open_fraction::open_share;
use radlab_scene::{Rgb, Scene};

use crate::link::{Link, link_stream};
use crate::node::{NodeKind, Patch};
use crate::params::{Gather, LeafVisibility};
use crate::transport::{GatherAt, NodeView, Transport};

/// Mean of the point-to-polygon factor F_{dA(x)→src} over `recv`'s m × m Gauss points x: `recv`'s
/// form factor to `src` by the receiver-side quadrature.
pub fn kernel_mean(recv: &Patch, src: &Patch, m: u32) -> f64 {
    receiver_points(&recv.polygon, m)
        .iter()
        .map(|(x, w)| w * point_polygon(*x, recv.normal, &src.polygon))
        .sum()
}

/// The visibility fraction between two patches by `sampling`'s rays, the ends ordered by key and the stream
/// the pair's ([`link_stream`]), so that the pair casts the same rays whichever end receives: a link's, and a
/// leaf's own below a link's receiver ([`crate::LeafVisibility`]). NaN where the sampling gives none.
pub fn pair_visibility(
    accel: &Accel,
    x: &Patch,
    y: &Patch,
    sampling: VisibilitySampling,
    seed: u64,
) -> f64 {
    let (kx, ky) = (x.key(), y.key());
    let (a, b) = if kx <= ky { (x, y) } else { (y, x) };
    visibility_fraction(
        accel,
        &a.polygon,
        a.face,
        &b.polygon,
        b.face,
        sampling,
        seed,
        link_stream(kx, ky),
    )
}

/// The patch-to-patch transport: receiver quadrature of the point-to-polygon factor times sampled visibility;
/// irradiance gathered per leaf ([`Gather::Leaf`]) or per link and pushed ([`Gather::Link`]).
#[derive(Debug)]
pub struct PatchKernel<'a> {
    accel: &'a Accel,
    quadrature: u32,
    visibility: VisibilitySampling,
    seed: u64,
    gather: Gather,
    /// Rays of a leaf's own visibility below a partly visible link's receiver; `None`: the link's fraction.
    leaf_visibility: Option<VisibilitySampling>,
    /// The scene whose leaves' open shares are estimated ([`PatchKernel::with_open_shares`]), if any.
    open_shares: Option<&'a Scene>,
}

impl<'a> PatchKernel<'a> {
    /// A kernel with `quadrature` Gauss points per side, the given ray sampling and gather.
    pub fn new(
        accel: &'a Accel,
        quadrature: u32,
        visibility: VisibilitySampling,
        seed: u64,
        gather: Gather,
    ) -> Self {
        Self {
            accel,
            quadrature,
            visibility,
            seed,
            gather,
            leaf_visibility: None,
            open_shares: None,
        }
    }

    /// The same kernel giving each leaf below a partly visible link's receiver its own visibility of the
    /// link's source ([`crate::LeafVisibility`]).
    pub fn with_leaf_visibility(mut self, leaf: LeafVisibility) -> Self {
        self.leaf_visibility = leaf.sampling();
        self
    }

    /// The same kernel estimating every leaf's open share in `scene` (the scene `accel` was built from):
    /// [`radlab_kernels::open_fraction`], 16 stratified points × 8 cosine rays, the stream keyed by the leaf's
    /// [`NodeKind::key`]. Only with area-sampled visibility: a link's visibility carries its source's sealed
    /// share only when its rays start all over the source; with one centre ray or none an element is open or
    /// closed as a whole, and the share stays 1.
    pub fn with_open_shares(mut self, scene: &'a Scene) -> Self {
        self.open_shares = self.visibility.is_area_sampled().then_some(scene);
        self
    }

    /// The accelerator rays are cast through.
    pub fn accel(&self) -> &'a Accel {
        self.accel
    }

    /// Mean of the point-to-polygon factor from `recv`'s quadrature points to `src`.
    pub fn kernel_mean(&self, recv: &Patch, src: &Patch) -> f64 {
        kernel_mean(recv, src, self.quadrature)
    }

    /// The weight of leaf `leaf` below an inner source in what a link sends to `recv`: how much the leaf
    /// sees the receiver, A_y F_{y→r} by the leaf's own Gauss points (one kernel evaluation).
    pub fn source_weight(&self, leaf: &Patch, recv: &Patch) -> f64 {
        leaf.area * kernel_mean(leaf, recv, self.quadrature)
    }

    /// Whether a form-factor link sends its source's radiosity (it is not a point-approximated cluster
    /// link), so that from an inner source its leaves are weighed ([`PatchKernel::source_weight`]).
    pub fn sends_source_radiosity(link: &Link) -> bool {
        !link.clustered
    }

    /// Mean, minimum and maximum of the point-to-polygon factor from `recv` to `src`: the mean over the
    /// quadrature points, the extremes over those points and the centroid (Gauss points lie symmetrically,
    /// so in symmetric configurations they alone would all agree).
    pub fn kernel_samples(&self, recv: &Patch, src: &Patch) -> (f64, f64, f64) {
        let mut mean = 0.0;
        let c = point_polygon(recv.centroid, recv.normal, &src.polygon);
        let (mut lo, mut hi) = (c, c);
        for (x, w) in receiver_points(&recv.polygon, self.quadrature) {
            let f = point_polygon(x, recv.normal, &src.polygon);
            mean += w * f;
            lo = lo.min(f);
            hi = hi.max(f);
        }
        (mean, lo, hi)
    }
}

impl PatchKernel<'_> {
    /// Whether two patches can exchange light: different faces, each partly in front of the other.
    pub fn patches_interact(recv: &Patch, src: &Patch) -> bool {
        recv.face != src.face
            && !facing_away(
                &recv.polygon,
                recv.centroid,
                recv.normal,
                &src.polygon,
                src.centroid,
                src.normal,
            )
    }

    /// The link between two patches: kernel quadrature, both form factors, sampled visibility.
    pub fn patch_link(&self, recv: &Patch, src: &Patch, src_id: u32) -> Option<Link> {
        if recv.face == src.face {
            return None;
        }
        let (mut f_rs, lo, mut hi) = self.kernel_samples(recv, src);
        if f_rs.is_nan() {
            return None;
        }
        let f_sr = self.kernel_mean(src, recv);
        if f_rs <= 0.0 {
            // Every receiver sample lies behind the source's plane, yet part of the receiver may still see
            // the source (a floor face whose Gauss points all lie on the far side of a block standing on
            // it): dropping the link would lose that light for good, since only links are refined. The
            // source's own samples see the receiver's front part, so F_rs comes by reciprocity,
            // A_r F_rs = A_s F_sr, and becomes the link's spread, so that the oracle refines the link
            // down to where the receiver's samples resolve the source's plane.
            if !(f_sr > 0.0) {
                return None;
            }
            f_rs = src.area * f_sr / recv.area;
            hi = hi.max(f_rs);
        }
        // The link and its reverse cast the same rays.
        let v = pair_visibility(self.accel, recv, src, self.visibility, self.seed);
        if v.is_nan() {
            return None;
        }
        let spread = if v < 1.0 { hi } else { hi - lo };
        Some(Link {
            source: src_id,
            coefficient: v * f_rs,
            f_recv: f_rs as f32,
            f_src: f_sr as f32,
            spread: spread as f32,
            visibility: v as f32,
            overlap: false,
            clustered: false,
        })
    }

    /// The coefficient of a patch link at `target`: the link's own at its receiver, else the kernel
    /// re-integrated over the target with the link's visibility, or, where that is partial and leaves cast
    /// their own rays, the target's visibility of the source.
    pub fn patch_coefficient(
        &self,
        target: &Patch,
        src: &Patch,
        link: &Link,
        at_receiver: bool,
    ) -> f64 {
        if at_receiver {
            return link.coefficient;
        }
        let v = link.visibility as f64;
        let v = match self.leaf_visibility {
            Some(sampling) if self.patch_own_visibility(link) => {
                // The rays a link between the leaf and the source would cast.
                let own = pair_visibility(self.accel, target, src, sampling, self.seed);
                if own.is_nan() { v } else { own }
            }
            _ => v,
        };
        v * self.kernel_mean(target, src)
    }

    /// Whether a patch link's coefficient at a target below its receiver measures the target's own
    /// visibility ([`crate::Transport::own_visibility`]): leaf visibility on, gathered at leaves, and the
    /// link partly visible. (A target that is the receiver itself takes the link's coefficient, whose rays
    /// start on it too.)
    pub fn patch_own_visibility(&self, link: &Link) -> bool {
        self.leaf_visibility.is_some()
            && self.gather == Gather::Leaf
            && !link.clustered
            && link.visibility > 0.0
            && link.visibility < 1.0
    }

    /// Where a patch link is gathered, by the [`Gather`] parameter.
    pub fn patch_gather_at(&self) -> GatherAt {
        match self.gather {
            Gather::Leaf => GatherAt::Leaves,
            Gather::Link => GatherAt::Receiver,
        }
    }
}

/// B = E + ρ H for a patch-like node.
pub fn reflect_scalar(emission: Rgb, reflectance: Rgb, h: Rgb, with_emission: bool) -> Rgb {
    let e = if with_emission { emission } else { Rgb::ZERO };
    e + reflectance * h
}

impl Transport<Patch> for PatchKernel<'_> {
    type Irradiance = Rgb;
    type Exitance = ();
    type Coefficient = f64;
    type Link = Link;
    type Flux = Rgb;

    fn may_interact(&self, recv: &Patch, src: &Patch) -> bool {
        Self::patches_interact(recv, src)
    }

    fn link(&self, recv: &Patch, _recv_id: u32, src: &Patch, src_id: u32) -> Option<Link> {
        self.patch_link(recv, src, src_id)
    }

    fn gather_at(&self, _recv: &Patch, _src: &Patch) -> GatherAt {
        self.patch_gather_at()
    }

    fn coefficient(&self, target: &Patch, src: &Patch, link: &Link, at_receiver: bool) -> f64 {
        self.patch_coefficient(target, src, link, at_receiver)
    }

    fn emit(
        &self,
        _view: &NodeView<'_, Patch>,
        b: &[Rgb],
        _x: &[()],
        _recv: u32,
        link: &Link,
    ) -> Rgb {
        b[link.source as usize]
    }

    fn weighs_source_leaves(&self, _recv: &Patch, link: &Link) -> bool {
        Self::sends_source_radiosity(link)
    }

    fn source_leaf_weight(&self, leaf: &Patch, recv: &Patch) -> Option<f64> {
        Some(self.source_weight(leaf, recv))
    }

    fn open_share(&self, leaf: &Patch) -> Option<f64> {
        let scene = self.open_shares?;
        let (o, _rays) = open_share(
            scene,
            self.accel,
            &leaf.polygon,
            leaf.face,
            self.seed,
            leaf.key(),
        );
        Some(o)
    }

    fn own_visibility(&self, _target: &Patch, _src: &Patch, link: &Link) -> bool {
        self.patch_own_visibility(link)
    }

    fn coefficient_weight(&self, c: &f64) -> f64 {
        *c
    }

    fn deliver(&self, h: &mut Rgb, c: &f64, flux: Rgb) {
        *h += *c * flux;
    }

    fn reflect(&self, leaf: &Patch, h: &Rgb, with_emission: bool) -> (Rgb, ()) {
        (
            reflect_scalar(leaf.emission, leaf.reflectance, *h, with_emission),
            (),
        )
    }

    fn uniform_response(&self, leaf: &Patch) -> (Rgb, ()) {
        (leaf.reflectance, ())
    }

    fn unit_response(&self, _leaf: &Patch) -> Option<(Rgb, ())> {
        Some((Rgb::ONE, ()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DVec3, dvec3};
    use radlab_scene::SceneBuilder;
    use radlab_testkit::{grid, material};

    /// A unit floor (y = 0, facing up) under a unit emitter (y = 1, facing down), and a panel a thousandth
    /// above the floor over its half x < 1/2, reaching far beyond it: the floor's half x < 1/2 sees nothing
    /// of the emitter, the other half all of it (but for rays that graze the panel's edge).
    fn half_shaded_floor() -> Scene {
        let mut b = SceneBuilder::new("half-shaded floor");
        let grey = material(&mut b, "grey", 0.5, 0.0);
        let lamp = material(&mut b, "lamp", 0.0, 1.0);
        grid(&mut b, DVec3::ZERO, DVec3::Z, DVec3::X, 1, grey);
        grid(&mut b, dvec3(0.0, 1.0, 0.0), DVec3::X, DVec3::Z, 1, lamp);
        grid(
            &mut b,
            dvec3(-50.0, 1e-3, -50.0),
            DVec3::Z * 100.0,
            DVec3::X * 50.5,
            1,
            grey,
        );
        b.build().expect("scene")
    }

    /// A link from the emitter to the whole floor is half visible; below it, a leaf of the floor's shaded half
    /// takes none of the emitter's light and a leaf of its lit half all of it, as each sees the emitter, and
    /// the leaves' coefficients add up to the link's. With the link's fraction (`link`) every leaf took half:
    /// the panel's shadow spread over the whole floor.
    #[test]
    fn a_leaf_below_a_partly_visible_link_measures_its_own_visibility() {
        let scene = half_shaded_floor();
        let accel = Accel::new(&scene);
        let (floor, lamp) = (Patch::root(&scene, 0), Patch::root(&scene, 1));
        let kernel = |leaf| {
            PatchKernel::new(&accel, 2, VisibilitySampling::Jittered4x4, 5, Gather::Leaf)
                .with_leaf_visibility(leaf)
        };
        let own = kernel(LeafVisibility::Jittered2x2);
        let link = own.patch_link(&floor, &lamp, 1).expect("link");
        assert!((link.visibility - 0.5).abs() < 0.2, "{}", link.visibility);
        let leaves: Vec<Patch> = floor.split().iter().flat_map(|c| c.split()).collect();
        assert_eq!(leaves.len(), 16);
        let (mut total, mut shaded, mut lit) = (0.0, 0, 0);
        for leaf in &leaves {
            let f = own.kernel_mean(leaf, &lamp);
            let c = own.patch_coefficient(leaf, &lamp, &link, false);
            let spread = kernel(LeafVisibility::Link).patch_coefficient(leaf, &lamp, &link, false);
            assert!((spread - link.visibility as f64 * f).abs() < 1e-12 * f);
            if leaf.centroid.x < 0.5 {
                assert_eq!(c, 0.0, "shaded leaf at {}", leaf.centroid);
                shaded += 1;
            } else {
                assert!(
                    (c - f).abs() < 1e-12 * f,
                    "lit leaf at {}: {c} of {f}",
                    leaf.centroid
                );
                lit += 1;
            }
            total += leaf.area * c;
        }
        assert_eq!((shaded, lit), (8, 8));
        // The leaves share what the link delivers, A_r V F_rs, up to its 16 rays' noise.
        let delivered = floor.area * link.coefficient;
        assert!(
            (total - delivered).abs() < 0.2 * delivered,
            "{total} {delivered}"
        );
    }
}

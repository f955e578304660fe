//! The transport contract, shown by two small transports that live outside the engine: a new node kind and
//! a new basis, each checked against closed forms.
//!
//! Both work on the inside of a sphere of unit area, its points addressed by an area coordinate t ∈ [0, 1)
//! (any measure-preserving map of the sphere onto [0, 1) will do; nothing below depends on which). From
//! any point of a sphere's inside, the form factor to a piece of it is that piece's share of the whole area
//! (Siegel & Howell, "Thermal Radiation Heat Transfer", the sphere's inside), F_{dA→s} = A_s / A, so the
//! radiosity equation B(t) = E(t) + ρ ∫ K(t, u) B(u) du has the kernel K = 1, and for uniform ρ its
//! solution is B(t) = E(t) + ρ Ē/(1 − ρ) with Ē the area mean of E: the furnace B = E/(1 − ρ) when E is
//! uniform.
//!
//! - A new node kind ([`Zone`], an interval of t) moved by the default constant basis ([`SphereInside`]: the
//!   form-factor [`Link`], an RGB flux, the default pull, error estimate and point evaluation).
//! - A new basis ([`LinearBasis`]): two coefficients per element (its mean and its slope in t, Legendre on
//!   the element), a link carrying a 2 × 2 tensor, irradiance pushed and radiosity pulled by the basis'
//!   two-scale relations, leaves evaluated at points. Its kernel K(t, u) = 1 + λ p(t) p(u), p(t) = √3 (2t − 1)
//!   (still a closed scene: ∫ K du = 1), has for E(t) = e₀ + e₁ p(t) the solution
//!   B(t) = e₀/(1 − ρ) + e₁ p(t)/(1 − ρλ), which the basis holds exactly and a constant basis cannot.

use glam::DVec3;
use radlab_hierarchical::{
    Bound, Engine, GatherAt, HierarchicalParams, LinearState, Link, LinkError, LinkPayload,
    NodeKind, NodeView, Oracle, SourceFlux, Transport,
};
use radlab_method::Step;
use radlab_scene::{FaceId, Rgb};

const SQRT3: f64 = 1.732_050_807_568_877_2;

/// The Legendre polynomial of degree one on [0, 1), orthonormal: ∫ p² = 1, ∫ p = 0.
fn p1(t: f64) -> f64 {
    SQRT3 * (2.0 * t - 1.0)
}

/// Emission over the sphere: `lamp` on t < `lamp_end`, plus `slope` p(t).
#[derive(Clone, Copy, Debug)]
struct Emission {
    rho: f64,
    lamp: f64,
    lamp_end: f64,
    slope: f64,
}

impl Emission {
    /// The area mean of the emission over [lo, hi).
    fn mean(&self, lo: f64, hi: f64) -> f64 {
        let lit = (hi.min(self.lamp_end) - lo).max(0.0);
        self.lamp * lit / (hi - lo) + self.slope * SQRT3 * (lo + hi - 1.0)
    }
}

/// A new node kind: the zone [lo, hi) of the sphere's area coordinate, split at its middle.
#[derive(Clone, Copy, Debug)]
struct Zone {
    lo: f64,
    hi: f64,
    root: usize,
    emission: Emission,
}

impl NodeKind for Zone {
    fn area(&self) -> f64 {
        self.hi - self.lo
    }
    fn bound(&self) -> Bound {
        Bound {
            centre: DVec3::new(0.5 * (self.lo + self.hi), 0.0, 0.0),
            radius: 0.5 * (self.hi - self.lo),
        }
    }
    fn normal(&self) -> Option<DVec3> {
        None
    }
    fn projected_area(&self, _dir: DVec3) -> f64 {
        0.25 * self.area()
    }
    fn reflectance(&self) -> Rgb {
        Rgb::splat(self.emission.rho)
    }
    fn emission(&self) -> Rgb {
        Rgb::splat(self.emission.mean(self.lo, self.hi))
    }
    fn can_split(&self, min_size: f64) -> bool {
        self.area() >= 2.0 * min_size
    }
    fn split(&self) -> Vec<Self> {
        let mid = 0.5 * (self.lo + self.hi);
        vec![Zone { hi: mid, ..*self }, Zone { lo: mid, ..*self }]
    }
    fn face(&self) -> Option<FaceId> {
        Some(self.root)
    }
    fn key(&self) -> u64 {
        self.lo.to_bits() ^ self.hi.to_bits().rotate_left(32)
    }
}

/// An engine over `roots` equal zones of the sphere, each root linked to itself (a zone of a sphere's inside
/// sees itself; the schedule links distinct roots), stepped until it converges.
fn solve<T: Transport<Zone>>(
    transport: T,
    emission: Emission,
    roots: usize,
    params: HierarchicalParams,
) -> Engine<Zone, T> {
    let zones = (0..roots)
        .map(|r| Zone {
            lo: r as f64 / roots as f64,
            hi: (r + 1) as f64 / roots as f64,
            root: r,
            emission,
        })
        .collect();
    let mut engine = Engine::new(zones, transport, params, 1.0 / 1024.0).expect("engine");
    for r in 0..roots as u32 {
        assert!(engine.add_link(r, r).expect("self-link"));
    }
    for _ in 0..10_000 {
        if engine.step().expect("step") != Step::Continue {
            return engine;
        }
    }
    panic!("no convergence in 10000 steps");
}

fn params(epsilon: f64, oracle: Oracle) -> HierarchicalParams {
    HierarchicalParams {
        epsilon,
        oracle,
        tolerance: 1e-9,
        ..HierarchicalParams::default()
    }
}

/// The leaves of `engine`, by id.
fn leaves<T: Transport<Zone>>(engine: &Engine<Zone, T>) -> Vec<u32> {
    (0..engine.nodes().len() as u32)
        .filter(|&i| engine.is_leaf(i))
        .collect()
}

/// The constant basis on a new node kind: every hook but the physics at its default.
#[derive(Debug)]
struct SphereInside;

impl Transport<Zone> for SphereInside {
    type Irradiance = Rgb;
    type Exitance = ();
    type Coefficient = f64;
    type Link = Link;
    type Flux = Rgb;

    fn may_interact(&self, _recv: &Zone, _src: &Zone) -> bool {
        true
    }

    /// F_rs = A_s / A (A = 1), unoccluded.
    fn link(&self, recv: &Zone, _recv_id: u32, src: &Zone, src_id: u32) -> Option<Link> {
        Some(Link {
            source: src_id,
            coefficient: src.area(),
            f_recv: src.area() as f32,
            f_src: recv.area() as f32,
            spread: 0.0,
            visibility: 1.0,
            overlap: false,
            clustered: false,
        })
    }

    fn gather_at(&self, _recv: &Zone, _src: &Zone) -> GatherAt {
        GatherAt::Receiver
    }

    fn coefficient(&self, _target: &Zone, _src: &Zone, link: &Link, _at_receiver: bool) -> f64 {
        link.coefficient
    }

    fn emit(&self, _view: &NodeView<'_, Zone>, b: &[Rgb], _x: &[()], _recv: u32, l: &Link) -> Rgb {
        b[l.source as usize]
    }

    fn deliver(&self, h: &mut Rgb, c: &f64, flux: Rgb) {
        *h += *c * flux;
    }

    fn reflect(&self, leaf: &Zone, h: &Rgb, with_emission: bool) -> (Rgb, ()) {
        let e = if with_emission {
            leaf.emission()
        } else {
            Rgb::ZERO
        };
        (e + leaf.reflectance() * *h, ())
    }

    fn uniform_response(&self, leaf: &Zone) -> (Rgb, ()) {
        (leaf.reflectance(), ())
    }
}

/// A new node kind through the default hooks: the F oracle refines the sphere's two halves (links at
/// mixed levels), and every leaf's radiosity is the closed form E_leaf + ρ Ē/(1 − ρ) — the furnace
/// E/(1 − ρ) when the whole sphere emits — with power balanced, Σ A (B − E) = ρ Σ A B.
#[test]
fn a_new_node_kind_solves_the_sphere_in_closed_form() {
    for (lamp_end, rho) in [(0.25, 0.8), (1.0, 0.9)] {
        let emission = Emission {
            rho,
            lamp: 1.0,
            lamp_end,
            slope: 0.0,
        };
        let engine = solve(SphereInside, emission, 2, params(0.05, Oracle::F));
        let leaves = leaves(&engine);
        // The oracle refined: no link's larger form factor above ε, except at the minimum size.
        assert!(leaves.len() >= 32, "{} leaves", leaves.len());
        for i in 0..engine.nodes().len() as u32 {
            for l in engine.links_of(i) {
                let e = l.error(Oracle::F, 1.0).estimate;
                assert!(e <= 0.05, "a link kept at F = {e}");
            }
        }
        let mean_b = lamp_end / (1.0 - rho);
        let (mut emitted, mut sent) = (0.0, 0.0);
        for &i in &leaves {
            let zone = &engine.nodes()[i as usize];
            let b = engine.radiosity()[i as usize];
            let exact = zone.emission().x + rho * mean_b;
            assert!(
                (b - Rgb::splat(exact)).abs().max_element() <= 1e-9 * exact,
                "zone [{}, {}): B = {b}, closed form {exact}",
                zone.lo,
                zone.hi
            );
            // The default point evaluation is the leaf's constant.
            let t = 0.5 * (zone.lo + zone.hi);
            assert_eq!(engine.radiosity_at_leaf(i, DVec3::new(t, 0.0, 0.0)), b);
            emitted += zone.area() * zone.emission().x;
            sent += zone.area() * b.x;
        }
        assert!((sent - emitted - rho * sent).abs() <= 1e-9 * emitted);
        // Inner nodes hold their children's area mean (the default pull).
        for &r in engine.roots() {
            let kids: Vec<u32> = engine.children(r).collect();
            let mean = kids
                .iter()
                .map(|&c| engine.nodes()[c as usize].area() * engine.radiosity()[c as usize].x)
                .sum::<f64>()
                / engine.nodes()[r as usize].area();
            assert!((engine.radiosity()[r as usize].x - mean).abs() <= 1e-12 * mean);
        }
    }
}

/// Per channel, the two coefficients of the linear basis on an element [a, b): f(t) = c₀ + c₁ ψ(t),
/// ψ(t) = √3 (2 (t − a)/(b − a) − 1), orthonormal under the element's mean.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Linear([Rgb; 2]);

impl LinearState for Linear {
    fn add_scaled(&mut self, c: Rgb, x: &Self) {
        self.0[0] += c * x.0[0];
        self.0[1] += c * x.0[1];
    }
}

/// A source of uniform radiosity B sends (B, 0).
impl From<Rgb> for Linear {
    fn from(b: Rgb) -> Self {
        Linear([b, Rgb::ZERO])
    }
}

impl SourceFlux for Linear {
    fn scaled(self, s: f64) -> Self {
        Linear([self.0[0] * s, self.0[1] * s])
    }
}

/// The link of the linear basis: K_ij = (1/|r|) ∫_r ∫_s K(t, u) ψ_i^r(t) ψ_j^s(u) du dt, the receiver's
/// coefficient i per unit source coefficient j. A basis of M functions in each of two directions holds M²
/// coefficients per element and M⁴ per link; this one, linear in one direction, holds 2 and 4.
#[derive(Clone, Debug)]
struct TensorLink {
    source: u32,
    k: [[f64; 2]; 2],
    /// The larger of the two ends' areas: the error estimate.
    size: f64,
}

impl LinkPayload for TensorLink {
    fn source(&self) -> u32 {
        self.source
    }
    /// The larger end's area, whatever the oracle: split one end at a time (links at mixed levels).
    fn error(&self, _oracle: Oracle, _weight: f64) -> LinkError {
        LinkError {
            estimate: self.size,
            each_end: None,
        }
    }
}

/// The moments of p over element [a, b): its mean, and its coefficient on ψ.
fn p1_moments(z: &Zone) -> [f64; 2] {
    [SQRT3 * (z.lo + z.hi - 1.0), z.hi - z.lo]
}

/// A new basis: piecewise linear in t, kernel 1 + λ p(t) p(u).
#[derive(Debug)]
struct LinearBasis {
    lambda: f64,
}

impl Transport<Zone> for LinearBasis {
    type Irradiance = Linear;
    /// The slope coefficient c₁ (the engine keeps the mean c₀ as the radiosity).
    type Exitance = Rgb;
    type Coefficient = [[f64; 2]; 2];
    type Link = TensorLink;
    type Flux = Linear;

    fn may_interact(&self, _recv: &Zone, _src: &Zone) -> bool {
        true
    }

    /// K_ij = |s| (δ_i0 δ_j0 + λ m_i^r m_j^s), m the moments of p ([`p1_moments`]): exact at any level.
    fn link(&self, recv: &Zone, _recv_id: u32, src: &Zone, src_id: u32) -> Option<TensorLink> {
        let (mr, ms) = (p1_moments(recv), p1_moments(src));
        let mut k = [[0.0; 2]; 2];
        for (i, row) in k.iter_mut().enumerate() {
            for (j, kij) in row.iter_mut().enumerate() {
                let delta = if i == 0 && j == 0 { 1.0 } else { 0.0 };
                *kij = src.area() * (delta + self.lambda * mr[i] * ms[j]);
            }
        }
        Some(TensorLink {
            source: src_id,
            k,
            size: recv.area().max(src.area()),
        })
    }

    fn gather_at(&self, _recv: &Zone, _src: &Zone) -> GatherAt {
        GatherAt::Receiver
    }

    fn coefficient(
        &self,
        _target: &Zone,
        _src: &Zone,
        link: &TensorLink,
        _at_receiver: bool,
    ) -> [[f64; 2]; 2] {
        link.k
    }

    fn emit(
        &self,
        _view: &NodeView<'_, Zone>,
        b: &[Rgb],
        x: &[Rgb],
        _recv: u32,
        l: &TensorLink,
    ) -> Linear {
        Linear([b[l.source as usize], x[l.source as usize]])
    }

    fn deliver(&self, h: &mut Linear, c: &[[f64; 2]; 2], flux: Linear) {
        for (hi, ci) in h.0.iter_mut().zip(c) {
            *hi += ci[0] * flux.0[0] + ci[1] * flux.0[1];
        }
    }

    /// On the lower half ψ_parent = ψ_child/2 − √3/2, on the upper half ψ_child/2 + √3/2.
    fn push(&self, parent: &Zone, child: &Zone, h: &Linear) -> Linear {
        let side = if child.lo == parent.lo { -1.0 } else { 1.0 };
        Linear([h.0[0] + side * 0.5 * SQRT3 * h.0[1], 0.5 * h.0[1]])
    }

    fn reflect(&self, leaf: &Zone, h: &Linear, with_emission: bool) -> (Rgb, Rgb) {
        let rho = leaf.reflectance();
        let (e0, e1) = if with_emission {
            let slope = leaf.emission.slope * (leaf.hi - leaf.lo);
            (leaf.emission(), Rgb::splat(slope))
        } else {
            (Rgb::ZERO, Rgb::ZERO)
        };
        (e0 + rho * h.0[0], e1 + rho * h.0[1])
    }

    /// The two-scale relation of the linear basis (children [lower, upper] halves).
    fn pull(&self, parent: &Zone, children: &[Zone], b: &[Rgb], x: &[Rgb]) -> (Rgb, Rgb) {
        let mean = (children[0].area() * b[0] + children[1].area() * b[1]) / parent.area();
        let slope = 0.25 * (x[0] + x[1]) + 0.25 * SQRT3 * (b[1] - b[0]);
        (mean, slope)
    }

    fn radiosity_at(&self, leaf: &Zone, b: Rgb, x: &Rgb, point: DVec3) -> Rgb {
        let psi = SQRT3 * (2.0 * (point.x - leaf.lo) / (leaf.hi - leaf.lo) - 1.0);
        b + *x * psi
    }

    fn uniform_response(&self, leaf: &Zone) -> (Rgb, Rgb) {
        (leaf.reflectance(), Rgb::ZERO)
    }
}

/// A new basis through the hooks: at two thresholds (links at several levels, irradiance pushed and
/// radiosity pulled across them) the leaves evaluated at points give the closed form
/// B(t) = e₀/(1 − ρ) + e₁ p(t)/(1 − ρλ), whose slope no constant element holds; inner nodes pulled by the
/// two-scale relation hold the same linear function's coefficients.
#[test]
fn a_new_basis_holds_the_linear_solution_exactly() {
    let (rho, lambda) = (0.7, 0.3);
    let emission = Emission {
        rho,
        lamp: 1.0,
        lamp_end: 1.0,
        slope: 0.5,
    };
    let exact = |t: f64| 1.0 / (1.0 - rho) + 0.5 * p1(t) / (1.0 - rho * lambda);
    for epsilon in [0.3, 0.04] {
        let engine = solve(
            LinearBasis { lambda },
            emission,
            1,
            params(epsilon, Oracle::F),
        );
        let leaves = leaves(&engine);
        assert!(
            leaves.len() as f64 >= 1.0 / epsilon,
            "{} leaves",
            leaves.len()
        );
        let mut widest_step: f64 = 0.0;
        for &i in &leaves {
            let zone = engine.nodes()[i as usize];
            for f in [0.0, 0.3, 0.999] {
                let t = zone.lo + f * (zone.hi - zone.lo);
                let b = engine.radiosity_at_leaf(i, DVec3::new(t, 0.0, 0.0));
                assert!(
                    (b - Rgb::splat(exact(t))).abs().max_element() <= 1e-9,
                    "ε = {epsilon}, t = {t}: B = {b}, closed form {}",
                    exact(t)
                );
                widest_step = widest_step.max((b.x - engine.radiosity()[i as usize].x).abs());
            }
        }
        // A constant element would be off by this much at its ends.
        assert!(widest_step > 1e-3, "{widest_step}");
        // Every node, inner ones included, holds the solution's coefficients on its own element.
        for (i, zone) in engine.nodes().iter().enumerate() {
            let mid = 0.5 * (zone.lo + zone.hi);
            let mean = engine.radiosity()[i].x;
            let slope = engine.exitance()[i].x;
            assert!((mean - exact(mid)).abs() <= 1e-9, "node {i}: mean {mean}");
            let want = 0.5 * (zone.hi - zone.lo) / (1.0 - rho * lambda);
            assert!(
                (slope - want).abs() <= 1e-9,
                "node {i}: slope {slope}, want {want}"
            );
        }
    }
}

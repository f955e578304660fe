//! What a face-cluster node gathers: an irradiance vector e per channel (Willmott, Heckbert & Garland 1999),
//! an isotropic irradiance s per channel, and the traced self-exchange t (isotropic too, but handed down by
//! where it lands, [`crate::self_exchange`]), so that a face of unit normal n below the node receives
//!
//!   I(n) = max(0, n·e + s + t),
//!
//! with e taken at the face's centroid when the node also holds e's Jacobian
//! ([`crate::irradiance_gradient`]).
//!
//! A link brings irradiance g travelling along unit u, and a face of normal n takes g max(0, n·u). Where every
//! face of the receiver faces the link (n·u ≥ 0 over the node's normal cone) that is g n·u: the link adds
//! g u to e, the exact vector transfer. Where the cone straddles
//! the link, some faces see it from behind and n·u would count them negatively; summed over links from many
//! directions those negative parts cancel what other links bring, so that a closed part linked whole
//! gathered nothing from an even surrounding. Such a link instead adds the least-squares line a + b x of the
//! clamped cosine max(0, x) over the spread of the receiver's cosines x = n_i·u: b g u to e and a g to s.
//! The spread is a uniform range with the faces' area-weighted mean and variance of x, from the node's sums
//! Σ A_i n_i and Σ A_i n_i n_iᵀ, kept within the range [cos(α + θ), cos(α − θ)] its normal cone allows
//! ([`CosineFit::of_node`]: the cone's range alone spreads the cosines evenly between its bounds, and
//! delivered too much). Over the whole range [−1, 1] that line is 1/4 + x/2, the clamped cosine's
//! projection on the constant and linear spherical harmonics (Ramamoorthi & Hanrahan 2001): exact on
//! average over an even surrounding (a closed part in a furnace receives a quarter of g per unit area,
//! Cauchy's mean projected area), and within g/4 at any face for one link. The same line gives what a
//! curved source with faces turned away sends toward d: Σ B_i A_i max(0, n_i·d) ≈ a Σ B_i A_i + b p·d, p = Σ B_i A_i n_i.

use glam::{DMat3, DVec3};
use radlab_hierarchical::LinearState;
use radlab_scene::Rgb;

/// A node's gathered irradiance: the vector part and the isotropic part, per channel, and the vector part's
/// Jacobian over the node ([`crate::irradiance_gradient`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClampedIrradiance {
    /// Irradiance vector e per channel, at the node's centroid.
    pub vector: [DVec3; 3],
    /// Isotropic irradiance s per channel: a face of any orientation receives s besides n·e.
    pub isotropic: Rgb,
    /// Traced self-exchange t per channel: isotropic like s, but spread over the node's parts by how much of
    /// their view their own mesh fills ([`crate::self_exchange`]) as it is pushed down.
    pub traced: Rgb,
    /// The part of t that this node's sibling sent it (its traced exchange link), not yet handed down: push
    /// spreads it by where the sibling's own rays landed, then adds it to `outside`.
    pub from_sibling: Rgb,
    /// The part of t that the siblings of this node's ancestors sent them, handed down: push spreads it by
    /// where the trace's rays from beyond the node's parent landed, near the boundary they crossed rather
    /// than over the node's own valleys.
    pub outside: Rgb,
    /// ∂e/∂y per channel: at a point y of the node, e(y) = e + J (y − c), c its centroid.
    pub gradient: [DMat3; 3],
}

impl Default for ClampedIrradiance {
    fn default() -> Self {
        Self::ZERO
    }
}

impl ClampedIrradiance {
    /// Nothing gathered.
    pub const ZERO: Self = Self {
        vector: [DVec3::ZERO; 3],
        isotropic: Rgb::ZERO,
        traced: Rgb::ZERO,
        from_sibling: Rgb::ZERO,
        outside: Rgb::ZERO,
        gradient: [DMat3::ZERO; 3],
    };

    /// All parts times `c`.
    pub fn scaled(&self, c: f64) -> Self {
        let mut out = Self::ZERO;
        out.add_scaled(Rgb::splat(c), self);
        out
    }

    /// The same field seen from a point `offset` away from the centroid: e + J offset there, J unchanged.
    pub fn moved(&self, offset: DVec3) -> Self {
        let mut out = *self;
        for k in 0..3 {
            out.vector[k] += self.gradient[k] * offset;
        }
        out
    }

    /// The unclamped irradiance n·e + s + t of channel `k` at the centroid of a face with unit normal `n`.
    pub fn linear(&self, n: DVec3, k: usize) -> f64 {
        n.dot(self.vector[k])
            + self.isotropic[k]
            + self.traced[k]
            + self.from_sibling[k]
            + self.outside[k]
    }

    /// The irradiance I(n) = max(0, n·e + s + t) at the centroid of a face with unit normal `n`, per channel.
    pub fn at(&self, n: DVec3) -> Rgb {
        Rgb::new(
            self.linear(n, 0).max(0.0),
            self.linear(n, 1).max(0.0),
            self.linear(n, 2).max(0.0),
        )
    }

    /// The isotropic parts s + t.
    pub fn isotropic_total(&self) -> Rgb {
        self.isotropic + self.traced + self.from_sibling + self.outside
    }
}

impl radlab_answer::irradiance_gouraud::LinearIrradiance for ClampedIrradiance {
    fn linear(&self, n: DVec3, k: usize) -> f64 {
        ClampedIrradiance::linear(self, n, k)
    }

    fn vector(&self, k: usize) -> DVec3 {
        self.vector[k]
    }
}

impl LinearState for ClampedIrradiance {
    fn add_scaled(&mut self, c: Rgb, x: &Self) {
        self.vector.add_scaled(c, &x.vector);
        self.isotropic += c * x.isotropic;
        self.traced += c * x.traced;
        self.from_sibling += c * x.from_sibling;
        self.outside += c * x.outside;
        for k in 0..3 {
            self.gradient[k] += x.gradient[k] * c[k];
        }
    }
}

/// The least-squares line a + b x of max(0, x) over x uniform in a range of cosines.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CosineFit {
    /// Offset a.
    pub offset: f64,
    /// Slope b.
    pub slope: f64,
}

impl CosineFit {
    /// Exact where every cosine is non-negative: max(0, x) = x.
    pub const FACING: Self = Self {
        offset: 0.0,
        slope: 1.0,
    };

    /// The fit over [lo, hi] (clamped to [−1, 1]): x itself when lo ≥ 0, zero when hi ≤ 0, otherwise the
    /// solution of the normal equations [L, m₁; m₁, m₂] (a, b) = (h²/2, h³/3) with L = h − l,
    /// m₁ = (h² − l²)/2, m₂ = (h³ − l³)/3.
    pub fn over(lo: f64, hi: f64) -> Self {
        let (l, h) = (lo.clamp(-1.0, 1.0), hi.clamp(-1.0, 1.0));
        if l >= 0.0 {
            return Self::FACING;
        }
        if h <= 0.0 || h <= l {
            return Self {
                offset: 0.0,
                slope: 0.0,
            };
        }
        let (m0, m1, m2) = (h - l, 0.5 * (h * h - l * l), (h * h * h - l * l * l) / 3.0);
        let (f0, f1) = (0.5 * h * h, h * h * h / 3.0);
        let det = m0 * m2 - m1 * m1;
        Self {
            offset: (f0 * m2 - f1 * m1) / det,
            slope: (m0 * f1 - m1 * f0) / det,
        }
    }

    /// The fit for the faces of tree node `node` toward unit `u`: exact ([`Self::FACING`]) when its normal
    /// cone (half-angle θ at angle α from u) faces u whole, α + θ ≤ 90°, or is flat; otherwise the fit over
    /// the uniform range with the area-weighted mean and variance of the node's cosines x = n_i·u,
    /// m = (Σ A_i n_i)·u / A and v = uᵀ(Σ A_i n_i n_iᵀ)u / A − m², that is [m − √3 √v, m + √3 √v], within
    /// the range [cos(α + θ), cos(α − θ)] the cone allows. The cone's range alone spreads the cosines evenly
    /// between its bounds, and a face cluster's cosines are not spread so: on the 10⁵-face bumpy sphere at
    /// ε = 1e-5 its straddling links delivered 13.7% more than the mean clamped cosine of their receivers'
    /// faces, against 0.02% less with the moments (6,390 links, measured once by a probe over the solve's
    /// links); those links made the room's rows sum to 1.014 over the sphere. The test
    /// `straddled_clusters_fit_their_faces_clamped_cosines` checks the fit against the faces over random
    /// straddling directions. Reads no face: the sums are the node's.
    pub fn of_node(node: &crate::Node, u: DVec3) -> Self {
        let theta = node.cone.half_angle;
        if theta < crate::vector_transport::FLAT_CONE {
            return Self::FACING;
        }
        let alpha = crate::bounds::angle_between(node.cone.axis, u);
        if alpha + theta <= std::f64::consts::FRAC_PI_2 {
            return Self::FACING;
        }
        let (cone_lo, cone_hi) = (
            (alpha + theta).min(std::f64::consts::PI).cos(),
            (alpha - theta).max(0.0).cos(),
        );
        if !(node.area > 0.0) {
            return Self::over(cone_lo, cone_hi);
        }
        let m = node.vector_area.dot(u) / node.area;
        let spread = 3f64.sqrt()
            * (node.normal_moment.quadratic(u) / node.area - m * m)
                .max(0.0)
                .sqrt();
        let (lo, hi) = ((m - spread).max(cone_lo), (m + spread).min(cone_hi));
        if lo <= hi {
            Self::over(lo, hi)
        } else {
            // Rounding put the mean outside the cone's range: the nearer bound.
            let x = m.clamp(cone_lo, cone_hi);
            Self::over(x, x)
        }
    }

    /// What a link bringing irradiance `g` along unit `u` adds to e and s, per unit flux.
    pub fn coefficient(self, u: DVec3, g: f64) -> LinkCoefficient {
        LinkCoefficient {
            vector: u * (self.slope * g),
            isotropic: self.offset * g,
            traced: 0.0,
            from_sibling: 0.0,
            gradient: DMat3::ZERO,
        }
    }

    /// What a source with power vectors `p` (Σ B_i A_i n_i) and total exitance `w` (Σ B_i A_i) sends toward
    /// unit `d`, per channel: max(0, a w + b p·d).
    pub fn sent(self, p: &[DVec3; 3], w: Rgb, d: DVec3) -> Rgb {
        let f = |k: usize| (self.offset * w[k] + self.slope * p[k].dot(d)).max(0.0);
        Rgb::new(f(0), f(1), f(2))
    }
}

/// A link's coefficient at its gather target, per unit flux: what it adds to e, to s and to e's Jacobian.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkCoefficient {
    /// Added to e per unit flux.
    pub vector: DVec3,
    /// Added to s per unit flux.
    pub isotropic: f64,
    /// Added to t per unit flux.
    pub traced: f64,
    /// Added to the sibling's part of t per unit flux.
    pub from_sibling: f64,
    /// Added to ∂e/∂y per unit flux (zero for a link that brings one irradiance to the whole target).
    pub gradient: DMat3,
}

impl Default for LinkCoefficient {
    fn default() -> Self {
        Self::vector(DVec3::ZERO)
    }
}

impl LinkCoefficient {
    /// A transfer every face of the target takes as n·v.
    pub fn vector(v: DVec3) -> Self {
        Self {
            vector: v,
            isotropic: 0.0,
            traced: 0.0,
            from_sibling: 0.0,
            gradient: DMat3::ZERO,
        }
    }

    /// A transfer every face of the target takes whole, whatever its orientation.
    pub fn isotropic(s: f64) -> Self {
        Self {
            vector: DVec3::ZERO,
            isotropic: s,
            traced: 0.0,
            from_sibling: 0.0,
            gradient: DMat3::ZERO,
        }
    }

    /// A traced self-exchange every face of the target takes whole, spread by its parts' view of their mesh.
    pub fn traced(t: f64) -> Self {
        Self {
            traced: t,
            ..Self::vector(DVec3::ZERO)
        }
    }

    /// The traced exchange from the target's sibling, spread by where that sibling's rays landed.
    pub fn from_sibling(t: f64) -> Self {
        Self {
            from_sibling: t,
            ..Self::vector(DVec3::ZERO)
        }
    }

    /// The same with the vector part's Jacobian `j` over the target.
    pub fn with_gradient(self, j: DMat3) -> Self {
        Self {
            gradient: j,
            ..self
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Over the whole range the fit is 1/4 + x/2 (the spherical-harmonic projection); over a range of
    /// non-negative cosines it is x.
    #[test]
    fn fit_over_the_whole_range_is_the_harmonic_projection() {
        let f = CosineFit::over(-1.0, 1.0);
        assert!(
            (f.offset - 0.25).abs() < 1e-15 && (f.slope - 0.5).abs() < 1e-15,
            "{f:?}"
        );
        assert_eq!(CosineFit::over(0.2, 0.9), CosineFit::FACING);
        assert_eq!(CosineFit::over(-0.9, -0.1).slope, 0.0);
    }

    /// The fit is the least-squares line: its residual is orthogonal to 1 and x over the range (midpoint
    /// quadrature with 200,000 cells, whose error is far below the 1e-9 asked).
    #[test]
    fn fit_residual_is_orthogonal_to_the_line() {
        for (lo, hi) in [(-1.0, 1.0), (-0.3, 0.8), (-0.9, 0.1), (-0.05, 1.0)] {
            let f = CosineFit::over(lo, hi);
            let n = 200_000;
            let dx = (hi - lo) / n as f64;
            let (mut r0, mut r1) = (0.0, 0.0);
            for i in 0..n {
                let x: f64 = lo + (i as f64 + 0.5) * dx;
                let r = x.max(0.0) - f.offset - f.slope * x;
                r0 += r * dx;
                r1 += r * x * dx;
            }
            assert!(r0.abs() < 1e-9 && r1.abs() < 1e-9, "{lo} {hi}: {r0} {r1}");
        }
    }

    /// The six axis directions.
    const AXES: [DVec3; 6] = [
        DVec3::X,
        DVec3::NEG_X,
        DVec3::Y,
        DVec3::NEG_Y,
        DVec3::Z,
        DVec3::NEG_Z,
    ];

    /// An even surrounding: links of equal g = 1 from the six axis directions and the eight cube diagonals,
    /// each delivered with the whole-range fit. Every face of a cube then gets 14/4 = 3.5 (the vector parts
    /// cancel, the isotropic parts add), against its exact clamped sum 1 + 4/√3 = 3.31, within the fit's bound
    /// of 1/4 per link; the mean of max(0, n·u) over all orientations n is 1/4 per link as well, so a closed
    /// part absorbs what it should. The vector form alone gives every face zero.
    #[test]
    fn an_even_surrounding_reaches_a_closed_part() {
        let mut dirs = AXES.to_vec();
        for k in 0..8 {
            let s = |b: usize| if k & (1 << b) == 0 { 1.0 } else { -1.0 };
            dirs.push(DVec3::new(s(0), s(1), s(2)).normalize());
        }
        let fit = CosineFit::over(-1.0, 1.0);
        let mut h = ClampedIrradiance::ZERO;
        for &u in &dirs {
            let c = fit.coefficient(u, 1.0);
            h.add_scaled(
                Rgb::ONE,
                &ClampedIrradiance {
                    vector: [c.vector; 3],
                    isotropic: Rgb::splat(c.isotropic),
                    traced: Rgb::splat(c.traced),
                    from_sibling: Rgb::splat(c.from_sibling),
                    outside: Rgb::ZERO,
                    gradient: [c.gradient; 3],
                },
            );
        }
        for n in AXES {
            let exact: f64 = dirs.iter().map(|u| n.dot(*u).max(0.0)).sum();
            assert!((exact - (1.0 + 4.0 / 3f64.sqrt())).abs() < 1e-12, "{exact}");
            let got = h.at(n).x;
            assert!((got - 3.5).abs() < 1e-12, "{n}: {got}");
            assert!((got - exact).abs() <= 0.25 * dirs.len() as f64);
        }
    }
}

//! The transfer tensor of a link between two quadtree elements (Gortler, Schröder, Cohen & Hanrahan 1993):
//! for receiver R, source S and the kernel G(x, y) = cos θ_x cos θ_y V(x, y) / (π r²),
//!
//!   T_αβ = (1/A_R) ∫_R ∫_S φ_α(x) G(x, y) φ_β(y) dy dx,
//!
//! the receiver's coefficient α per unit source coefficient β (average-normalised functions,
//! [`crate::basis`]), so that a gather adds ρ_R Σ_β T_αβ b^S_β to the receiver's irradiance coefficients and
//! T_00 is the form factor F_RS. It is computed by product Gauss quadrature on both elements,
//!
//!   T_αβ ≈ Σ_k w_k φ_α(x_k) g_β(x_k),   g_β(x) = ∫_S G(x, y) φ_β(y) dy,
//!
//! where the point-to-element value g_β at each receiver node is the exact unoccluded point-to-polygon factor
//! F(x → S) (Lambert's contour integral; Baum, Rushmeier & Winget 1989) times the source rule's
//! kernel-weighted mean of V φ_β: g_β(x) = F(x → S) Σ_l w_l G_l V_l φ_β(y_l) / Σ_l w_l G_l. For β = 0 and no
//! occluder that is F(x → S) exactly, so the receiver rows of the mean sum to the exact form-factor sums (one
//! in a closed scene) whatever the distance, which the furnace needs; the higher moments and the visibility
//! come from the source rule (Wallace, Elmquist & Haines 1989 split kernel and visibility alike). Reciprocity,
//! A_R T^{R←S}_αβ = A_S T^{S←R}_βα, then holds to the source rule's error.
//!
//! Visibility is either evaluated for every pair of quadrature nodes (one ray each: `per-pair`, as RenderPark
//! and Cuny, Alonso & Holzschuch 2000 do) or as one kernel-weighted fraction of 16 jittered rays scaling the
//! whole unoccluded tensor (`per-link`, as the constant basis does: with higher orders this gives the blocky
//! shadows Willmott & Heckbert 1997 reported).
//!
//! The link also keeps Bekaert & Willems 1996's error estimate: at each receiver node the difference between
//! what the link reproduces there, Σ_α T_αβ φ_α(x_k), and the point-to-element value g_β(x_k), per source
//! function β: e_β = max_k |Σ_α T_αβ φ_α(x_k) − g_β(x_k)|. It costs nothing beyond the tensor.

use glam::DVec3;
use radlab_hierarchical::Patch;
use radlab_kernels::form_factor::{
    VisibilitySampling, pair_kernel, point_polygon, receiver_points, visibility_fraction,
};
use radlab_visibility::{Accel, Segment};

use crate::basis::Basis;

/// How visibility enters a link's tensor.
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
pub enum Visibility {
    /// One ray per pair of quadrature nodes (n⁴ rays for n² nodes per element): shadows resolved within a
    /// link by the basis (Cuny, Alonso & Holzschuch 2000).
    #[default]
    PerPair,
    /// One kernel-weighted visibility fraction from 4 × 4 jittered rays scaling the whole unoccluded tensor
    /// (Willmott & Heckbert 1997's higher orders: blocky shadows).
    PerLink,
}

/// Quadrature nodes of one element with the basis functions there.
#[derive(Clone, Debug)]
pub struct ElementRule<const K: usize> {
    /// Points, weights (summing to 1) and the K functions at each point (zero beyond the first on an
    /// element that holds the mean only).
    pub nodes: Vec<(DVec3, f64, [f64; K])>,
}

/// Largest relative twist |v0 − v1 + v2 − v3| / longest edge of a quad that carries the tensor basis.
pub const MAX_TWIST: f64 = 0.05;

/// Whether an element carries the whole tensor basis: a quad whose bilinear map is within [`MAX_TWIST`] of
/// affine. On a parallelogram (constant Jacobian) the tensor functions are orthonormal under the area mean;
/// on a slightly twisted quad (the published Cornell box's floor: 0.6%) the mean coefficient stays the
/// exact area mean (the rule carries the Jacobian) and the others are orthonormal to O(twist). Triangles and
/// other quads hold their mean only (constant elements): see the crate documentation.
pub fn holds_tensor(p: &Patch) -> bool {
    if p.polygon.is_triangle() {
        return false;
    }
    let v = p.polygon.vertices();
    let twist = (v[0] - v[1] + v[2] - v[3]).length();
    twist <= MAX_TWIST * p.max_edge
}

impl<const K: usize> ElementRule<K> {
    /// The rule of `patch` under `basis` with `points` Gauss points per cell and side: the product rule in
    /// the element's (s, t) where it holds the tensor basis, else radlab-kernels' receiver rule with φ_0 = 1
    /// only.
    pub fn new(patch: &Patch, basis: Basis, points: usize) -> Self {
        debug_assert_eq!(K, basis.len());
        if holds_tensor(patch) {
            let r = basis.rule1(points);
            let v = patch.polygon.vertices();
            let mut nodes = Vec::with_capacity(r.len() * r.len());
            let mut total = 0.0;
            for &(t, wt) in &r {
                for &(s, ws) in &r {
                    let mut f = [0.0; K];
                    basis.eval(s, t, &mut f);
                    // The bilinear map's Jacobian |∂p/∂s × ∂p/∂t| (constant on a parallelogram).
                    let ds = (v[1] - v[0]) * (1.0 - t) + (v[2] - v[3]) * t;
                    let dt = (v[3] - v[0]) * (1.0 - s) + (v[2] - v[1]) * s;
                    let w = ws * wt * ds.cross(dt).length();
                    total += w;
                    nodes.push((patch.polygon.point_at(s, t), w, f));
                }
            }
            for n in &mut nodes {
                n.1 /= total;
            }
            Self { nodes }
        } else {
            let n = (points * basis.cells()).max(2) as u32;
            let mut one = [0.0; K];
            one[0] = 1.0;
            Self {
                nodes: receiver_points(&patch.polygon, n)
                    .into_iter()
                    .map(|(x, w)| (x, w, one))
                    .collect(),
            }
        }
    }
}

/// A link's tensor with what its error estimates read.
#[derive(Clone, Debug)]
pub struct Tensor<const K: usize> {
    /// T_αβ (receiver α, source β).
    pub t: [[f32; K]; K],
    /// Bekaert & Willems 1996's residual per source function: max over receiver nodes of
    /// |Σ_α T_αβ φ_α(x_k) − g_β(x_k)|.
    pub residual: [f32; K],
    /// The unoccluded form factor F_RS by the receiver rule (exact point-to-polygon factors).
    pub f_rs: f64,
    /// The visibility the link's tensor carries: the per-link fraction, or the kernel-weighted mean of the
    /// per-pair rays.
    pub visibility: f64,
}

/// How a tensor is computed.
#[derive(Clone, Copy, Debug)]
pub struct TensorSetup<'a> {
    /// Rays.
    pub accel: &'a Accel,
    /// Visibility mode.
    pub visibility: Visibility,
    /// Seed of the per-link rays.
    pub seed: u64,
    /// Stream of the per-link rays (the pair's).
    pub stream: u64,
    /// A visibility already known (a link's, re-integrated below its receiver): no rays are cast and the
    /// unoccluded tensor is scaled by it.
    pub given: Option<f64>,
}

/// The tensor of link `recv ← src` from the two elements' rules, or `None` when nothing is transferred.
pub fn link_tensor<const K: usize>(
    setup: &TensorSetup<'_>,
    recv: &Patch,
    rr: &ElementRule<K>,
    src: &Patch,
    rs: &ElementRule<K>,
) -> Option<Tensor<K>> {
    let (nr, ns) = (recv.normal, src.normal);
    let nk = rr.nodes.len();
    let nl = rs.nodes.len();
    // Kernels G_kl (without the 1/π, which cancels in the ratio) and, per pair, the rays.
    let mut g = vec![0.0; nk * nl];
    for (k, (x, _, _)) in rr.nodes.iter().enumerate() {
        for (l, (y, _, _)) in rs.nodes.iter().enumerate() {
            g[k * nl + l] = pair_kernel(*x, nr, *y, ns);
        }
    }
    let mut vis = vec![true; nk * nl];
    if setup.visibility == Visibility::PerPair && setup.given.is_none() {
        let mut segments = Vec::new();
        let mut index = Vec::new();
        for (k, (x, _, _)) in rr.nodes.iter().enumerate() {
            for (l, (y, _, _)) in rs.nodes.iter().enumerate() {
                if g[k * nl + l] > 0.0 {
                    segments.push(Segment {
                        p: *x,
                        fp: recv.face,
                        q: *y,
                        fq: src.face,
                    });
                    index.push(k * nl + l);
                }
            }
        }
        let mut seen = vec![false; segments.len()];
        setup.accel.visible_many(&segments, &mut seen);
        for (i, v) in index.into_iter().zip(seen) {
            vis[i] = v;
        }
    }
    // g_β(x_k) by the hybrid rule of the module documentation.
    let mut gk = vec![[0.0; K]; nk];
    let mut f_rs = 0.0;
    let (mut seen_w, mut all_w) = (0.0, 0.0);
    for (k, (x, wk, _)) in rr.nodes.iter().enumerate() {
        let f = point_polygon(*x, nr, &src.polygon);
        if !(f > 0.0) {
            continue;
        }
        f_rs += wk * f;
        let mut den = 0.0;
        let mut num = [0.0; K];
        for (l, (_, wl, phi)) in rs.nodes.iter().enumerate() {
            let w = wl * g[k * nl + l];
            if w <= 0.0 {
                continue;
            }
            den += w;
            all_w += wk * w;
            if vis[k * nl + l] {
                seen_w += wk * w;
                for b in 0..K {
                    num[b] += w * phi[b];
                }
            }
        }
        if den > 0.0 {
            for b in 0..K {
                gk[k][b] = f * num[b] / den;
            }
        } else {
            // No source node in front of x (a grazing corner of the horizon): the mean only, unoccluded.
            gk[k][0] = f;
        }
    }
    if !(f_rs > 0.0) {
        return None;
    }
    let mut visibility = if all_w > 0.0 { seen_w / all_w } else { 1.0 };
    if let Some(v) = setup.given {
        visibility = v;
        for row in &mut gk {
            for x in row.iter_mut() {
                *x *= v;
            }
        }
    } else if setup.visibility == Visibility::PerLink {
        // Ends ordered by key so the link and its reverse cast the same rays.
        use radlab_hierarchical::NodeKind;
        let (a, b) = if recv.key() <= src.key() {
            (recv, src)
        } else {
            (src, recv)
        };
        visibility = visibility_fraction(
            setup.accel,
            &a.polygon,
            a.face,
            &b.polygon,
            b.face,
            VisibilitySampling::Jittered4x4,
            setup.seed,
            setup.stream,
        );
        if visibility.is_nan() {
            return None;
        }
        for row in &mut gk {
            for v in row.iter_mut() {
                *v *= visibility;
            }
        }
    }
    let mut t = [[0.0f64; K]; K];
    for (k, (_, wk, phi)) in rr.nodes.iter().enumerate() {
        for a in 0..K {
            if phi[a] == 0.0 {
                continue;
            }
            for b in 0..K {
                t[a][b] += wk * phi[a] * gk[k][b];
            }
        }
    }
    let mut residual = [0.0f32; K];
    for (k, (_, _, phi)) in rr.nodes.iter().enumerate() {
        for b in 0..K {
            let rep: f64 = (0..K).map(|a| t[a][b] * phi[a]).sum();
            residual[b] = residual[b].max((rep - gk[k][b]).abs() as f32);
        }
    }
    let mut t32 = [[0.0f32; K]; K];
    for a in 0..K {
        for b in 0..K {
            t32[a][b] = t[a][b] as f32;
        }
    }
    Some(Tensor {
        t: t32,
        residual,
        f_rs,
        visibility,
    })
}

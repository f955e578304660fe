//! Symmetric 3×3 matrices and the accumulated point moments behind a cluster's least-squares plane.
//!
//! A region's vertices are summarised by their count c, mean m and scatter S = Σ (p − m)(p − m)ᵀ; two regions
//! combine in O(1) by the pairwise update of Chan, Golub & LeVeque (1979, eq. 2.1b):
//! S = S₁ + S₂ + (c₁c₂/c) δδᵀ with δ = m₂ − m₁, which keeps its digits far from the origin where the raw
//! moments A − b bᵀ/c of Garland, Willmott & Heckbert (2001, section 4.1) would cancel. The least-squares
//! plane passes through m with normal the eigenvector of S's smallest eigenvalue λ_min, and λ_min / c is the
//! mean squared distance of the vertices to it (Garland et al. 2001, E_fit). Eigen-decompositions are
//! nalgebra's symmetric QR iteration.

use glam::DVec3;
use serde::{Deserialize, Serialize};

/// A symmetric 3×3 matrix stored by its six distinct entries.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SymMat3 {
    /// Entries xx, yy, zz, xy, xz, yz.
    pub e: [f64; 6],
}

impl SymMat3 {
    /// The zero matrix.
    pub const ZERO: Self = Self { e: [0.0; 6] };

    /// s · v vᵀ.
    pub fn outer(v: DVec3, s: f64) -> Self {
        Self {
            e: [
                s * v.x * v.x,
                s * v.y * v.y,
                s * v.z * v.z,
                s * v.x * v.y,
                s * v.x * v.z,
                s * v.y * v.z,
            ],
        }
    }

    /// The matrix times a vector.
    pub fn mul_vec(&self, v: DVec3) -> DVec3 {
        let [xx, yy, zz, xy, xz, yz] = self.e;
        DVec3::new(
            xx * v.x + xy * v.y + xz * v.z,
            xy * v.x + yy * v.y + yz * v.z,
            xz * v.x + yz * v.y + zz * v.z,
        )
    }

    /// The quadratic form vᵀ M v.
    pub fn quadratic(&self, v: DVec3) -> f64 {
        v.dot(self.mul_vec(v))
    }

    /// As a glam matrix (columns).
    pub fn to_dmat3(&self) -> glam::DMat3 {
        let [xx, yy, zz, xy, xz, yz] = self.e;
        glam::DMat3::from_cols_array(&[xx, xy, xz, xy, yy, yz, xz, yz, zz])
    }

    fn to_na(self) -> nalgebra::Matrix3<f64> {
        let [xx, yy, zz, xy, xz, yz] = self.e;
        nalgebra::Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz)
    }

    /// The smallest eigenvalue.
    pub fn min_eigenvalue(&self) -> f64 {
        self.to_na().symmetric_eigenvalues().min()
    }

    /// Eigenvectors as a right-handed orthonormal frame, by decreasing eigenvalue (the last is the
    /// smallest's); `None` if the decomposition did not give finite vectors.
    pub fn eigen_frame(&self) -> Option<[DVec3; 3]> {
        let eig = self.to_na().symmetric_eigen();
        let mut order = [0usize, 1, 2];
        order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
        let col = |i: usize| {
            let c = eig.eigenvectors.column(i);
            DVec3::new(c[0], c[1], c[2])
        };
        let a = col(order[0]).normalize();
        let b = col(order[1]);
        let b = (b - a * a.dot(b)).normalize();
        let c = a.cross(b);
        (a.is_finite() && b.is_finite() && c.is_finite()).then_some([a, b, c])
    }
}

impl std::ops::Add for SymMat3 {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        let mut e = self.e;
        for (x, y) in e.iter_mut().zip(o.e) {
            *x += y;
        }
        Self { e }
    }
}

impl std::ops::AddAssign for SymMat3 {
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}

/// Count, mean and scatter of a set of points (see the module doc).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Moments {
    /// Number of points.
    pub count: f64,
    /// Their mean.
    pub mean: DVec3,
    /// Scatter Σ (p − mean)(p − mean)ᵀ.
    pub scatter: SymMat3,
}

impl Moments {
    /// The moments of a few points.
    pub fn of_points(pts: &[DVec3]) -> Self {
        let count = pts.len() as f64;
        let mean = pts.iter().copied().sum::<DVec3>() / count;
        let mut scatter = SymMat3::ZERO;
        for &p in pts {
            scatter += SymMat3::outer(p - mean, 1.0);
        }
        Self {
            count,
            mean,
            scatter,
        }
    }

    /// The moments of both sets together (Chan, Golub & LeVeque 1979).
    pub fn combine(&self, o: &Self) -> Self {
        let count = self.count + o.count;
        let d = o.mean - self.mean;
        Self {
            count,
            mean: self.mean + d * (o.count / count),
            scatter: self.scatter + o.scatter + SymMat3::outer(d, self.count * o.count / count),
        }
    }

    /// Mean squared distance of the points to their least-squares plane: λ_min(S) / c.
    pub fn plane_fit_error(&self) -> f64 {
        (self.scatter.min_eigenvalue() / self.count).max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use glam::dvec3;

    use super::*;

    #[test]
    fn combined_moments_equal_the_moments_of_the_union() {
        let a = [
            dvec3(1e6, 2.0, 3.0),
            dvec3(1e6 + 1.0, 2.5, 3.0),
            dvec3(1e6, 4.0, 3.5),
        ];
        let b = [dvec3(1e6 + 2.0, 2.0, 5.0), dvec3(1e6 + 0.5, 1.0, 3.0)];
        let all: Vec<DVec3> = a.iter().chain(&b).copied().collect();
        let (m, w) = (
            Moments::of_points(&a).combine(&Moments::of_points(&b)),
            Moments::of_points(&all),
        );
        assert_eq!(m.count, 5.0);
        assert!((m.mean - w.mean).length() < 1e-9);
        for (x, y) in m.scatter.e.iter().zip(w.scatter.e) {
            assert!((x - y).abs() < 1e-9, "{m:?} {w:?}");
        }
    }

    #[test]
    fn points_on_a_plane_fit_it_exactly_and_the_frame_ends_with_its_normal() {
        let n = dvec3(1.0, 2.0, 2.0) / 3.0;
        let (u, v) = (
            dvec3(2.0, -1.0, 0.0).normalize(),
            n.cross(dvec3(2.0, -1.0, 0.0).normalize()),
        );
        let pts: Vec<DVec3> = (0..7)
            .map(|i| {
                dvec3(5.0, -3.0, 1.0) + u * (i as f64).sin() * 3.0 + v * (i as f64 * 0.7).cos()
            })
            .collect();
        let m = Moments::of_points(&pts);
        assert!(m.plane_fit_error() < 1e-14);
        let f = m.scatter.eigen_frame().expect("finite");
        assert!((f[2].dot(n).abs() - 1.0).abs() < 1e-12);
        assert!((f[0].cross(f[1]) - f[2]).length() < 1e-12);
    }
}

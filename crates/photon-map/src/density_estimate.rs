//! Irradiance from photons by a k-nearest-neighbour density estimate (Jensen 1996, §3; Jensen 2001, §7.2):
//! with r the distance to the k-th nearest photon of x,
//!
//! H(x) ≈ Σ_p w(d_p) Φ_p / (c π r² N_e),
//!
//! over the photons within r that arrived from x's side (ω_p · n > 0) on a surface facing the same way
//! (n_p · n > 0), Φ_p their unnormalised power and N_e the photons emitted. Filters: the cone filter
//! w = 1 − d/(k_c r) with k_c = 1, normalised by c = 1 − 2/(3 k_c) = 1/3 (Jensen 1996, eq. 7), or the 2-D
//! Epanechnikov kernel w = 2 (1 − d²/r²), c = 1 (Silverman 1986). The disk is assumed flat and wholly on
//! the surface: near edges and corners, and on strongly curved surfaces, the estimate is biased (a point on a
//! convex edge sees half a disk of photons).
//!
//! The k-d tree is kiddo's `ImmutableKdTree` (balanced, built once).

use std::num::NonZero;

use glam::DVec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use radlab_scene::Rgb;
use serde::{Deserialize, Serialize};

use radlab_pathtrace::Photon;

/// The density-estimation filter.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum DensityFilter {
    /// Jensen's cone filter, w = 1 − d/r (k_c = 1), normalisation 1/3. The default.
    #[default]
    Cone,
    /// The 2-D Epanechnikov kernel, w = 2 (1 − d²/r²).
    Epanechnikov,
}

/// Photons in a k-d tree.
pub struct PhotonMap {
    photons: Vec<Photon>,
    tree: Option<ImmutableKdTree<f64, 3>>,
    emitted: u64,
}

impl std::fmt::Debug for PhotonMap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PhotonMap")
            .field("photons", &self.photons.len())
            .field("emitted", &self.emitted)
            .finish()
    }
}

impl PhotonMap {
    /// The map of `photons` from `emitted` emitted photons.
    pub fn new(photons: Vec<Photon>, emitted: u64) -> Self {
        let tree = (!photons.is_empty()).then(|| {
            let pts: Vec<[f64; 3]> = photons.iter().map(|p| p.point.to_array()).collect();
            ImmutableKdTree::new_from_slice(&pts)
        });
        Self {
            photons,
            tree,
            emitted,
        }
    }

    /// The photons.
    pub fn photons(&self) -> &[Photon] {
        &self.photons
    }

    /// Photons emitted.
    pub fn emitted(&self) -> u64 {
        self.emitted
    }

    /// Irradiance at `x` (normal `n`) from its `k` nearest photons with `filter`.
    pub fn irradiance(&self, x: DVec3, n: DVec3, k: usize, filter: DensityFilter) -> Rgb {
        let Some(tree) = &self.tree else {
            return Rgb::ZERO;
        };
        let k = NonZero::new(k).unwrap_or(NonZero::<usize>::MIN);
        let found = tree.nearest_n::<SquaredEuclidean>(&x.to_array(), k);
        let r2 = found.iter().map(|f| f.distance).fold(0.0, f64::max);
        if !(r2 > 0.0) || self.emitted == 0 {
            return Rgb::ZERO;
        }
        let r = r2.sqrt();
        let mut sum = Rgb::ZERO;
        for f in &found {
            let p = &self.photons[f.item as usize];
            if !(p.toward_source.dot(n) > 0.0 && p.normal.dot(n) > 0.0) {
                continue;
            }
            let w = match filter {
                DensityFilter::Cone => 1.0 - f.distance.sqrt() / r,
                DensityFilter::Epanechnikov => 2.0 * (1.0 - f.distance / r2),
            };
            sum += p.power * w;
        }
        let c = match filter {
            DensityFilter::Cone => 1.0 / 3.0,
            DensityFilter::Epanechnikov => 1.0,
        };
        sum / (c * std::f64::consts::PI * r2 * self.emitted as f64)
    }

    /// Indices of the photons within distance √`r2` of `x`, in increasing index order.
    pub fn within(&self, x: DVec3, r2: f64) -> Vec<usize> {
        let Some(tree) = &self.tree else {
            return Vec::new();
        };
        let mut idx: Vec<usize> = tree
            .within_unsorted::<SquaredEuclidean>(&x.to_array(), r2)
            .iter()
            .map(|f| f.item as usize)
            .collect();
        idx.sort_unstable();
        idx
    }

    /// Bytes held: the photons and the tree (its points and indices).
    pub fn bytes(&self) -> usize {
        self.photons.capacity() * size_of::<Photon>()
            + self
                .tree
                .as_ref()
                .map_or(0, |_| self.photons.len() * (24 + 8))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use radlab_scene::sampling;

    /// Photons uniformly on the unit square (z = 0, facing +z), total power 1 per emitted photon.
    fn uniform_square(count: usize) -> PhotonMap {
        let mut r = sampling::rng(9, 0);
        let photons = (0..count)
            .map(|_| Photon {
                point: DVec3::new(sampling::uniform(&mut r), sampling::uniform(&mut r), 0.0),
                normal: DVec3::Z,
                face: 0,
                toward_source: DVec3::Z,
                power: Rgb::ONE,
                bounces: 0,
            })
            .collect();
        PhotonMap::new(photons, count as u64)
    }

    #[test]
    fn uniform_density_is_recovered_by_both_filters_away_from_edges() {
        // Irradiance = power per area = 1 on the unit square.
        let map = uniform_square(200_000);
        for filter in [DensityFilter::Cone, DensityFilter::Epanechnikov] {
            let mut mean = 0.0;
            let m = 50;
            for i in 0..m {
                let x = DVec3::new(0.3 + 0.4 * (i as f64 / m as f64), 0.5, 0.0);
                mean += map.irradiance(x, DVec3::Z, 400, filter).x / m as f64;
            }
            // 400 photons per estimate, 50 nearly independent estimates: relative noise about
            // 1/√(400 · 50) × (filter variance factor < 2): 2 % is over 2.5 standard errors.
            assert!((mean - 1.0).abs() < 0.02, "{filter:?}: {mean}");
            // Photons arriving from below are not counted.
            assert_eq!(
                map.irradiance(DVec3::new(0.5, 0.5, 0.0), -DVec3::Z, 50, filter),
                Rgb::ZERO
            );
        }
        // A corner point sees a quarter disk: biased low by about 4 (the known edge bias).
        let corner = map
            .irradiance(DVec3::ZERO, DVec3::Z, 400, DensityFilter::Cone)
            .x;
        assert!(corner < 0.4, "{corner}");
        assert!(
            PhotonMap::new(Vec::new(), 0).irradiance(DVec3::ZERO, DVec3::Z, 5, DensityFilter::Cone)
                == Rgb::ZERO
        );
    }
}

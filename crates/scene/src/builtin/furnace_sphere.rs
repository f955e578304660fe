//! The furnace sphere: the inside of a closed tessellated sphere, every face with the same reflectance ρ and
//! emission E. In any closed scene with uniform ρ and E the radiosity is B = E/(1 − ρ) everywhere, whatever
//! the tessellation; the sphere adds curved, non-axis-aligned faces of
//! varied shape to the furnace cube. The tessellation is the cube sphere of [`super::primitives`]:
//! 12 n² triangles facing the centre.
//!
//! Concentric spheres (Christensen 1995, §8.3; Christensen et al. 1997): a unit sphere facing out
//! inside a radius-2 sphere facing in, every triangle with the same ρ and E. A closed scene with uniform ρ and
//! E is a furnace, so B = E/(1 − ρ) exactly at any face count k, which makes it the scaling scene for cluster
//! methods: slope and error at once. Half the faces (to the nearest cube-sphere resolution) on each sphere.

use glam::DVec3;

use super::primitives::{add_cube_sphere, cube_sphere_resolution};
use super::{Args, BuiltinInfo};
use crate::{Material, Scene, SceneBuilder, SceneError};

pub(super) fn infos() -> Vec<BuiltinInfo> {
    vec![
        BuiltinInfo {
            name: "furnace-sphere",
            doc: "Inside of a closed tessellated sphere, uniform rho and E: B = E/(1-rho) everywhere.",
            params: &[
                ("reflectance", "0.5", "rho in [0, 1), grey or r,g,b"),
                ("emission", "1", "E >= 0 (W/m^2), grey or r,g,b"),
                (
                    "tessellation",
                    "8",
                    "cells per cube-face edge n (12 n^2 triangles), 1..512",
                ),
                ("radius", "1", "sphere radius (scene units)"),
            ],
            build: furnace_sphere,
        },
        BuiltinInfo {
            name: "concentric-spheres",
            doc: "A unit sphere facing out inside a radius-2 sphere facing in, uniform rho and E \
              (Christensen 1995): a furnace, B = E/(1-rho) everywhere, at any face count.",
            params: &[
                ("faces", "1000", "total triangle count k, 24..8000000"),
                ("reflectance", "0.5", "rho in [0, 1), grey or r,g,b"),
                ("emission", "1", "E >= 0 (W/m^2), grey or r,g,b"),
            ],
            build: concentric_spheres,
        },
    ]
}

fn concentric_spheres(a: &Args) -> Result<Scene, SceneError> {
    let k = a.usize("faces", 1000, 24, 8_000_000)?;
    let rho = a.rgb("reflectance", DVec3::splat(0.5), 0.0, 1.0, true)?;
    let e = a.rgb("emission", DVec3::ONE, 0.0, f64::MAX, false)?;
    let mut b = SceneBuilder::new("concentric-spheres");
    let m = b.add_material(Material::new("furnace", rho, e)?)?;
    let n = cube_sphere_resolution(k / 2);
    add_cube_sphere(
        &mut b,
        DVec3::ZERO,
        1.0,
        n,
        false,
        m,
        &|_| 1.0,
        "inner sphere",
    )?;
    add_cube_sphere(
        &mut b,
        DVec3::ZERO,
        2.0,
        n,
        true,
        m,
        &|_| 1.0,
        "outer sphere",
    )?;
    b.build()
}

fn furnace_sphere(a: &Args) -> Result<Scene, SceneError> {
    let rho = a.rgb("reflectance", DVec3::splat(0.5), 0.0, 1.0, true)?;
    let e = a.rgb("emission", DVec3::ONE, 0.0, f64::MAX, false)?;
    let n = a.usize("tessellation", 8, 1, 512)?;
    let r = a.f64("radius", 1.0, 1e-100, 1e100)?;
    let mut b = SceneBuilder::new("furnace-sphere");
    let m = b.add_material(Material::new("furnace", rho, e)?)?;
    add_cube_sphere(
        &mut b,
        DVec3::ZERO,
        r,
        [n; 3],
        true,
        m,
        &|_| 1.0,
        "furnace-sphere",
    )?;
    b.build()
}

//! The furnace sphere: the inside of a closed tessellated sphere, every face with the same reflectance ρ and
//! emission E. In any closed scene with uniform ρ and E the radiosity is B = E/(1 − ρ) everywhere
//! (ALGORITHMS.md, "Furnace"), whatever the tessellation; the sphere adds curved, non-axis-aligned faces of
//! varied shape to the furnace cube. The tessellation is the cube sphere of [`super::primitives`]:
//! 12 n² triangles facing the centre.

use glam::DVec3;

use super::primitives::add_cube_sphere;
use super::{Args, BuiltinInfo};
use crate::{Material, Scene, SceneBuilder, SceneError};

pub(super) fn infos() -> Vec<BuiltinInfo> {
    vec![BuiltinInfo {
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
    }]
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

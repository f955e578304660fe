//! Detailed meshes for scaling studies, where the face count k is the parameter (`faces`, from about 100 to
//! several million) and generation costs O(k):
//!
//! - **bumpy-sphere**: a cube sphere (see [`super::primitives`]) whose radius varies smoothly,
//!   r(u) = R (1 + a tanh Σ_b h_b exp(−(1 − u·c_b)/σ_b²)), with bump centres c_b, heights h_b ∈ [−1, 1] and
//!   angular widths σ_b drawn from `sampling::rng(seed, 0)`; it floats just above the floor of a closed room
//!   lit by a square area light set into the ceiling, so light bounces between sphere, floor and walls.
//! - **terrain**: a fractal height field (fBm value noise, see [`super::primitives`]) over a 10 × 10 square,
//!   under a 4 × 4 area light facing down at height 6 (or 1 above the highest peak; an open scene).
//! - **polygon-soup**: k independent triangles (no shared vertices, free to intersect one another) in the
//!   bumpy sphere's room: each an equilateral triangle of circumradius r = s (0.5 + u) about a centre uniform
//!   in [−1, 1] × [r, 1.2] × [−1, 1], facing a uniform direction (Archimedes), turned uniformly about it; u,
//!   the centre and the directions drawn from `sampling::rng(seed, 0)`. One-sided like every face, so about
//!   half face away from the light; the soup scatters and shadows like foliage and has no connectivity for
//!   a mesh hierarchy to walk.
//!
//! The face count lands within a few percent of `faces` (the grid resolutions are chosen to fit it); the
//! room or the light adds a fixed handful of faces, counted in the total.

use glam::{DVec3, dvec3};

use super::primitives::{
    Fractal, add_cube_sphere, add_height_field, add_quad_grid, box_faces, cube_sphere_resolution,
    fractal_heights, height_field_resolution,
};
use super::{Args, BuiltinInfo};
use crate::{Material, Scene, SceneBuilder, SceneError, sampling};

/// Faces of the room of bumpy-sphere and polygon-soup: floor, four walls, ceiling as four quads around the
/// light, the light.
const ROOM_FACES: usize = 10;

pub(super) fn infos() -> Vec<BuiltinInfo> {
    vec![
        BuiltinInfo {
            name: "bumpy-sphere",
            doc: "A smoothly bumped sphere of k faces above the floor of a closed room lit by a ceiling light.",
            params: &[
                (
                    "faces",
                    "10000",
                    "total face count k (room included), 100..4000000",
                ),
                (
                    "bumpiness",
                    "0.15",
                    "relative radius variation a in [0, 0.5]",
                ),
                ("bumps", "32", "number of bumps, 1..1000"),
                ("seed", "1", "seed of the bumps"),
                ("reflectance", "0.7", "sphere's rho, grey or r,g,b"),
                ("walls", "0.6", "room's rho, grey or r,g,b"),
                ("emission", "10", "light's E (W/m^2), grey or r,g,b"),
            ],
            build: bumpy_sphere,
        },
        BuiltinInfo {
            name: "terrain",
            doc: "A fractal height-field terrain of k faces under a square area light (open scene).",
            params: &[
                (
                    "faces",
                    "10000",
                    "total face count k (light included), 100..4000000",
                ),
                ("relief", "1", "height scale (first octave's amplitude)"),
                (
                    "roughness",
                    "0.5",
                    "amplitude ratio between octaves, [0, 1]",
                ),
                (
                    "octaves",
                    "8",
                    "noise octaves, 1..16 (at most log2 of the grid's cells per side)",
                ),
                ("seed", "1", "seed of the noise"),
                ("reflectance", "0.5", "terrain's rho, grey or r,g,b"),
                ("emission", "10", "light's E (W/m^2), grey or r,g,b"),
            ],
            build: terrain,
        },
        BuiltinInfo {
            name: "polygon-soup",
            doc: "k unconnected, intersecting triangles of random orientation heaped in a closed room lit by a ceiling light.",
            params: &[
                (
                    "faces",
                    "20000",
                    "total face count k (room included), 100..4000000",
                ),
                (
                    "size",
                    "0.04",
                    "triangles' mean circumradius s (the room is 4 wide), (0, 0.5]",
                ),
                ("seed", "1", "seed of the triangles"),
                ("reflectance", "0.6", "triangles' rho, grey or r,g,b"),
                ("walls", "0.6", "room's rho, grey or r,g,b"),
                ("emission", "10", "light's E (W/m^2), grey or r,g,b"),
            ],
            build: polygon_soup,
        },
    ]
}

/// A bump on the unit sphere: centre, height, angular width².
struct Bump {
    centre: DVec3,
    height: f64,
    width2: f64,
}

fn bumps(count: usize, seed: u64) -> Vec<Bump> {
    let mut r = sampling::rng(seed, 0);
    (0..count)
        .map(|_| {
            // Uniform direction: z uniform in [−1, 1], φ uniform (Archimedes).
            let z = 2.0 * sampling::uniform(&mut r) - 1.0;
            let phi = std::f64::consts::TAU * sampling::uniform(&mut r);
            let s = (1.0 - z * z).max(0.0).sqrt();
            let height = 2.0 * sampling::uniform(&mut r) - 1.0;
            let sigma = 0.15 + 0.35 * sampling::uniform(&mut r);
            Bump {
                centre: dvec3(s * phi.cos(), s * phi.sin(), z),
                height,
                width2: sigma * sigma,
            }
        })
        .collect()
}

/// The closed room [−2, 2] × [0, 3] × [−2, 2] (faces inward, material `walls`) whose ceiling is a frame of four
/// quads around a 1 × 1 light (material `light`) facing down at its centre: [`ROOM_FACES`] faces.
fn add_lit_room(
    b: &mut SceneBuilder,
    m_walls: u32,
    m_light: u32,
    what: &str,
) -> Result<(), SceneError> {
    // Room [−2, 2] × [0, 3] × [−2, 2], faces inward, ceiling replaced by a frame around a 1 × 1 light.
    let (lo, hi) = (dvec3(-2.0, 0.0, -2.0), dvec3(2.0, 3.0, 2.0));
    for (i, mut c) in box_faces(lo, hi).into_iter().enumerate() {
        if i == 2 {
            continue; // +y: the ceiling, built below
        }
        c.reverse();
        add_quad_grid(b, c, 1, 1, m_walls, &format!("{what} room"))?;
    }
    let y = hi.y;
    // (x0..x1) × (z0..z1) at the ceiling, counter-clockwise seen from below (normal −y).
    let down = |x0: f64, x1: f64, z0: f64, z1: f64| {
        [
            dvec3(x1, y, z0),
            dvec3(x1, y, z1),
            dvec3(x0, y, z1),
            dvec3(x0, y, z0),
        ]
    };
    for c in [
        down(0.5, 2.0, -2.0, 2.0),
        down(-2.0, -0.5, -2.0, 2.0),
        down(-0.5, 0.5, -2.0, -0.5),
        down(-0.5, 0.5, 0.5, 2.0),
    ] {
        add_quad_grid(b, c, 1, 1, m_walls, &format!("{what} ceiling"))?;
    }
    add_quad_grid(
        b,
        down(-0.5, 0.5, -0.5, 0.5),
        1,
        1,
        m_light,
        &format!("{what} light"),
    )?;
    Ok(())
}

fn bumpy_sphere(a: &Args) -> Result<Scene, SceneError> {
    let k = a.usize("faces", 10_000, 100, 4_000_000)?;
    let amp = a.f64("bumpiness", 0.15, 0.0, 0.5)?;
    let nb = a.usize("bumps", 32, 1, 1000)?;
    let seed = a.usize("seed", 1, 0, usize::MAX)? as u64;
    let rho = a.rgb("reflectance", DVec3::splat(0.7), 0.0, 1.0, true)?;
    let rho_walls = a.rgb("walls", DVec3::splat(0.6), 0.0, 1.0, true)?;
    let e = a.rgb("emission", DVec3::splat(10.0), 0.0, f64::MAX, false)?;
    let mut b = SceneBuilder::new("bumpy-sphere");
    let m_sphere = b.add_material(Material::new("sphere", rho, DVec3::ZERO)?)?;
    let m_walls = b.add_material(Material::new("walls", rho_walls, DVec3::ZERO)?)?;
    let m_light = b.add_material(Material::new("light", DVec3::ZERO, e)?)?;

    add_lit_room(&mut b, m_walls, m_light, "bumpy-sphere")?;

    let radius = 0.75;
    let bs = bumps(nb, seed);
    let displace = |u: DVec3| {
        let f: f64 = bs
            .iter()
            .map(|bump| bump.height * (-(1.0 - u.dot(bump.centre)) / bump.width2).exp())
            .sum();
        1.0 + amp * f.tanh()
    };
    let centre = dvec3(0.0, radius * (1.0 + amp) + 0.05, 0.0);
    let n = cube_sphere_resolution(k.saturating_sub(ROOM_FACES));
    add_cube_sphere(
        &mut b,
        centre,
        radius,
        n,
        false,
        m_sphere,
        &displace,
        "bumpy-sphere sphere",
    )?;
    b.build()
}

fn terrain(a: &Args) -> Result<Scene, SceneError> {
    let k = a.usize("faces", 10_000, 100, 4_000_000)?;
    let relief = a.f64("relief", 1.0, 0.0, 1e6)?;
    let roughness = a.f64("roughness", 0.5, 0.0, 1.0)?;
    let octaves = a.usize("octaves", 8, 1, 16)?;
    let seed = a.usize("seed", 1, 0, usize::MAX)? as u64;
    let rho = a.rgb("reflectance", DVec3::splat(0.5), 0.0, 1.0, true)?;
    let e = a.rgb("emission", DVec3::splat(10.0), 0.0, f64::MAX, false)?;
    let mut b = SceneBuilder::new("terrain");
    let m_ground = b.add_material(Material::new("ground", rho, DVec3::ZERO)?)?;
    let m_light = b.add_material(Material::new("light", DVec3::ZERO, e)?)?;
    let (nx, nz) = height_field_resolution(k.saturating_sub(1));
    let h = fractal_heights(
        nx,
        nz,
        &Fractal {
            amplitude: relief,
            roughness,
            octaves,
            seed,
        },
    );
    add_height_field(
        &mut b,
        DVec3::ZERO,
        (10.0, 10.0),
        nx,
        nz,
        &h,
        false,
        m_ground,
        "terrain",
    )?;
    // A 4 × 4 light over the centre, facing down, at y = 6 or 1 above the highest point.
    let y = h.iter().fold(5.0f64, |m, &v| m.max(v)) + 1.0;
    add_quad_grid(
        &mut b,
        [
            dvec3(7.0, y, 3.0),
            dvec3(7.0, y, 7.0),
            dvec3(3.0, y, 7.0),
            dvec3(3.0, y, 3.0),
        ],
        1,
        1,
        m_light,
        "terrain light",
    )?;
    b.build()
}

fn polygon_soup(a: &Args) -> Result<Scene, SceneError> {
    let k = a.usize("faces", 20_000, 100, 4_000_000)?;
    let size = a.f64("size", 0.04, 1e-6, 0.5)?;
    let seed = a.usize("seed", 1, 0, usize::MAX)? as u64;
    let rho = a.rgb("reflectance", DVec3::splat(0.6), 0.0, 1.0, true)?;
    let rho_walls = a.rgb("walls", DVec3::splat(0.6), 0.0, 1.0, true)?;
    let e = a.rgb("emission", DVec3::splat(10.0), 0.0, f64::MAX, false)?;
    let mut b = SceneBuilder::new("polygon-soup");
    let m_soup = b.add_material(Material::new("soup", rho, DVec3::ZERO)?)?;
    let m_walls = b.add_material(Material::new("walls", rho_walls, DVec3::ZERO)?)?;
    let m_light = b.add_material(Material::new("light", DVec3::ZERO, e)?)?;
    add_lit_room(&mut b, m_walls, m_light, "polygon-soup")?;

    let mut r = sampling::rng(seed, 0);
    let tau = std::f64::consts::TAU;
    for _ in 0..k.saturating_sub(ROOM_FACES) {
        let radius = size * (0.5 + sampling::uniform(&mut r));
        let centre = dvec3(
            2.0 * sampling::uniform(&mut r) - 1.0,
            radius + (1.2 - radius).max(0.0) * sampling::uniform(&mut r),
            2.0 * sampling::uniform(&mut r) - 1.0,
        );
        // Uniform facing direction: z uniform in [−1, 1], φ uniform (Archimedes).
        let z = 2.0 * sampling::uniform(&mut r) - 1.0;
        let phi = tau * sampling::uniform(&mut r);
        let s = (1.0 - z * z).max(0.0).sqrt();
        let n = dvec3(s * phi.cos(), s * phi.sin(), z);
        let t1 = n.any_orthonormal_vector();
        let t2 = n.cross(t1);
        let turn = tau * sampling::uniform(&mut r);
        // Counter-clockwise about n, since t1 × t2 = t1 × (n × t1) = n.
        let corner = |i: f64| {
            let t = turn + i * tau / 3.0;
            centre + radius * (t.cos() * t1 + t.sin() * t2)
        };
        b.add_polygon_points(
            &[corner(0.0), corner(1.0), corner(2.0)],
            m_soup,
            "polygon-soup triangle",
        )?;
    }
    b.build()
}

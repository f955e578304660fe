//! The Cornell box as published by the Cornell University Program of Computer Graphics ("Cornell Box Data",
//! www.graphics.cornell.edu/online/box/data.html): the measured vertex lists in millimetres, the measured
//! reflectance spectra of the white, green and red paints (400–700 nm every 4 nm) and the light's emission
//! spectrum (400, 500, 600, 700 nm: 0, 8, 15.6, 18.4), turned into linear sRGB by [`super::spectrum_rgb`].
//!
//! Geometry notes: the published light lies in the ceiling plane (y = 548.8), so the ceiling is built as four
//! quads around a 130 × 105 mm hole that the light fills exactly (no overlapping faces; ceiling + light =
//! the published ceiling). The published left (red) wall is not planar (its corners are 3.2 mm out of one
//! plane), so it is two triangles split along its shorter diagonal. Walls, floor, ceiling and light face the
//! inside of the box; the blocks face outward; the blocks have no bottom faces (they stand on the floor).
//! Camera: eye (278, 273, −800) looking along +z, up +y, focal length 35 mm on a 25 × 25 mm film:
//! vertical field of view 2 atan(12.5/35) ≈ 39.31°.
//!
//! Emission: the published spectrum is read as radiance L (as common renderers use it); the scene stores
//! radiant exitance E = π L per channel, times the `light` parameter. The light's own reflectance is not
//! published: 0.78 grey, as in Mitsuba's "cbox" scene.

use glam::{DVec3, dvec3};

use super::primitives::{add_subdivided, add_triangle_grid};
use super::spectrum_rgb::{Spectrum, emission_rgb, reflectance_rgb};
use super::{Args, BuiltinInfo};
use crate::{Camera, Material, Scene, SceneBuilder, SceneError};

/// Reflectance of the white paint, 400–700 nm every 4 nm (Cornell Box Data).
#[rustfmt::skip]
const WHITE: [f64; 76] = [
    0.343, 0.445, 0.551, 0.624, 0.665, 0.687, 0.708, 0.723, 0.715, 0.710, 0.745, 0.758, 0.739, 0.767, 0.777,
    0.765, 0.751, 0.745, 0.748, 0.729, 0.745, 0.757, 0.753, 0.750, 0.746, 0.747, 0.735, 0.732, 0.739, 0.734,
    0.725, 0.721, 0.733, 0.725, 0.732, 0.743, 0.744, 0.748, 0.728, 0.716, 0.733, 0.726, 0.713, 0.740, 0.754,
    0.764, 0.752, 0.736, 0.734, 0.741, 0.740, 0.732, 0.745, 0.755, 0.751, 0.744, 0.731, 0.733, 0.744, 0.731,
    0.712, 0.708, 0.729, 0.730, 0.727, 0.707, 0.703, 0.729, 0.750, 0.760, 0.751, 0.739, 0.724, 0.730, 0.740,
    0.737,
];

/// Reflectance of the green paint, 400–700 nm every 4 nm (Cornell Box Data).
#[rustfmt::skip]
const GREEN: [f64; 76] = [
    0.092, 0.096, 0.098, 0.097, 0.098, 0.095, 0.095, 0.097, 0.095, 0.094, 0.097, 0.098, 0.096, 0.101, 0.103,
    0.104, 0.107, 0.109, 0.112, 0.115, 0.125, 0.140, 0.160, 0.187, 0.229, 0.285, 0.343, 0.390, 0.435, 0.464,
    0.472, 0.476, 0.481, 0.462, 0.447, 0.441, 0.426, 0.406, 0.373, 0.347, 0.337, 0.314, 0.285, 0.277, 0.266,
    0.250, 0.230, 0.207, 0.186, 0.171, 0.160, 0.148, 0.141, 0.136, 0.130, 0.126, 0.123, 0.121, 0.122, 0.119,
    0.114, 0.115, 0.117, 0.117, 0.118, 0.120, 0.122, 0.128, 0.132, 0.139, 0.144, 0.146, 0.150, 0.152, 0.157,
    0.159,
];

/// Reflectance of the red paint, 400–700 nm every 4 nm (Cornell Box Data).
#[rustfmt::skip]
const RED: [f64; 76] = [
    0.040, 0.046, 0.048, 0.053, 0.049, 0.050, 0.053, 0.055, 0.057, 0.056, 0.059, 0.057, 0.061, 0.061, 0.060,
    0.062, 0.062, 0.062, 0.061, 0.062, 0.060, 0.059, 0.057, 0.058, 0.058, 0.058, 0.056, 0.055, 0.056, 0.059,
    0.057, 0.055, 0.059, 0.059, 0.058, 0.059, 0.061, 0.061, 0.063, 0.063, 0.067, 0.068, 0.072, 0.080, 0.090,
    0.099, 0.124, 0.154, 0.192, 0.255, 0.287, 0.349, 0.402, 0.443, 0.487, 0.513, 0.558, 0.584, 0.620, 0.606,
    0.609, 0.651, 0.612, 0.610, 0.650, 0.638, 0.627, 0.620, 0.630, 0.628, 0.642, 0.639, 0.657, 0.639, 0.635,
    0.642,
];

/// The light's emission spectrum at 400, 500, 600, 700 nm (Cornell Box Data), read as radiance.
const LIGHT: [f64; 4] = [0.0, 8.0, 15.6, 18.4];

fn paint(values: &[f64]) -> Spectrum<'_> {
    Spectrum {
        start: 400.0,
        step: 4.0,
        values,
    }
}

fn light_spectrum() -> Spectrum<'static> {
    Spectrum {
        start: 400.0,
        step: 100.0,
        values: &LIGHT,
    }
}

/// Linear sRGB reflectances (white, green, red) of the published paints under the published light.
pub fn cornell_reflectances() -> [DVec3; 3] {
    let l = light_spectrum();
    [
        reflectance_rgb(paint(&WHITE), l),
        reflectance_rgb(paint(&GREEN), l),
        reflectance_rgb(paint(&RED), l),
    ]
}

/// Radiant exitance E = π L (W/m², linear sRGB) of the published light at `light` = 1.
pub fn cornell_light_exitance() -> DVec3 {
    std::f64::consts::PI * emission_rgb(light_spectrum())
}

/// Vertical field of view of the published camera: 2 atan(12.5 mm / 35 mm), in degrees.
pub fn cornell_fov_deg() -> f64 {
    2.0 * (12.5f64 / 35.0).atan().to_degrees()
}

pub(super) fn infos() -> Vec<BuiltinInfo> {
    vec![BuiltinInfo {
        name: "cornell",
        doc: "The published Cornell box (millimetres): room, light, short and tall block; RGB from the measured spectra.",
        params: &[
            (
                "light",
                "1",
                "scale of the light's exitance (pi x the published spectrum as radiance)",
            ),
            (
                "tessellation",
                "1",
                "split every published polygon into n x n pieces, 1..256",
            ),
            ("width", "256", "image width in pixels"),
            ("height", "256", "image height in pixels"),
        ],
        build: cornell,
    }]
}

fn cornell(a: &Args) -> Result<Scene, SceneError> {
    let scale = a.f64("light", 1.0, 0.0, 1e12)?;
    let n = a.usize("tessellation", 1, 1, 256)?;
    let width = a.usize("width", 256, 1, 16384)? as u32;
    let height = a.usize("height", 256, 1, 16384)? as u32;
    let [white, green, red] = cornell_reflectances();
    let mut b = SceneBuilder::new("cornell");
    let m_white = b.add_material(Material::new("white", white, DVec3::ZERO)?)?;
    let m_green = b.add_material(Material::new("green", green, DVec3::ZERO)?)?;
    let m_red = b.add_material(Material::new("red", red, DVec3::ZERO)?)?;
    // The light's reflectance is not published; 0.78 grey as in Mitsuba's "cbox" scene.
    let m_light = b.add_material(Material::new(
        "light",
        DVec3::splat(0.78),
        cornell_light_exitance() * scale,
    )?)?;
    let v = |x: f64, y: f64, z: f64| dvec3(x, y, z);
    let quad = |b: &mut SceneBuilder, c: [DVec3; 4], m: u32, what: &str| {
        add_subdivided(b, &c, n, m, what).map(|_| ())
    };
    // Floor (white), published order; normal +y.
    quad(
        &mut b,
        [
            v(552.8, 0.0, 0.0),
            v(0.0, 0.0, 0.0),
            v(0.0, 0.0, 559.2),
            v(549.6, 0.0, 559.2),
        ],
        m_white,
        "cornell floor",
    )?;
    // Light (published), normal −y.
    quad(
        &mut b,
        [
            v(343.0, 548.8, 227.0),
            v(343.0, 548.8, 332.0),
            v(213.0, 548.8, 332.0),
            v(213.0, 548.8, 227.0),
        ],
        m_light,
        "cornell light",
    )?;
    // Ceiling (published: 556.0 × 559.2 at y = 548.8) minus the light's rectangle, as four quads; normal −y.
    // A quad (x0..x1) × (z0..z1) at the ceiling, counter-clockwise seen from below.
    let ceiling = |x0: f64, x1: f64, z0: f64, z1: f64| {
        [
            v(x1, 548.8, z0),
            v(x1, 548.8, z1),
            v(x0, 548.8, z1),
            v(x0, 548.8, z0),
        ]
    };
    for c in [
        ceiling(343.0, 556.0, 0.0, 559.2),
        ceiling(0.0, 213.0, 0.0, 559.2),
        ceiling(213.0, 343.0, 0.0, 227.0),
        ceiling(213.0, 343.0, 332.0, 559.2),
    ] {
        quad(&mut b, c, m_white, "cornell ceiling")?;
    }
    // Back wall (white), normal −z.
    quad(
        &mut b,
        [
            v(549.6, 0.0, 559.2),
            v(0.0, 0.0, 559.2),
            v(0.0, 548.8, 559.2),
            v(556.0, 548.8, 559.2),
        ],
        m_white,
        "cornell back wall",
    )?;
    // Right wall (green, x = 0), normal +x.
    quad(
        &mut b,
        [
            v(0.0, 0.0, 559.2),
            v(0.0, 0.0, 0.0),
            v(0.0, 548.8, 0.0),
            v(0.0, 548.8, 559.2),
        ],
        m_green,
        "cornell right wall",
    )?;
    // Left wall (red): published corners 552.8 0 0, 549.6 0 559.2, 556 548.8 559.2, 556 548.8 0 are not
    // coplanar; two triangles split along the shorter diagonal (corners 0–2, shorter than 1–3 by 0.02 mm),
    // normal ≈ −x.
    let left = [
        v(552.8, 0.0, 0.0),
        v(549.6, 0.0, 559.2),
        v(556.0, 548.8, 559.2),
        v(556.0, 548.8, 0.0),
    ];
    let (t1, t2) = if (left[2] - left[0]).length() <= (left[3] - left[1]).length() {
        ([left[0], left[1], left[2]], [left[0], left[2], left[3]])
    } else {
        ([left[0], left[1], left[3]], [left[1], left[2], left[3]])
    };
    add_triangle_grid(&mut b, t1, n, m_red, "cornell left wall")?;
    add_triangle_grid(&mut b, t2, n, m_red, "cornell left wall")?;
    // Short block (published quads: top, then four sides), outward.
    let short = [
        [
            v(130.0, 165.0, 65.0),
            v(82.0, 165.0, 225.0),
            v(240.0, 165.0, 272.0),
            v(290.0, 165.0, 114.0),
        ],
        [
            v(290.0, 0.0, 114.0),
            v(290.0, 165.0, 114.0),
            v(240.0, 165.0, 272.0),
            v(240.0, 0.0, 272.0),
        ],
        [
            v(130.0, 0.0, 65.0),
            v(130.0, 165.0, 65.0),
            v(290.0, 165.0, 114.0),
            v(290.0, 0.0, 114.0),
        ],
        [
            v(82.0, 0.0, 225.0),
            v(82.0, 165.0, 225.0),
            v(130.0, 165.0, 65.0),
            v(130.0, 0.0, 65.0),
        ],
        [
            v(240.0, 0.0, 272.0),
            v(240.0, 165.0, 272.0),
            v(82.0, 165.0, 225.0),
            v(82.0, 0.0, 225.0),
        ],
    ];
    // Tall block (published quads), outward.
    let tall = [
        [
            v(423.0, 330.0, 247.0),
            v(265.0, 330.0, 296.0),
            v(314.0, 330.0, 456.0),
            v(472.0, 330.0, 406.0),
        ],
        [
            v(423.0, 0.0, 247.0),
            v(423.0, 330.0, 247.0),
            v(472.0, 330.0, 406.0),
            v(472.0, 0.0, 406.0),
        ],
        [
            v(472.0, 0.0, 406.0),
            v(472.0, 330.0, 406.0),
            v(314.0, 330.0, 456.0),
            v(314.0, 0.0, 456.0),
        ],
        [
            v(314.0, 0.0, 456.0),
            v(314.0, 330.0, 456.0),
            v(265.0, 330.0, 296.0),
            v(265.0, 0.0, 296.0),
        ],
        [
            v(265.0, 0.0, 296.0),
            v(265.0, 330.0, 296.0),
            v(423.0, 330.0, 247.0),
            v(423.0, 0.0, 247.0),
        ],
    ];
    for c in short {
        quad(&mut b, c, m_white, "cornell short block")?;
    }
    for c in tall {
        quad(&mut b, c, m_white, "cornell tall block")?;
    }
    let camera = Camera {
        eye: v(278.0, 273.0, -800.0),
        target: v(278.0, 273.0, 0.0),
        up: DVec3::Y,
        fov_y_deg: cornell_fov_deg(),
        width,
        height,
    };
    camera.validate()?;
    b.set_camera(camera);
    b.build()
}

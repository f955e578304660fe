//! Linear sRGB from spectra: the tristimulus values X, Y, Z of a spectral power distribution by the CIE 1931
//! 2° standard observer, then linear sRGB by the IEC 61966-2-1 matrix.
//!
//! X = (1/k) ∫ S(λ) x̄(λ) dλ (likewise Y, Z), integrated by the trapezoid rule on a 1 nm grid from 400 to 700 nm
//! with every table interpolated linearly; k = ∫ ȳ dλ over 360–830 nm (106.856895, CIE 1931 at 1 nm), so a
//! constant spectrum S = 1 has Y = 1. RGB = M · XYZ with
//! M = [[3.2406, −1.5372, −0.4986], [−0.9689, 1.8758, 0.0415], [0.0557, −0.2040, 1.0570]] (IEC 61966-2-1).
//! A reflectance spectrum ρ(λ) seen under a light S(λ) becomes the per-channel ratio
//! ρ_c = RGB_c(ρ S) / RGB_c(S), so an RGB renderer reproduces exactly the first bounce of that light off that
//! surface. The colour-matching table is CIE 1931 at 5 nm (CIE 015:2004, table T.4), 400–700 nm.
//!
//! Colours given as CIE chromaticity (x, y) and luminance Y (as MGF gives them: Ward 1995, "The Materials and
//! Geometry Format") use the same matrix. XYZ = (x Y / y, Y, (1 − x − y) Y / y). An emitter's exitance is
//! E = M · XYZ. A reflectance follows the ratio rule above under the equal-energy white that MGF's
//! reflectances are defined against (XYZ_E = (1, 1, 1)): ρ_c = (M · XYZ_ρ)_c / (M · (1, 1, 1))_c, so a neutral
//! colour (x = y = 1/3) of reflectance Y is Y in every channel. [`linear_srgb_to_xyz`] inverts M exactly
//! (to round-off), so RGB → (x, y, Y) → RGB returns what it was given.

use glam::{DMat3, DVec3};

/// First wavelength of [`CIE_1931_5NM`], nm.
const CMF_START: f64 = 400.0;
/// Spacing of [`CIE_1931_5NM`], nm.
const CMF_STEP: f64 = 5.0;
/// ∫ ȳ(λ) dλ over 360–830 nm at 1 nm (CIE 1931 2°).
const Y_INTEGRAL: f64 = 106.856_895;

/// CIE 1931 2° colour-matching functions x̄, ȳ, z̄ at 400, 405, …, 700 nm.
#[rustfmt::skip]
const CIE_1931_5NM: [[f64; 3]; 61] = [
    [0.01431, 0.000396, 0.06785], [0.02319, 0.00064, 0.1102], [0.04351, 0.00121, 0.2074],
    [0.07763, 0.00218, 0.3713], [0.13438, 0.004, 0.6456], [0.21477, 0.0073, 1.03905],
    [0.2839, 0.0116, 1.3856], [0.3285, 0.01684, 1.62296], [0.34828, 0.023, 1.74706],
    [0.34806, 0.0298, 1.7826], [0.3362, 0.038, 1.77211], [0.3187, 0.048, 1.7441],
    [0.2908, 0.06, 1.6692], [0.2511, 0.0739, 1.5281], [0.19536, 0.09098, 1.28764],
    [0.1421, 0.1126, 1.0419], [0.09564, 0.13902, 0.81295], [0.05795, 0.1693, 0.6162],
    [0.03201, 0.20802, 0.46518], [0.0147, 0.2586, 0.3533], [0.0049, 0.323, 0.272],
    [0.0024, 0.4073, 0.2123], [0.0093, 0.503, 0.1582], [0.0291, 0.6082, 0.1117],
    [0.06327, 0.71, 0.07825], [0.1096, 0.7932, 0.05725], [0.1655, 0.862, 0.04216],
    [0.22575, 0.91485, 0.02984], [0.2904, 0.954, 0.0203], [0.3597, 0.9803, 0.0134],
    [0.43345, 0.99495, 0.00875], [0.51205, 1.0, 0.00575], [0.5945, 0.995, 0.0039],
    [0.6784, 0.9786, 0.00275], [0.7621, 0.952, 0.0021], [0.8425, 0.9154, 0.0018],
    [0.9163, 0.87, 0.00165], [0.9786, 0.8163, 0.0014], [1.0263, 0.757, 0.0011],
    [1.0567, 0.6949, 0.001], [1.0622, 0.631, 0.0008], [1.0456, 0.5668, 0.0006],
    [1.0026, 0.503, 0.00034], [0.9384, 0.4412, 0.00024], [0.85445, 0.381, 0.00019],
    [0.7514, 0.321, 0.0001], [0.6424, 0.265, 5e-05], [0.5419, 0.217, 3e-05],
    [0.4479, 0.175, 2e-05], [0.3608, 0.1382, 1e-05], [0.2835, 0.107, 0.0],
    [0.2187, 0.0816, 0.0], [0.1649, 0.061, 0.0], [0.1212, 0.04458, 0.0],
    [0.0874, 0.032, 0.0], [0.0636, 0.0232, 0.0], [0.04677, 0.017, 0.0],
    [0.0329, 0.01192, 0.0], [0.0227, 0.00821, 0.0], [0.01584, 0.005723, 0.0],
    [0.0113592, 0.004102, 0.0],
];

/// XYZ → linear sRGB (IEC 61966-2-1).
const XYZ_TO_SRGB: [[f64; 3]; 3] = [
    [3.2406, -1.5372, -0.4986],
    [-0.9689, 1.8758, 0.0415],
    [0.0557, -0.2040, 1.0570],
];

/// A spectrum tabulated at increasing wavelengths (nm), linear between samples and zero outside them.
#[derive(Clone, Copy, Debug)]
pub struct Spectrum<'a> {
    /// First wavelength, nm.
    pub start: f64,
    /// Spacing, nm.
    pub step: f64,
    /// Values.
    pub values: &'a [f64],
}

impl Spectrum<'_> {
    /// The value at wavelength `nm` (linear interpolation, zero outside the table).
    pub fn at(&self, nm: f64) -> f64 {
        let n = self.values.len();
        let x = (nm - self.start) / self.step;
        if n == 0 || x < 0.0 || x > (n - 1) as f64 {
            return 0.0;
        }
        let i = (x.floor() as usize).min(n.saturating_sub(2));
        let t = x - i as f64;
        let a = self.values.get(i).copied().unwrap_or(0.0);
        let b = self.values.get(i + 1).copied().unwrap_or(a);
        a + (b - a) * t
    }
}

fn cmf_at(nm: f64) -> DVec3 {
    let x = ((nm - CMF_START) / CMF_STEP).clamp(0.0, (CIE_1931_5NM.len() - 1) as f64);
    let i = (x.floor() as usize).min(CIE_1931_5NM.len() - 2);
    let t = x - i as f64;
    let (a, b) = (
        DVec3::from(CIE_1931_5NM[i]),
        DVec3::from(CIE_1931_5NM[i + 1]),
    );
    a + (b - a) * t
}

/// CIE XYZ of the product of spectra, normalised so a constant 1 has Y = 1 (see the module doc).
pub fn xyz_of_product(spectra: &[Spectrum]) -> DVec3 {
    let mut sum = DVec3::ZERO;
    for k in 0..=300 {
        let nm = 400.0 + k as f64;
        let w = if k == 0 || k == 300 { 0.5 } else { 1.0 };
        let s: f64 = spectra.iter().map(|sp| sp.at(nm)).product();
        sum += cmf_at(nm) * (w * s);
    }
    sum / Y_INTEGRAL
}

/// The matrix M of [`XYZ_TO_SRGB`] as a glam matrix.
fn srgb_matrix() -> DMat3 {
    DMat3::from_cols_array_2d(&XYZ_TO_SRGB).transpose()
}

/// CIE XYZ of chromaticity (x, y) at luminance `big_y`; `y` must be positive.
pub fn xyy_to_xyz(x: f64, y: f64, big_y: f64) -> DVec3 {
    DVec3::new(x * big_y / y, big_y, (1.0 - x - y) * big_y / y)
}

/// CIE XYZ of a linear sRGB triple: M⁻¹ · rgb.
pub fn linear_srgb_to_xyz(rgb: DVec3) -> DVec3 {
    srgb_matrix().inverse() * rgb
}

/// Linear sRGB reflectance of a surface whose reflected colour under equal-energy white is `xyz`:
/// (M · XYZ)_c / (M · (1, 1, 1))_c per channel (see the module doc). Not clamped.
pub fn reflectance_rgb_from_xyz(xyz: DVec3) -> DVec3 {
    let m = srgb_matrix();
    (m * xyz) / (m * DVec3::ONE)
}

/// The XYZ a linear sRGB reflectance has under equal-energy white: the inverse of
/// [`reflectance_rgb_from_xyz`].
pub fn reflectance_xyz_from_rgb(rgb: DVec3) -> DVec3 {
    let m = srgb_matrix();
    m.inverse() * (rgb * (m * DVec3::ONE))
}

/// Chromaticity (x, y) of a spectrum tabulated from `start` nm every `step` nm (zero outside), or `None` if
/// it has no colour in 400–700 nm.
pub fn spectrum_xy(start: f64, step: f64, values: &[f64]) -> Option<(f64, f64)> {
    let xyz = xyz_of_product(&[Spectrum {
        start,
        step,
        values,
    }]);
    let sum = xyz.element_sum();
    (sum > 0.0 && xyz.is_finite()).then(|| (xyz.x / sum, xyz.y / sum))
}

/// Chromaticity (x, y) of a black body at `kelvin` (Planck's law, tabulated every 5 nm over 400–700 nm).
pub fn blackbody_xy(kelvin: f64) -> Option<(f64, f64)> {
    // Planck: M(λ) ∝ λ⁻⁵ / (exp(c₂ / (λ T)) − 1), c₂ = 1.438777e7 nm·K; the scale cancels in (x, y).
    let c2 = 1.438_777e7;
    let values: Vec<f64> = (0..=60)
        .map(|k| {
            let nm = 400.0 + 5.0 * k as f64;
            let r = nm / 550.0;
            1.0 / (r.powi(5) * ((c2 / (nm * kelvin)).exp_m1()))
        })
        .collect();
    spectrum_xy(400.0, 5.0, &values)
}

/// Linear sRGB of an XYZ triple.
pub fn xyz_to_linear_srgb(xyz: DVec3) -> DVec3 {
    let m = XYZ_TO_SRGB;
    DVec3::new(
        m[0][0] * xyz.x + m[0][1] * xyz.y + m[0][2] * xyz.z,
        m[1][0] * xyz.x + m[1][1] * xyz.y + m[1][2] * xyz.z,
        m[2][0] * xyz.x + m[2][1] * xyz.y + m[2][2] * xyz.z,
    )
}

/// Linear sRGB of an emission spectrum (same units as the spectrum; Y = 1 for a constant 1).
pub fn emission_rgb(light: Spectrum) -> DVec3 {
    xyz_to_linear_srgb(xyz_of_product(&[light]))
}

/// Per-channel RGB reflectance of `reflectance` under `light`: RGB(ρ S) / RGB(S), each channel clamped to
/// [0, 0.999].
pub fn reflectance_rgb(reflectance: Spectrum, light: Spectrum) -> DVec3 {
    let lit = emission_rgb(light);
    let seen = xyz_to_linear_srgb(xyz_of_product(&[reflectance, light]));
    let ratio = |s: f64, l: f64| {
        if l > 0.0 {
            (s / l).clamp(0.0, 0.999)
        } else {
            0.0
        }
    };
    DVec3::new(
        ratio(seen.x, lit.x),
        ratio(seen.y, lit.y),
        ratio(seen.z, lit.z),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_energy_white_has_unit_luminance_and_srgb_chromaticity_near_e() {
        // A constant spectrum over 400–700 nm: Y = ∫ȳ(400..700)/∫ȳ(360..830) (≈ 0.9997 from the CIE table).
        let one = [1.0, 1.0];
        let s = Spectrum {
            start: 400.0,
            step: 300.0,
            values: &one,
        };
        let xyz = xyz_of_product(&[s]);
        assert!((xyz.y - 1.0).abs() < 2e-3, "{xyz}");
        // Illuminant E has x = y = 1/3.
        let sum = xyz.x + xyz.y + xyz.z;
        assert!((xyz.x / sum - 1.0 / 3.0).abs() < 3e-3 && (xyz.y / sum - 1.0 / 3.0).abs() < 3e-3);
    }

    #[test]
    fn chromaticity_conversions_round_trip_and_keep_neutral_grey() {
        // Equal-energy white at reflectance 0.4 is 0.4 in every channel.
        let grey = reflectance_rgb_from_xyz(xyy_to_xyz(1.0 / 3.0, 1.0 / 3.0, 0.4));
        assert!(
            (grey - DVec3::splat(0.4)).abs().max_element() < 1e-12,
            "{grey}"
        );
        // RGB → XYZ → RGB, for a reflectance and for an exitance.
        let rgb = DVec3::new(0.6, 0.07, 0.05);
        let back = reflectance_rgb_from_xyz(reflectance_xyz_from_rgb(rgb));
        assert!((back - rgb).abs().max_element() < 1e-12, "{back}");
        let e = DVec3::new(17.0, 12.0, 4.0);
        assert!(
            (xyz_to_linear_srgb(linear_srgb_to_xyz(e)) - e)
                .abs()
                .max_element()
                < 1e-12
        );
        // The sRGB red primary (IEC 61966-2-1: x = 0.64, y = 0.33) has G = B = 0 to the matrix's 4 digits.
        let red = xyz_to_linear_srgb(xyy_to_xyz(0.64, 0.33, 0.2126));
        assert!(
            red.y.abs() < 2e-3 && red.z.abs() < 2e-3 && (red.x - 1.0).abs() < 3e-3,
            "{red}"
        );
        // D65 (x = 0.3127, y = 0.3290) at Y = 1 is white: R = G = B = 1 to the matrix's 4 digits.
        let d65 = xyz_to_linear_srgb(xyy_to_xyz(0.3127, 0.3290, 1.0));
        assert!((d65 - DVec3::ONE).abs().max_element() < 2e-3, "{d65}");
    }

    #[test]
    fn blackbody_chromaticity_matches_the_planckian_locus() {
        // CIE 015:2004: the Planckian locus at 2856 K (illuminant A) is x = 0.4476, y = 0.4074; at 6504 K about
        // (0.3135, 0.3237). The 400–700 nm window moves them by a few thousandths.
        let (x, y) = blackbody_xy(2856.0).expect("colour");
        assert!(
            (x - 0.4476).abs() < 5e-3 && (y - 0.4074).abs() < 5e-3,
            "{x} {y}"
        );
        let (x, y) = blackbody_xy(6504.0).expect("colour");
        assert!(
            (x - 0.3135).abs() < 5e-3 && (y - 0.3237).abs() < 5e-3,
            "{x} {y}"
        );
    }

    #[test]
    fn a_flat_reflectance_keeps_its_value_in_every_channel() {
        let light = [0.0, 8.0, 15.6, 18.4];
        let l = Spectrum {
            start: 400.0,
            step: 100.0,
            values: &light,
        };
        let flat = [0.6, 0.6];
        let r = reflectance_rgb(
            Spectrum {
                start: 400.0,
                step: 300.0,
                values: &flat,
            },
            l,
        );
        assert!((r - DVec3::splat(0.6)).abs().max_element() < 1e-12, "{r}");
    }
}

//! The ambient term of Cohen, Chen, Wallace & Greenberg (1988): an estimate of the light not yet shot, for
//! display while the solution is incomplete.
//!
//! With ρ̄ = Σ_f A_f ρ_f / Σ_f A_f the area-mean reflectance and R = 1/(1 − ρ̄) the interreflection factor
//! (Σ_k ρ̄^k), the ambient radiosity is
//!
//! B_amb = R · Σ_p A_p ΔB_p / Σ_p A_p,
//!
//! and an element is displayed as B_e + ρ_e B_amb. In a closed scene of uniform reflectance whose unshot
//! radiosity is spread evenly (the furnace) this is exactly the light still to arrive; elsewhere it is a
//! rough, view-independent guess that goes to zero as the unshot power does. It never enters the solution
//! itself (shooting and the stopping rule ignore it), which is why it is off for error measurement.

use radlab_scene::{Rgb, Scene};

use crate::substructuring::Patch;

/// The interreflection factor R = 1 / (1 − ρ̄) per channel, ρ̄ the area-weighted mean reflectance.
pub(crate) fn interreflection_factor(scene: &Scene) -> Rgb {
    let area = scene.total_area();
    let rho_mean: Rgb = (0..scene.face_count())
        .map(|f| scene.faces[f].area * scene.reflectance(f))
        .sum::<Rgb>()
        / area;
    // Reflectances are below 1, so the mean is too.
    Rgb::ONE / (Rgb::ONE - rho_mean)
}

/// The ambient radiosity R · Σ_p A_p ΔB_p / Σ_p A_p.
pub(crate) fn ambient_radiosity(patches: &[Patch], interreflection: Rgb) -> Rgb {
    let area: f64 = patches.iter().map(|p| p.open_area).sum();
    if area.is_nan() || area <= 0.0 {
        return Rgb::ZERO;
    }
    let unshot: Rgb = patches.iter().map(|p| p.open_area * p.unshot).sum();
    interreflection * unshot / area
}

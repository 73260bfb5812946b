//! The host's side of Mitsuba's `plastic` (shaders/common/plastic.glsl; its CPU twin is
//! reference/plastic.rs): the diffuse lobe's factor D the material table holds, and the bound on a
//! photon's diffuse bounce that keeps it from gaining flux.

use glam::Vec3;

/// The coat's Fresnel reflectance at normal incidence, ((ior - 1) / (ior + 1))^2: its least.
fn normal_fresnel(ior: f32) -> f32 {
    ((ior - 1.0) / (ior + 1.0)).powi(2)
}

/// Mitsuba's `fresnel_diffuse_reflectance`: the hemispherical average of the Fresnel reflectance for a
/// relative index `eta`, by the fits Mitsuba uses (Egan and Hilgeman 1973 below 1, d'Eon and Irving 2011
/// above, a polynomial in 1 / eta).
pub fn fresnel_diffuse_reflectance(eta: f32) -> f32 {
    if eta < 1.0 {
        0.0636 / eta + eta * (eta * -1.4399 + 0.7099) + 0.6681
    } else {
        let c = [0.919317, -3.4793, 6.75335, -7.80989, 4.98554, -1.36881];
        c.iter().rev().fold(0.0, |acc, &x| acc / eta + x)
    }
}

/// The diffuse lobe's factor D per channel (`Material::color` of a plastic).
pub fn diffuse_factor(diffuse: Vec3, ior: f32, nonlinear: bool) -> Vec3 {
    let fdr_int = fresnel_diffuse_reflectance(1.0 / ior);
    let inner = if nonlinear {
        Vec3::ONE - diffuse * fdr_int
    } else {
        Vec3::splat(1.0 - fdr_int)
    };
    diffuse / inner / (ior * ior)
}

/// The largest weight a cosine-sampled diffuse bounce gives: max D (1 - F(1)), F smallest at normal
/// incidence (`Material::lobe_b[0]`). The photons choose the diffuse lobe with (1 - F(cos_i)) times this.
pub fn diffuse_bound(diffuse: Vec3, ior: f32, nonlinear: bool) -> f32 {
    diffuse_factor(diffuse, ior, nonlinear).max_element() * (1.0 - normal_fresnel(ior))
}

/// The largest diffuse_reflectance per channel for which [`diffuse_bound`] stays at most 1, so that no
/// photon leaves a plastic with more flux than it arrived with (the fixed-point sums rely on it). Mitsuba's
/// model allows more (up to 1): above this the per-sample weight of a cosine-sampled bounce exceeds 1
/// although the albedo does not.
pub fn max_diffuse_reflectance(ior: f32, nonlinear: bool) -> f32 {
    let fdr_int = fresnel_diffuse_reflectance(1.0 / ior);
    // D (1 - F0) = 1, with D = rd / inner / ior^2.
    let c = ior * ior / (1.0 - normal_fresnel(ior));
    let rd = if nonlinear {
        c / (1.0 + c * fdr_int)
    } else {
        c * (1.0 - fdr_int)
    };
    rd.min(1.0)
}

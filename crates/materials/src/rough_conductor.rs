//! Mitsuba's `roughconductor` (shaders/materials/rough_conductor.glsl): smooth-conductor facets
//! (conductor.rs) oriented by a microfacet distribution (microfacet.rs), sampled by the visible normals.
//! What of it needs no material record: its density and the bound of a glossy hit point's BRDF. Its value
//! and sampler read the record's colour and complex index, so they are the CPU twin's
//! (the engine's reference/rough_conductor.rs, whose tests check all of it against Mitsuba's own).

use glam::Vec3;

use crate::math::PI;
use crate::Microfacet;

/// The density of the sampled wo (the CPU twin's `sample`): the visible normals' density times the
/// reflection's Jacobian 1 / (4 wo.h).
pub fn pdf(mf: &Microfacet, wi: Vec3, wo: Vec3) -> f32 {
    if wi.z <= 0.0 || wo.z <= 0.0 {
        return 0.0;
    }
    let h = (wi + wo).normalize();
    mf.visible_pdf(wi, h) / (4.0 * wo.dot(h))
}

/// The bound of a glossy hit point's BRDF over ks / (4 cos_o): D's peak (1 / (pi alpha^2) for smooth
/// enough distributions) times the supremum of G1(v) / cos_v (2 / min(alpha, 2) for GGX; 3.535 / alpha + 1
/// for Beckmann's fit), as rough_conductor.glsl's `rough_conductor_bound`.
pub fn bound(mf: &Microfacet) -> f32 {
    let a2 = mf.alpha * mf.alpha_v;
    // D's peak over 1 / (pi alpha^2): at the normal for GGX up to alpha 1 and Beckmann up to 1 / sqrt(2),
    // beyond at grazing (GGX: alpha^4) or at tan^2 = 2 alpha^2 - 1 (Beckmann).
    let peak = match (mf.ggx, a2 > 0.5) {
        (true, _) => (a2 * a2).max(1.0),
        (false, true) => 4.0 * a2 * a2 * (1.0 / a2 - 2.0).exp(),
        (false, false) => 1.0,
    };
    let gb = if mf.ggx {
        2.0 / mf.alpha.min(2.0)
    } else {
        3.535 / mf.alpha + 1.0
    };
    gb * peak / (PI * a2)
}

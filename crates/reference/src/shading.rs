//! Smooth shading, as `shaders/common/shading.glsl`: the shading normal of a hit, which directions take
//! part, and Veach's correction for photons (the reasons are in the GLSL).

use glam::Vec3;

use super::trace::Hit;

/// The shading normal of `h` on the side of `ng` (its geometric normal turned towards the ray); `ng`
/// where the triangle is flat or its vertex normals cancel.
pub fn normal(h: &Hit, ng: Vec3) -> Vec3 {
    match h.smooth {
        Some(n) if n.dot(ng) < 0.0 => -n,
        Some(n) => n,
        None => ng,
    }
}

/// Whether direction `w` (either way along it) lies on the same side of `ng` and `ns`.
pub fn valid(w: Vec3, ng: Vec3, ns: Vec3) -> bool {
    w.dot(ng) * w.dot(ns) > 0.0
}

/// A record's factor, |wi . ns| / |wi . ng|.
pub fn factor_in(wi: Vec3, ng: Vec3, ns: Vec3) -> f32 {
    wi.dot(ns).abs() / wi.dot(ng).abs()
}

/// The factor of a photon leaving along `wo`: |wo . ng| / |wo . ns|.
pub fn factor_out(wo: Vec3, ng: Vec3, ns: Vec3) -> f32 {
    wo.dot(ng).abs() / wo.dot(ns).abs()
}

/// A photon's flux held at `layout::FLUX_CAP_FIXED` fixed-point units (photon.comp's `capped`); the
/// bool: whether it was.
pub fn capped(flux: Vec3, flux_fixed: f32) -> (Vec3, bool) {
    let cap = ppm_vk_kernels::layout::FLUX_CAP_FIXED as f32 / flux_fixed;
    match flux.max_element() > cap {
        true => (flux.min(Vec3::splat(cap)), true),
        false => (flux, false),
    }
}

//! CPU twin of shaders/materials/rough_dielectric.glsl's bounce: Mitsuba's `roughdielectric` at a hit, its
//! sampler (and value and density, checked against Mitsuba's there) ppm_vk_materials::rough_dielectric's.

use glam::{Vec2, Vec3};
use ppm_vk_kernels::layout::Material;
use ppm_vk_materials::math::{frame, to_local};
use ppm_vk_materials::rough_dielectric::sample;

use super::microfacet;
use super::trace::offset_ray;
use ppm_vk_engine::lower::GpuScene;

/// common/lobe_bounce.glsl, rough glass: the new origin, direction and weight of a path
/// arriving along `d` at `pos` (`nf` facing it, `front` if from outside); a zero weight ends the path.
#[allow(clippy::too_many_arguments)]
pub fn bounce(
    g: &GpuScene,
    m: &Material,
    pos: Vec3,
    nf: Vec3,
    dpdu: Vec3,
    front: bool,
    u: f32,
    u2: Vec2,
    d: Vec3,
) -> (Vec3, Vec3, f32) {
    let (t, b) = frame(nf, dpdu);
    let wi = -to_local(d, t, b, nf);
    match sample(&microfacet::of(m), m.ior, front, wi, u, u2) {
        Some((wo, w)) => {
            let side = if wo.z > 0.0 { nf } else { -nf };
            (
                offset_ray(g, pos, side),
                (wo.x * t + wo.y * b + wo.z * nf).normalize(),
                w,
            )
        }
        None => (pos, d, 0.0),
    }
}

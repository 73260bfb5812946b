//! CPU twin of shaders/materials/thin_dielectric.glsl's branch: Mitsuba's `thindielectric` at a hit, its
//! reflection probability (checked against Mitsuba's there) ppm_vk_materials::thin_dielectric's.

use glam::Vec3;
use ppm_vk_kernels::layout::Material;
use ppm_vk_materials::math::{reflect, v3};
/// The reflection probability, where the twin's eye pass splits a pane's two branches.
pub use ppm_vk_materials::thin_dielectric::reflectance;

use super::trace::offset_ray;
use ppm_vk_engine::lower::GpuScene;

/// thin_dielectric.glsl's `thin_branch`: for uniform `u`, reflection (weight specular_reflectance, in
/// `Material::color`) or transmission straight on (specular_transmittance, `Material::lobe_a`), `nf`
/// facing the incoming direction `d`. Returns the new origin, direction and the weight.
pub fn branch(g: &GpuScene, m: &Material, pos: Vec3, nf: Vec3, u: f32, d: Vec3) -> (Vec3, Vec3, Vec3) {
    if u < reflectance(-d.dot(nf), m.ior) {
        (offset_ray(g, pos, nf), reflect(d, nf), v3(m.color))
    } else {
        (offset_ray(g, pos, -nf), d, v3(m.lobe_a))
    }
}

//! CPU twin of shaders/materials/conductor.glsl's reflectors at a hit: the mirror, and Mitsuba's `conductor`
//! with its Fresnel term (ppm_vk_materials::conductor, checked there against Mitsuba's own conductor).

use glam::Vec3;
use ppm_vk_kernels::layout::{Material, SURFACE_CONDUCTOR, SURFACE_MIRROR};
use ppm_vk_materials::conductor::fresnel_conductor;
use ppm_vk_materials::math::v3;

pub fn is_reflector(surface: u32) -> bool {
    surface == SURFACE_MIRROR || surface == SURFACE_CONDUCTOR
}

/// What a specular bounce off `m` at incidence `cos_i` leaves of the throughput or flux.
pub fn reflector_weight(m: &Material, cos_i: f32) -> Vec3 {
    match m.surface {
        SURFACE_MIRROR => v3(m.color),
        _ => v3(m.color) * fresnel_conductor(cos_i.clamp(0.0, 1.0), v3(m.lobe_a), v3(m.lobe_b)),
    }
}

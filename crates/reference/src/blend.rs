//! CPU twin of shaders/materials/blend.glsl: a hit's material with its blends resolved, one component
//! chosen per blend from the path's random numbers (the choice's math: ppm_vk_materials::blend).

use ppm_vk_kernels::layout::{MAX_BLEND_DEPTH, SURFACE_BLEND};
use ppm_vk_materials::blend::{luminance, second};
use ppm_vk_materials::math::v3;

use crate::rng::Rng;
use crate::texture;
use crate::trace::Hit;
use ppm_vk_engine::lower::GpuScene;

/// blend.glsl's `resolve_blend`.
pub fn resolve(g: &GpuScene, h: &mut Hit, rng: &mut Rng) {
    for _ in 0..MAX_BLEND_DEPTH {
        let m = &g.materials[h.material as usize];
        if m.surface != SURFACE_BLEND {
            return;
        }
        let w = match m.texture {
            0 => m.ior,
            t => luminance(texture::value(&g.textures, t - 1, h.uv)),
        };
        let [first, other, _] = v3(m.lobe_a).to_array().map(f32::to_bits);
        h.material = if second(w, || rng.float()) { other } else { first };
    }
}

//! CPU twin of shaders/materials/mask.glsl: whether a ray stops at a masked surface, decided by the same
//! hash (ppm_vk_materials::mask) of the ray, the primitive and the render's seed.

use glam::Vec2;
use ppm_vk_engine::lower::GpuScene;
use ppm_vk_materials::mask;
use ppm_vk_materials::rng::Rng;

/// `mask_key`: the key a ray about to be traced draws from its path's stream (0, drawing nothing, in a
/// scene without masks).
pub fn key(g: &GpuScene, rng: &mut Rng) -> u32 {
    if g.params.masks != 0 {
        rng.next_u32()
    } else {
        0
    }
}

/// `mask_keeps`: whether the ray of key `key` stops where it meets material `m` at texture coordinates
/// `uv` (computed only for a masked material), as primitive `prim` (mask::PRIM_*).
pub fn keeps(g: &GpuScene, m: u32, key: u32, prim: u32, uv: impl FnOnce() -> Vec2) -> bool {
    let at = g.materials[m as usize].opacity;
    if at == 0 {
        return true;
    }
    let opacity = mask::luminance(super::texture::value(&g.textures, at - 1, uv()));
    mask::keeps(opacity, mask::uniform(key, prim))
}

#[cfg(test)]
mod tests {
    /// The host's primitive keys are the kernels' (reflected from geometry.glsl).
    #[test]
    fn primitive_keys_match_the_glsl() {
        use ppm_vk_kernels::reflected::constants::{MASK_PRIM_QUAD, MASK_PRIM_SPHERE};
        assert_eq!(ppm_vk_materials::mask::PRIM_QUAD, MASK_PRIM_QUAD);
        assert_eq!(ppm_vk_materials::mask::PRIM_SPHERE, MASK_PRIM_SPHERE);
    }
}

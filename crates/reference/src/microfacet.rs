//! The microfacet distribution of a material record, as the kernels read it (microfacet.glsl); the
//! distribution's math is ppm_vk_materials::microfacet.

use ppm_vk_kernels::layout::{Material, MICROFACET_GGX};
use ppm_vk_materials::Microfacet;

/// The distribution of material `m` (its fifth texel).
pub fn of(m: &Material) -> Microfacet {
    Microfacet {
        ggx: m.distribution == MICROFACET_GGX,
        alpha: m.alpha_u,
        alpha_v: m.alpha_v,
    }
}

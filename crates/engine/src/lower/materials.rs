//! The material table: each scene material as the kernels' `Material` record (types.glsl says which
//! fields each surface reads).

use glam::Vec3;
use ppm_vk_kernels::layout::{self, Material};
use ppm_vk_materials::plastic;

use crate::scene::{Microfacet, NormalMap, Scene, Surface};

/// The records of `scene`'s materials, in order. `texture_at` is the texel of each texture's header;
/// rough plastics' coat tables are appended to `textures`, one per material (each distinct coat made once).
pub fn materials(scene: &Scene, texture_at: &[u32], textures: &mut Vec<[u32; 4]>) -> Vec<Material> {
    let mut coats = plastic::Coats::default();
    scene
        .materials
        .iter()
        .map(|m| material(m, texture_at, textures, &mut coats))
        .collect()
}

/// The record of material `m`: one arm per surface, each writing all the fields that surface reads;
/// the others stay zero. A plastic's coat comes from `coats`.
fn material(
    m: &crate::scene::Material,
    texture_at: &[u32],
    textures: &mut Vec<[u32; 4]>,
    coats: &mut plastic::Coats,
) -> Material {
    let base = Material {
        emission: m.emission.to_array(),
        texture: header(m.texture, texture_at),
        normal_map: m.normal_map.map_or(0, |n| push_normal_map(textures, n, texture_at)),
        opacity: header(m.opacity, texture_at),
        specular_texture: header(m.specular_texture, texture_at),
        alpha_texture: header(m.alpha_texture, texture_at),
        emission_texture: header(m.emission_texture, texture_at),
        ..Default::default()
    };
    match m.surface {
        Surface::Diffuse { albedo } => Material {
            color: albedo.to_array(),
            surface: layout::SURFACE_DIFFUSE,
            ior: 1.0,
            ..base
        },
        Surface::Mirror { reflectance } => Material {
            color: reflectance.to_array(),
            surface: layout::SURFACE_MIRROR,
            ior: 1.0,
            ..base
        },
        Surface::Conductor { reflectance, eta, k } => Material {
            color: reflectance.to_array(),
            surface: layout::SURFACE_CONDUCTOR,
            ior: 1.0,
            lobe_a: eta.to_array(),
            lobe_b: k.to_array(),
            ..base
        },
        Surface::Glass { ior } => Material {
            color: Vec3::ONE.to_array(),
            surface: layout::SURFACE_GLASS,
            ior,
            ..base
        },
        Surface::Plastic {
            diffuse,
            specular,
            ior,
            nonlinear,
            rough,
        } => {
            // The coat (ppm_vk_materials::plastic): a rough one's transmittance table goes after the textures.
            let coat = coats.coat(ior, rough);
            let table = match coat.table.as_ref() {
                Some(t) => push_table(textures, t),
                None => 0,
            };
            Material {
                color: plastic::diffuse_factor(diffuse, ior, nonlinear, coat.internal).to_array(),
                surface: layout::SURFACE_PLASTIC,
                ior,
                lobe_a: specular.to_array(),
                lobe_b: [
                    plastic::diffuse_bound(diffuse, ior, nonlinear, coat),
                    coat.internal,
                    nonlinear as u32 as f32,
                ],
                table,
                ..with_microfacet(base, rough)
            }
        }
        Surface::ThinDielectric {
            ior,
            reflectance,
            transmittance,
        } => Material {
            color: reflectance.to_array(),
            surface: layout::SURFACE_THIN,
            ior,
            lobe_a: transmittance.to_array(),
            ..base
        },
        Surface::RoughConductor {
            reflectance,
            eta,
            k,
            rough,
        } => Material {
            color: reflectance.to_array(),
            surface: layout::SURFACE_ROUGH_CONDUCTOR,
            ior: 1.0,
            lobe_a: eta.to_array(),
            lobe_b: k.to_array(),
            ..with_microfacet(base, Some(rough))
        },
        Surface::RoughGlass { ior, rough } => Material {
            color: Vec3::ONE.to_array(),
            surface: layout::SURFACE_ROUGH_GLASS,
            ior,
            ..with_microfacet(base, Some(rough))
        },
        // blend.glsl: the weight, its texture (`base.texture`) and the components' indices as lobe_a's bits.
        Surface::Blend { weight, first, second } => Material {
            surface: layout::SURFACE_BLEND,
            ior: weight,
            lobe_a: [f32::from_bits(first), f32::from_bits(second), 0.0],
            ..base
        },
    }
}

// blend.glsl resolves as many levels as the scene lets blends nest.
const _: () = assert!(layout::MAX_BLEND_DEPTH == ppm_vk_materials::blend::MAX_BLEND_DEPTH);

/// A material's reference to texture `t` (an index into `Scene::textures`): 0 for none, else 1 + the
/// texel of its header.
fn header(t: Option<u32>, texture_at: &[u32]) -> u32 {
    t.map_or(0, |t| texture_at[t as usize] + 1)
}

/// `base` with a microfacet distribution's roughness and kind; a smooth surface (`None`) keeps zeros.
fn with_microfacet(base: Material, rough: Option<Microfacet>) -> Material {
    Material {
        alpha_u: rough.map_or(0.0, |r| r.alpha),
        alpha_v: rough.map_or(0.0, |r| r.alpha_v),
        distribution: rough.map_or(0, |r| match r.ggx {
            true => layout::MICROFACET_GGX,
            false => layout::MICROFACET_BECKMANN,
        }),
        ..base
    }
}

/// Appends a bump or normal map's record to the texture buffer (normal_map.glsl: its kind, its texture's
/// header, a bump map's scale); returns 1 + its texel (`Material::normal_map`).
fn push_normal_map(textures: &mut Vec<[u32; 4]>, n: NormalMap, texture_at: &[u32]) -> u32 {
    let (kind, scale) = match n {
        NormalMap::Bump { scale, .. } => (layout::NORMAL_MAP_BUMP, scale),
        NormalMap::Normal { .. } => (layout::NORMAL_MAP_NORMAL, 0.0),
    };
    textures.push([kind, texture_at[n.texture() as usize], scale.to_bits(), 0]);
    textures.len() as u32
}

/// Appends a coat's transmittance table to the texture buffer, four values a texel (plastic.glsl's
/// coat_transmittance reads it); returns 1 + its first texel (`Material::table`).
fn push_table(textures: &mut Vec<[u32; 4]>, table: &[f32]) -> u32 {
    let at = textures.len() as u32 + 1;
    textures.extend(table.chunks(4).map(|c| {
        let mut texel = [0u32; 4];
        for (k, v) in c.iter().enumerate() {
            texel[k] = v.to_bits();
        }
        texel
    }));
    at
}

//! Textures on specular_reflectance and on a rough bsdf's alpha (issue 37; shaders/common/texture.glsl's
//! apply_parameter_textures): against Mitsuba 3 on scenes/textured-params.xml, and a constant texture
//! against the constant it holds. The kernels against their CPU twin: tests/kernels.rs
//! (`..._with_parameter_textures`).

mod common;

use common::*;
use glam::Vec3;
use ppm_vk_engine::scene::texture::{Filter, Pattern, Texture, Wrap, IDENTITY_UV};
use ppm_vk_engine::scene::{Microfacet, Surface};
use ppm_vk_engine::{Scene, Settings};

/// Mitsuba 3 on scenes/textured-params.xml (a roughconductor whose alpha is a bitmap, a GGX
/// roughconductor whose specular_reflectance is a checkerboard and a conductor whose
/// specular_reflectance is that bitmap, under an area light; its reference:
/// scenes/references/textured-params.txt, made by make_reference.py): the image's mean within 1% per
/// channel, and each plane's (the image's thirds; measured: image -0.13% at most, thirds 0.23%).
#[test]
fn parameter_textures_match_mitsuba() {
    let scene = mitsuba_scene("textured-params", &[]);
    assert_eq!(
        scene.materials.iter().filter(|m| m.alpha_texture.is_some()).count()
            + scene.materials.iter().filter(|m| m.specular_texture.is_some()).count(),
        3
    );
    let (image, want) = against_mitsuba(&scene, "textured-params", 12);
    let (w, h) = (image.width, image.height);
    // Measured within 0.25% (SPPM, 12 x 200k photons).
    for k in 0..3 {
        let third = |img| window_mean(img, k * w / 3..(k + 1) * w / 3, 0..h);
        assert_means_within(&format!("third {k}"), third(&image), third(&want), 0.01);
    }
    assert_means_within("image", image.mean(), want.mean(), 0.01);
}

/// A texture whose every value is the surface's constant renders bit for bit as the constant: a 1 x 1
/// bitmap on the specular_reflectance of a conductor, a rough conductor and a thin dielectric, and on the
/// alpha of a rough conductor and rough glass (its value grey, the constant alpha its luminance; glossy hit points off, since a textured alpha never holds them).
#[test]
fn a_constant_texture_renders_as_its_constant() {
    let text = std::fs::read_to_string(format!("{}/scenes/cornell-spheres.toml", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let mut plain = Scene::parse(&text, "cornell-spheres.toml").unwrap();
    plain.camera.width = 48;
    plain.camera.height = 48;
    let (eta, k) = ppm_vk_engine::scene::conductors::named("Cu").unwrap();
    // 0.5 times each luminance weight is exact, so the kernels' dot product gives the f32 sum below in
    // any order of its terms that the host's takes.
    let grey = 0.5f32;
    let y = Vec3::new(0.212671, 0.715160, 0.072169);
    let alpha = Vec3::splat(grey).dot(y);
    let reflectance = Vec3::new(0.9, 0.7, 0.5);
    // Spheres and walls turned into the surfaces that read these textures.
    let surfaces = [
        Surface::Conductor { reflectance, eta, k },
        Surface::RoughConductor {
            reflectance,
            eta,
            k,
            rough: Microfacet::isotropic(true, alpha),
        },
        Surface::RoughGlass {
            ior: 1.5,
            rough: Microfacet::isotropic(false, alpha),
        },
        Surface::ThinDielectric {
            ior: 1.5,
            reflectance,
            transmittance: Vec3::new(0.8, 0.9, 1.0),
        },
    ];
    // The three spheres' materials (mirror, blue, glass) and the red wall's.
    let mut users: Vec<u32> = plain.spheres.iter().map(|s| s.material).collect();
    users.push(plain.materials.iter().position(|m| m.name == "red").unwrap() as u32);
    assert_eq!(users.len(), surfaces.len());
    for (m, surface) in users.iter().zip(surfaces) {
        plain.materials[*m as usize].surface = surface;
    }
    let mut textured = plain.clone();
    let one = |v: Vec3| Texture {
        name: "constant".into(),
        pattern: Pattern::Bitmap {
            width: 1,
            height: 1,
            pixels: vec![v],
        },
        filter: Filter::Nearest, // exactly the pixel (bilinear weights may round it by an ulp)
        wrap: Wrap::Repeat,
        to_uv: IDENTITY_UV,
    };
    textured.textures.extend([one(reflectance), one(Vec3::splat(grey))]);
    let (spec, rough) = (textured.textures.len() as u32 - 2, textured.textures.len() as u32 - 1);
    for m in &mut textured.materials {
        match m.surface {
            Surface::Conductor { .. } | Surface::ThinDielectric { .. } => m.specular_texture = Some(spec),
            Surface::RoughConductor { .. } => {
                m.specular_texture = Some(spec);
                m.alpha_texture = Some(rough);
            }
            Surface::RoughGlass { .. } => m.alpha_texture = Some(rough),
            _ => {}
        }
    }
    textured.validate().unwrap_or_else(|e| panic!("{e:#}"));
    assert_eq!(
        textured
            .materials
            .iter()
            .filter(|m| m.specular_texture.is_some())
            .count(),
        3
    );
    assert_eq!(
        textured.materials.iter().filter(|m| m.alpha_texture.is_some()).count(),
        2
    );
    let settings = Settings {
        photons_per_pass: 20_000,
        glossy_hits: None,
        ..Settings::default()
    };
    let ctx = ctx();
    let a = render(&ctx, &plain, settings.clone(), 2);
    let b = render(&ctx, &textured, settings, 2);
    assert_clean(&ctx);
    let lit = a.pixels.iter().filter(|p| p.iter().any(|c| *c > 0.0)).count();
    assert!(lit > a.pixels.len() / 2, "{lit} pixels lit");
    assert!(a.pixels == b.pixels, "the textured scene differs from the constant one");
}

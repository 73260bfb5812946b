//! A texture on an area emitter's `radiance` (issue 37, as Mitsuba 3's src/emitters/area.cpp): a render
//! against Mitsuba's path tracer on scenes/textured-light.xml (its reference made by make_reference.py,
//! its texture by textured_light.py) and the invariance that a constant texture is the constant.

mod common;

use std::path::Path;

use common::{against_mitsuba, assert_clean, assert_means_within, ctx, render};
use glam::Vec3;
use ppm_vk_engine::scene::texture::{Filter, Pattern, Texture, Wrap, IDENTITY_UV};
use ppm_vk_engine::{Mode, Scene, Settings};

fn load(name: &str) -> Scene {
    let root = env!("CARGO_MANIFEST_DIR");
    let scene = Scene::load(Path::new(&format!("{root}/scenes/{name}.xml"))).unwrap_or_else(|e| panic!("{e:#}"));
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    scene
}

fn textured_light() -> Scene {
    load("textured-light")
}

/// `name`'s render (SPPM, 8 x 200k photons) against its Mitsuba reference: the image's mean per channel
/// within 1%.
fn matches_mitsuba(name: &str, scene: &Scene) {
    let (image, want) = against_mitsuba(scene, name, 8);
    assert_means_within(name, image.mean(), want.mean(), 0.01);
}

fn settings() -> Settings {
    Settings {
        mode: Mode::Sppm,
        photons_per_pass: 200_000,
        ..Settings::default()
    }
}

/// A 1 x 1 m light whose radiance is an 8 x 8 EXR (half black, half up to 18) over a diffuse floor, seen
/// with the light's face in view: eye rays see Le(uv), shadow rays and photons take it at their points.
/// The image's mean per channel within 1% of Mitsuba's.
#[test]
fn textured_light_matches_mitsuba() {
    let scene = textured_light();
    let light = scene
        .materials
        .iter()
        .find(|m| m.emission_texture.is_some())
        .expect("a textured light");
    assert_eq!(
        light.emission,
        Vec3::new(18.0, 6.0, 10.0),
        "the texture's largest values"
    );
    matches_mitsuba("textured-light", &scene);
}

/// The same light as an OBJ square of two triangles (scenes/textured-light-mesh.xml): a mesh light, Le at
/// its triangles' interpolated texture coordinates.
#[test]
fn textured_mesh_light_matches_mitsuba() {
    let scene = load("textured-light-mesh");
    assert!(
        scene.meshes.iter().any(|m| m.uvs.is_some()),
        "a mesh with texture coordinates"
    );
    matches_mitsuba("textured-light-mesh", &scene);
}

/// A radiance texture that is one colour everywhere renders as that constant radiance: pixel by pixel
/// within 1e-6 relative (the photons' flux is (A pi) Le / prob instead of (Le A pi) / prob, rounded
/// differently in f32; a checkerboard of one colour returns it exactly, so the rest is bit for bit).
#[test]
fn a_constant_radiance_texture_renders_as_the_constant() {
    let le = Vec3::new(3.0, 2.0, 0.5);
    let mut textured = textured_light();
    let m = textured
        .materials
        .iter()
        .position(|m| m.emission_texture.is_some())
        .unwrap();
    textured.textures.push(Texture {
        name: "constant".into(),
        pattern: Pattern::Checkerboard { color0: le, color1: le },
        filter: Filter::Bilinear,
        wrap: Wrap::Repeat,
        to_uv: IDENTITY_UV,
    });
    textured.materials[m].emission_texture = Some(textured.textures.len() as u32 - 1);
    textured.materials[m].emission = le;
    textured.validate().unwrap_or_else(|e| panic!("{e:#}"));
    let mut constant = textured.clone();
    constant.materials[m].emission_texture = None;
    let ctx = ctx();
    let settings = Settings {
        photons_per_pass: 50_000,
        ..settings()
    };
    let a = render(&ctx, &textured, settings.clone(), 2);
    let b = render(&ctx, &constant, settings, 2);
    assert_clean(&ctx);
    let mut worst = 0f64;
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        for c in 0..3 {
            let (x, y) = (p[c] as f64, q[c] as f64);
            worst = worst.max((x - y).abs() / y.abs().max(1e-3));
        }
    }
    println!("constant texture against the constant: worst relative difference {worst:e}");
    assert!(worst < 1e-6, "{worst}");
    assert!(b.mean().iter().all(|&x| x > 0.0));
}

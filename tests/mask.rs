//! Mitsuba's `mask` and `null` on the GPU (shaders/materials/mask.glsl): a surface there with probability
//! `opacity`, in eye rays, photons and shadow rays alike. Checked against a closed form (the shadow of a
//! half-transparent pane) and two invariances, bit for bit: opacity 1 renders the scene without the mask,
//! opacity 0 the scene without the surface. (GPU against the CPU twin: tests/kernels.rs, `..._with_masks`;
//! against Mitsuba 3: `masks_match_mitsuba` below.)

mod common;

use common::*;
use glam::Vec3;
use ppm_vk_engine::scene::texture::{Filter, Pattern, Texture, Wrap, IDENTITY_UV};
use ppm_vk_engine::scene::{Material, Mesh, Quad, Surface};
use ppm_vk_engine::{DirectLight, RgbImage, Scene, Settings};

const RES: u32 = 24;

fn settings() -> Settings {
    Settings {
        photons_per_pass: 4_000,
        seed: 11,
        emission_samples: 2,
        rough_samples: 2,
        light_samples: 2,
        ..Settings::default()
    }
}

/// A constant opacity, as the Mitsuba reader makes one: a checkerboard of two equal colours.
fn opacity(v: f32) -> Texture {
    Texture {
        name: format!("opacity {v}"),
        pattern: Pattern::Checkerboard {
            color0: Vec3::splat(v),
            color1: Vec3::splat(v),
        },
        filter: Filter::Bilinear,
        wrap: Wrap::Repeat,
        to_uv: IDENTITY_UV,
    }
}

/// A material of `surface` masked by texture `opacity`.
fn masked(name: &str, surface: Surface, opacity: u32) -> Material {
    Material {
        name: name.into(),
        surface,
        emission: Vec3::ZERO,
        texture: None,
        normal_map: None,
        opacity: Some(opacity),
        specular_texture: None,
        alpha_texture: None,
        emission_texture: None,
    }
}

fn mean(image: &RgbImage) -> f64 {
    image.pixels.iter().flatten().map(|&v| v as f64).sum::<f64>() / (3 * image.pixels.len()) as f64
}

/// Every surface of the paper's scene (quads, spheres, the light's quad included) given opacity 1 renders
/// its image bit for bit: a surface of opacity 1 stops every ray, and draws no random number.
#[test]
fn opacity_one_is_the_surface_opaque_bit_for_bit() {
    let ctx = ctx();
    let plain = cornell(RES, RES);
    let mut with = plain.clone();
    with.textures.push(opacity(1.0));
    let t = (with.textures.len() - 1) as u32;
    for m in with.materials.iter_mut().filter(|m| !m.is_light()) {
        m.opacity = Some(t);
    }
    with.validate().unwrap_or_else(|e| panic!("{e:#}"));
    assert_ne!(
        plain.content_sha256(),
        with.content_sha256(),
        "the mask is part of the scene's hash"
    );
    let a = render(&ctx, &plain, settings(), 2);
    let b = render(&ctx, &with, settings(), 2);
    assert!(mean(&a) > 0.01, "a dark image proves nothing");
    assert_eq!(pixels_sha256(&a), pixels_sha256(&b), "opacity 1 changed the image");
    assert_clean(&ctx);
}

/// A pane of quads, a sphere and a mesh of opacity 0 (Mitsuba's null bsdf) put in the paper's scene, where
/// they would block the light and the view, render its image bit for bit: every ray passes them.
#[test]
fn opacity_zero_is_the_surface_removed_bit_for_bit() {
    let ctx = ctx();
    let plain = cornell(RES, RES);
    let mut with = plain.clone();
    with.textures.push(opacity(0.0));
    let t = (with.textures.len() - 1) as u32;
    with.materials.push(masked(
        "null",
        Surface::Diffuse {
            albedo: Vec3::splat(0.8),
        },
        t,
    ));
    let null = (with.materials.len() - 1) as u32;
    with.quads.push(Quad {
        origin: Vec3::new(-0.8, 0.1, 0.0),
        edge_u: Vec3::new(1.6, 0.0, 0.0),
        edge_v: Vec3::new(0.0, 1.7, 0.0),
        material: null,
        disk: false,
    });
    with.spheres.push(ppm_vk_engine::scene::Sphere {
        center: Vec3::new(0.0, 1.5, 0.5),
        radius: 0.3,
        material: null,
    });
    with.meshes.push(Mesh::with_material(
        "null mesh",
        vec![
            Vec3::new(-0.9, 1.9, -0.9),
            Vec3::new(0.9, 1.9, -0.9),
            Vec3::new(0.0, 1.9, 0.9),
        ],
        vec![[0, 1, 2]],
        null,
    ));
    with.validate().unwrap_or_else(|e| panic!("{e:#}"));
    let a = render(&ctx, &plain, settings(), 2);
    let b = render(&ctx, &with, settings(), 2);
    assert!(mean(&a) > 0.01, "a dark image proves nothing");
    assert_eq!(pixels_sha256(&a), pixels_sha256(&b), "opacity 0 changed the image");
    assert_clean(&ctx);
}

/// A black pane of opacity a between a floor and a square light, wide enough that every line from the
/// floor's visible patch to the light crosses it: the floor's irradiance is (1 - a) E, E the square's
/// closed form (tests/stability.rs: irradiance_under_a_square_light_matches_its_closed_form). Photons,
/// shadow rays, and the pane as two triangles of a mesh through the BVH (a bitmap of the same opacity).
#[test]
fn a_half_transparent_pane_lets_through_one_minus_its_opacity() {
    let (le, a, h, rho) = (10.0f64, 0.2f64, 1.0f64, 0.5f64);
    let x = a / (2.0 * h);
    let q = x / (1.0 + x * x).sqrt() * (x / (1.0 + x * x).sqrt()).atan();
    let f = 4.0 * (2.0 * q) / (2.0 * std::f64::consts::PI);
    let open = rho / std::f64::consts::PI * std::f64::consts::PI * le * f;
    let alpha = 0.3f32;
    let want = open * (1.0 - alpha as f64);
    let base = Scene::parse(OPEN_FLOOR, "open-floor.toml").unwrap();
    // The pane 0.25 below the light (the camera is at 0.5), 1 m wide: the floor's patch sees the light
    // through it alone.
    let pane = |mesh: bool| {
        let mut s = base.clone();
        s.textures.push(match mesh {
            false => opacity(alpha),
            true => Texture {
                name: "opacity bitmap".into(),
                pattern: Pattern::Bitmap {
                    width: 2,
                    height: 2,
                    pixels: vec![Vec3::splat(alpha); 4],
                },
                filter: Filter::Nearest,
                wrap: Wrap::Repeat,
                to_uv: IDENTITY_UV,
            },
        });
        s.materials
            .push(masked("pane", Surface::Diffuse { albedo: Vec3::ZERO }, 0));
        let m = (s.materials.len() - 1) as u32;
        let (o, u, v) = (
            Vec3::new(-0.5, 0.75, -0.5),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
        );
        if mesh {
            let mut pane = Mesh::with_material("pane", vec![o, o + u, o + u + v, o + v], vec![[0, 1, 2], [0, 2, 3]], m);
            pane.uvs = Some(vec![glam::Vec2::ZERO; 4]);
            s.meshes.push(pane);
        } else {
            s.quads.push(Quad {
                origin: o,
                edge_u: u,
                edge_v: v,
                material: m,
                disk: false,
            });
        }
        s.validate().unwrap_or_else(|e| panic!("{e:#}"));
        s
    };
    let ctx = ctx();
    let settings = |direct| Settings {
        mode: ppm_vk_engine::Mode::Ppm,
        photons_per_pass: 400_000,
        initial_radius: Some(0.05),
        direct,
        light_samples: 16,
        ..Settings::default()
    };
    // The photons' estimate of the open floor itself is 1% low here (PPM's radius over the falloff, and
    // its noise): they are held to (1 - a) times their own open floor, the shadow rays to the closed form.
    let open_photons = mean(&render(&ctx, &base, settings(DirectLight::Photons), 20));
    println!("open floor, photons: {open_photons:.5}, closed form {open:.5}");
    let mut results = Vec::new();
    for (name, mesh, direct) in [
        ("quad, photons", false, DirectLight::Photons),
        ("quad, shadow rays", false, DirectLight::Sample),
        ("mesh, photons", true, DirectLight::Photons),
        ("mesh, shadow rays", true, DirectLight::Sample),
    ] {
        let got = mean(&render(&ctx, &pane(mesh), settings(direct), 20));
        let want = match direct {
            DirectLight::Sample => want,
            DirectLight::Photons => open_photons * (1.0 - alpha as f64),
        };
        println!("{name}: floor radiance {got:.5}, want {want:.5}");
        results.push((name, direct, got, want));
    }
    for (name, direct, got, want) in results {
        // Shadow rays: 20 passes of 16 samples in 64 pixels, each visible with probability 0.7 (0.65 relative
        // sd a sample): 0.4%, and 1% is 2.5 sd. Photons: ~10,000 a hit point a pass, 0.7 of them passing the
        // pane (0.5% sd from the pane alone, 1% in all): 3%, as the open floor's test. A pane the mask
        // ignored gives 0 (it is black), one always passed 1 / 0.7.
        let tol = if direct == DirectLight::Sample { 0.01 } else { 0.03 };
        assert!((got / want - 1.0).abs() < tol, "{name}: {got} vs {want}");
    }
    assert_clean(&ctx);
}

/// Mitsuba 3 on scenes/mask-pane.xml (a pane masked by a bitmap with holes over a floor, a sphere at
/// opacity 0.4, a null rectangle across the view; its reference: scenes/references/mask-pane.txt, made by
/// make_reference.py with Mitsuba's volumetric path tracer): the image's mean, and the pane's shadow
/// (the floor under it), within 1% per channel.
#[test]
fn masks_match_mitsuba() {
    let scene = mitsuba_scene("mask-pane", &[]);
    let (image, want) = against_mitsuba(&scene, "mask-pane", 12);
    // The floor under the pane: rows 55% to 80% down, columns 15% to 45% across (the pane's shadow).
    let (w, h) = (image.width, image.height);
    let shadow = |img: &RgbImage| window_mean(img, w * 15 / 100..w * 45 / 100, h * 55 / 100..h * 80 / 100);
    assert_means_within("image", image.mean(), want.mean(), 0.01);
    assert_means_within("the pane's shadow", shadow(&image), shadow(&want), 0.01);
}

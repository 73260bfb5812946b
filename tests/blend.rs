//! Mitsuba's `blendbsdf` on the GPU (shaders/materials/blend.glsl): a blend of weight 0 or 1 is its
//! component bit for bit, Mitsuba 3's weight texture read as it reads it (eval_1: the luminance), and a
//! scene of blends against Mitsuba 3's path tracer. (GPU against the CPU twin: tests/kernels.rs,
//! `..._with_blends`.)

mod common;

use common::*;
use glam::{Vec2, Vec3};
use ppm_vk_engine::scene::{Material, Surface};
use ppm_vk_engine::{RgbImage, Scene, Settings};

const RES: u32 = 24;
const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn settings() -> Settings {
    Settings {
        photons_per_pass: 4_000,
        seed: 5,
        emission_samples: 2,
        rough_samples: 2,
        light_samples: 2,
        ..Settings::default()
    }
}

/// The paper's scene with every material that does not emit replaced by a blend of weight `weight` of
/// it and a red diffuse: the original `first` where `weight` is 0, else `second`.
fn blended(plain: &Scene, weight: f32) -> Scene {
    let mut s = plain.clone();
    let red = s.materials.len() as u32;
    s.materials.push(Material {
        name: "red".into(),
        surface: Surface::Diffuse {
            albedo: Vec3::new(0.8, 0.1, 0.1),
        },
        ..plain.materials[0].clone()
    });
    let mut blend_of = Vec::new();
    for (i, m) in plain.materials.iter().enumerate() {
        if m.is_light() {
            blend_of.push(i as u32);
            continue;
        }
        let (first, second) = if weight == 0.0 {
            (i as u32, red)
        } else {
            (red, i as u32)
        };
        s.materials.push(Material {
            name: format!("blend of {}", m.name),
            surface: Surface::Blend { weight, first, second },
            texture: None,
            normal_map: None,
            emission: Vec3::ZERO,
            ..m.clone()
        });
        blend_of.push(s.materials.len() as u32 - 1);
    }
    s.quads
        .iter_mut()
        .for_each(|q| q.material = blend_of[q.material as usize]);
    s.spheres
        .iter_mut()
        .for_each(|q| q.material = blend_of[q.material as usize]);
    s.meshes
        .iter_mut()
        .for_each(|m| m.materials.iter_mut().for_each(|k| *k = blend_of[*k as usize]));
    s.validate().unwrap_or_else(|e| panic!("{e:#}"));
    s
}

fn same_pixels(a: &RgbImage, b: &RgbImage) -> bool {
    a.pixels.len() == b.pixels.len()
        && a.pixels
            .iter()
            .flatten()
            .zip(b.pixels.iter().flatten())
            .all(|(x, y)| x.to_bits() == y.to_bits())
}

/// Weight 0 is the first component and weight 1 the second, bit for bit: no random number is drawn for a
/// certain choice, so every path is the one the component alone gives (blend.glsl).
#[test]
fn a_blend_of_weight_0_or_1_is_its_component_bit_for_bit() {
    let ctx = ctx();
    let plain = cornell(RES, RES);
    let a = render(&ctx, &plain, settings(), 2);
    let mean = a.mean();
    assert!(
        mean.iter().all(|&m| m > 0.01),
        "a dark image proves nothing: mean {mean:?}"
    );
    for weight in [0.0, 1.0] {
        let b = render(&ctx, &blended(&plain, weight), settings(), 2);
        assert!(same_pixels(&a, &b), "weight {weight}: the blend changed the image");
    }
    // And the red it would otherwise pick does change it.
    let c = render(&ctx, &blended(&plain, 0.5), settings(), 2);
    assert!(!same_pixels(&a, &c), "a blend of weight 0.5 left the image as it was");
    assert_clean(&ctx);
}

/// Mitsuba 3's eval_1 of the scene's RGB weight texture (scenes/references/blend-weight.json, made by
/// blend_textures.py) is the luminance of its value, which is what ppm-vk reads; and weight 0 picks the
/// first bsdf written, as ppm-vk's `first`.
#[test]
fn the_weight_is_mitsubas_eval_1_and_the_first_bsdf_is_the_first_written() {
    use ppm_vk_materials::blend::luminance;
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(format!("{ROOT}/scenes/references/blend-weight.json")).unwrap())
            .unwrap();
    let scene = Scene::load(std::path::Path::new(&format!("{ROOT}/scenes/blend-plane.xml")))
        .unwrap_or_else(|e| panic!("{e:#}"));
    let textured = scene
        .materials
        .iter()
        .find(|m| matches!(m.surface, Surface::Blend { .. }) && m.texture.is_some());
    let t = textured.expect("a textured blend").texture.unwrap();
    let (texels, at) = ppm_vk_engine::lower::texture_texels(&scene.textures);
    let points = json["eval_1"].as_array().unwrap();
    assert!(points.len() >= 5);
    for p in points {
        let uv = Vec2::new(p["uv"][0].as_f64().unwrap() as f32, p["uv"][1].as_f64().unwrap() as f32);
        let want = p["eval_1"].as_f64().unwrap() as f32;
        let rgb = Vec3::from_array([0, 1, 2].map(|c| p["rgb"][c].as_f64().unwrap() as f32));
        // Mitsuba's eval_1 is the luminance of its eval...
        assert!(
            (luminance(rgb) - want).abs() < 1e-6,
            "{uv}: luminance {} vs eval_1 {want}",
            luminance(rgb)
        );
        // ...and ppm-vk's weight the luminance of the same texture's value.
        let got = luminance(ppm_vk_reference::texture::value(&texels, at[t as usize], uv));
        assert!((got - want).abs() < 1e-5, "{uv}: ppm-vk {got}, Mitsuba {want}");
    }
    let red = [0.8, 0.1, 0.1];
    for key in ["order_dict", "order_xml"] {
        let got: Vec<f64> = json[key]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert!(got.iter().zip(red).all(|(g, r)| (g - r).abs() < 1e-6), "{key}: {got:?}");
    }
    let s = Scene::load(write_blend_of_red_and_blue()).unwrap_or_else(|e| panic!("{e:#}"));
    let Surface::Blend { first, .. } = s.materials[s.spheres[0].material as usize].surface else {
        panic!("a blend")
    };
    assert_eq!(
        s.materials[first as usize].surface,
        Surface::Diffuse {
            albedo: Vec3::from_array(red.map(|c| c as f32))
        }
    );
}

/// A scene whose sphere is blend_textures.py's XML blend: red first, blue second.
fn write_blend_of_red_and_blue() -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("ppm-vk-blend-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("red-blue.xml");
    std::fs::write(
        &path,
        r#"<scene version="3.0.0"><sensor type="perspective"><transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform></sensor>
           <shape type="rectangle"><transform name="to_world"><translate z="-2"/></transform><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>
           <shape type="sphere"><bsdf type="blendbsdf"><float name="weight" value="0"/>
             <bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.1, 0.1"/></bsdf>
             <bsdf type="diffuse"><rgb name="reflectance" value="0.1, 0.1, 0.8"/></bsdf></bsdf></shape></scene>"#,
    )
    .unwrap();
    path
}

/// Mitsuba 3 on scenes/blend-plane.xml (a blend of a diffuse and a rough gold conductor, and a
/// textured-weight blend of two diffuse colours, on planes under an area light; its reference:
/// scenes/references/blend-plane.txt, made by make_reference.py): the image's mean and each plane's (the
/// left and right halves) within 1% per channel.
#[test]
fn blends_match_mitsuba() {
    let scene = mitsuba_scene("blend-plane", &[("res", "64")]);
    let (image, want) = against_mitsuba(&scene, "blend-plane", 12);
    let (w, h) = (image.width, image.height);
    let half = |img: &RgbImage, right: bool| window_mean(img, if right { w / 2..w } else { 0..w / 2 }, 0..h);
    let worst = [
        assert_means_within("image", image.mean(), want.mean(), 0.01),
        assert_means_within(
            "diffuse / rough gold (left)",
            half(&image, false),
            half(&want, false),
            0.01,
        ),
        assert_means_within(
            "textured-weight diffuse pair (right)",
            half(&image, true),
            half(&want, true),
            0.01,
        ),
    ]
    .into_iter()
    .fold(0f64, f64::max);
    println!("largest difference {:.2}%", 100.0 * worst);
}

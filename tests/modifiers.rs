//! Mitsuba's bsdf modifiers on the GPU: bump and normal maps (shaders/materials/normal_map.glsl). Their
//! invariances, bit for bit: a map that leaves every normal as it is renders the image of the scene
//! without it. (GPU against the CPU twin: tests/kernels.rs, `..._with_normal_maps`.)

mod common;

use common::*;
use glam::Vec3;
use ppm_vk_engine::scene::texture::{Filter, Pattern, Texture, Wrap, IDENTITY_UV};
use ppm_vk_engine::scene::NormalMap;
use ppm_vk_engine::{RgbImage, Scene, Settings};

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

/// `scene` with `texture` added and every material given `map(texture index)`.
fn mapped(scene: &Scene, texture: Texture, map: impl Fn(u32) -> NormalMap) -> Scene {
    let mut s = scene.clone();
    s.textures.push(texture);
    let t = (s.textures.len() - 1) as u32;
    for m in &mut s.materials {
        m.normal_map = Some(map(t));
    }
    s.validate().unwrap_or_else(|e| panic!("{e:#}"));
    s
}

/// The paper's scene (quads, a mirror and a glass sphere), its image hash with `map` on every material
/// against without.
fn renders_unchanged(texture: Texture, map: impl Fn(u32) -> NormalMap) {
    let ctx = ctx();
    let plain = cornell(RES, RES);
    let with = mapped(&plain, texture, map);
    assert_ne!(
        plain.content_sha256(),
        with.content_sha256(),
        "the map is part of the scene's hash"
    );
    let a = render(&ctx, &plain, settings(), 2);
    let b = render(&ctx, &with, settings(), 2);
    let mean = a.pixels.iter().flatten().map(|&v| v as f64).sum::<f64>() / (3 * a.pixels.len()) as f64;
    assert!(mean > 0.01, "a dark image proves nothing: mean {mean}");
    assert_eq!(pixels_sha256(&a), pixels_sha256(&b), "the map changed the image");
    assert_clean(&ctx);
}

/// A height field of one value everywhere (a bitmap: Mitsuba's gradient is that of its bilinear
/// interpolation, exactly 0 here) moves no normal.
#[test]
fn a_flat_height_map_changes_nothing_bit_for_bit() {
    let flat = Texture {
        name: "flat".into(),
        pattern: Pattern::Bitmap {
            width: 4,
            height: 4,
            pixels: vec![Vec3::splat(0.6); 16],
        },
        filter: Filter::Bilinear,
        wrap: Wrap::Repeat,
        to_uv: IDENTITY_UV,
    };
    renders_unchanged(flat, |texture| NormalMap::Bump { texture, scale: 3.0 });
}

/// A normal map of (0.5, 0.5, 1) everywhere is the unperturbed normal, (0, 0, 1) in the shading frame.
/// A checkerboard of that colour holds it exactly (an 8-bit image cannot: 128/255 is not 1/2).
#[test]
fn a_normal_map_of_the_unperturbed_normal_changes_nothing_bit_for_bit() {
    let up = Texture {
        name: "up".into(),
        pattern: Pattern::Checkerboard {
            color0: Vec3::new(0.5, 0.5, 1.0),
            color1: Vec3::new(0.5, 0.5, 1.0),
        },
        filter: Filter::Bilinear,
        wrap: Wrap::Repeat,
        to_uv: IDENTITY_UV,
    };
    renders_unchanged(up, |texture| NormalMap::Normal { texture });
}

/// A constant normal map tilting the normal 35 degrees on a floor mesh, against the same floor
/// smooth-shaded by vertex normals leaning the same way (the leaning floor of tests/energy.rs): the same
/// photons land at the same points, and each record on the mapped floor carries the leaning floor's flux
/// (Veach's correction about the same normal) times the shadowing term of the direction it arrived from,
/// 2 / (1 + sqrt(1 + alpha^2 tan^2)) with alpha^2 = tan^2(35 deg) / 8 (Estevez et al. 2019; Mitsuba 3's
/// normalmap_helpers.h), here in closed form. The eye's hit points see the same normals.
#[test]
fn a_tilted_normal_map_is_the_leaning_floor_times_the_shadowing_term() {
    use ppm_vk_engine::scene::Mesh;
    use ppm_vk_engine::{DirectLight, Mode, Renderer};
    let mut leaning = Scene::parse(
        r#"
[camera]
eye = [0.0, 3.0, 3.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
vfov = 50.0
resolution = [16, 16]
[materials.floor]
diffuse = [0.5, 0.5, 0.5]
[materials.light]
emission = [10.0, 10.0, 10.0]
[[quad]]
origin = [-0.5, 2.0, -0.5]
edge_u = [1.0, 0.0, 0.0]
edge_v = [0.0, 0.0, 1.0]
material = "light"
"#,
        "leaning.toml",
    )
    .unwrap_or_else(|e| panic!("{e:#}"));
    let tilt = 35f32.to_radians();
    let ns = Vec3::new(-tilt.sin(), tilt.cos(), 0.0);
    let corners = [(-2.0, -2.0), (-2.0, 2.0), (2.0, 2.0), (2.0, -2.0)];
    let floor = Mesh {
        name: "floor".into(),
        positions: corners.iter().map(|&(x, z)| Vec3::new(x, 0.0, z)).collect(),
        normals: Some(vec![ns; 4]),
        // u along x, v along z: dp/du = x, and the shading frame (s, t, n) = (x, -z, y).
        uvs: Some(corners.iter().map(|&(x, z)| glam::Vec2::new(x, z)).collect()),
        indices: vec![[0, 1, 2], [0, 2, 3]],
        materials: vec![0; 2],
    };
    leaning.meshes.push(floor);
    let mut mapped = leaning.clone();
    mapped.meshes[0].normals = None;
    // ns in the frame (x, -z, y): (-sin, 0, cos), stored as (c + 1) / 2.
    let c = (Vec3::new(-tilt.sin(), 0.0, tilt.cos()) + 1.0) / 2.0;
    mapped.textures.push(Texture {
        name: "tilt".into(),
        pattern: Pattern::Checkerboard { color0: c, color1: c },
        filter: Filter::Bilinear,
        wrap: Wrap::Repeat,
        to_uv: IDENTITY_UV,
    });
    mapped.materials[0].normal_map = Some(NormalMap::Normal { texture: 0 });
    mapped.validate().unwrap_or_else(|e| panic!("{e:#}"));

    let ctx = ctx();
    let settings = Settings {
        mode: Mode::Sppm,
        photons_per_pass: 20_000,
        // Records where the photons first land (the floor is flat: none lands on it twice).
        direct: DirectLight::Photons,
        ..settings()
    };
    let run = |scene: &Scene| {
        let mut r = Renderer::new(&ctx, scene, settings.clone()).unwrap_or_else(|e| panic!("{e:#}"));
        let hits = r.read_hit_points().unwrap();
        let mut records = r.trace_and_gather(0, 20_000).unwrap();
        records.sort_by_key(|p| p.pos.map(f32::to_bits));
        (hits, records)
    };
    let (hits_a, recs_a) = run(&leaning);
    let (hits_b, recs_b) = run(&mapped);
    assert_eq!(recs_a.len(), recs_b.len(), "the same photons land");
    assert!(recs_a.len() > 5_000, "{} records", recs_a.len());
    let alpha2 = (tilt.tan().powi(2) / 8.0).min(1.0);
    let mut worst = 0f32;
    let mut least = 1f32;
    for (a, b) in recs_a.iter().zip(&recs_b) {
        assert_eq!(a.pos, b.pos, "the same landing point");
        let d = ppm_vk_materials::math::oct_decode(b.dir);
        let cos2 = d.y * d.y;
        let g = 2.0 / (1.0 + (1.0 + alpha2 * (1.0 - cos2).max(0.0) / cos2).sqrt());
        least = least.min(g);
        for k in 0..3 {
            worst = worst.max((b.flux[k] / (a.flux[k] * g) - 1.0).abs());
        }
    }
    println!(
        "{} records; shadowing term down to {least:.4}; largest relative error {worst:.2e}",
        recs_a.len()
    );
    // Photons reach the floor up to 55 degrees from the vertical: a term down to about 0.97.
    assert!(least < 0.98, "no record arrived where the term matters ({least})");
    // The term is taken here from the record's direction as stored, 16 bits a coordinate, and the leaning
    // floor's normals are stored so too (triangle_texels): near grazing each moves a record's flux by up
    // to a few 1e-4 (measured 2.96e-4 at 35 degrees' tilt).
    assert!(
        worst < 1e-3,
        "a record is {worst:e} off the leaning floor's times the term"
    );
    let agree = hits_a.iter().zip(&hits_b).filter(|(a, b)| a.pixel == b.pixel).count();
    assert_eq!(agree, hits_a.len());
    for (a, b) in hits_a.iter().zip(&hits_b).filter(|(a, _)| !a.is_empty()) {
        let (na, nb) = (Vec3::from_array(a.normal), Vec3::from_array(b.normal));
        // The leaning floor's vertex normals are stored octahedral, 16 bits a coordinate (about 2e-5).
        assert!((na - nb).length() < 1e-4, "hit point normals {na} and {nb}");
        assert_eq!(a.weight, b.weight);
    }
    assert_clean(&ctx);
}

/// Mitsuba 3 on scenes/bump-plane.xml (a bumpmapped and a normal-mapped diffuse plane under an area
/// light; its reference: scenes/references/bump-plane.txt, made by make_reference.py): the image's mean
/// and each plane's (the left and right halves of the image) within 1% per channel.
#[test]
fn bump_and_normal_maps_match_mitsuba() {
    let scene = mitsuba_scene("bump-plane", &[]);
    let (image, want) = against_mitsuba(&scene, "bump-plane", 12);
    let (w, h) = (image.width, image.height);
    let half = |img: &RgbImage, right: bool| window_mean(img, if right { w / 2..w } else { 0..w / 2 }, 0..h);
    assert_means_within("image", image.mean(), want.mean(), 0.01);
    assert_means_within("bumpmapped plane (left)", half(&image, false), half(&want, false), 0.01);
    assert_means_within(
        "normal-mapped plane (right)",
        half(&image, true),
        half(&want, true),
        0.01,
    );
}

//! Helpers shared by the integration tests: a validated context, the clean-validation check and scene
//! loading. Each test file includes this with `mod common;`, so not every helper is used by every file.
#![allow(dead_code)]

use std::path::Path;

use ppm_vk_engine::{Context, ContextOptions, Scene};

/// A 1000 m square floor under a small square light, seen from straight above: the radiance below the
/// light has a closed form (tests/stability.rs for a diffuse floor, tests/materials.rs for a plastic one).
pub const OPEN_FLOOR: &str = r#"
# A 1000 m square floor under a small square light: the irradiance below the light has a closed form.
[camera]
eye = [0.0, 0.5, 0.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
vfov = 2.0
resolution = [8, 8]
[materials.floor]
diffuse = [0.5, 0.5, 0.5]
[materials.light]
emission = [10.0, 10.0, 10.0]
[[quad]]
origin = [-500.0, 0.0, -500.0]
edge_u = [0.0, 0.0, 1000.0]
edge_v = [1000.0, 0.0, 0.0]
material = "floor"
[[quad]]
origin = [-0.1, 1.0, -0.1]
edge_u = [0.2, 0.0, 0.0]
edge_v = [0.0, 0.0, 0.2]
material = "light"
"#;

/// The test scene of the paper.
pub const CORNELL: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cornell-spheres.toml");
/// The regions of the test scene's file, in the pixels of its 512 x 512 reference.
pub fn cornell_regions() -> Vec<ppm_vk_engine::metrics::Region> {
    load(CORNELL).regions.iter().map(|r| r.pixels(512, 512)).collect()
}

/// The white-furnace scene: a closed box of uniform albedo 0.5 and emission 1.
pub const FURNACE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/furnace.toml");
/// The Mitsuba 3 scene the reference was rendered from: cornell-spheres as Mitsuba XML.
pub const CORNELL_XML: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/reference/cornell-spheres.xml");
/// The Mitsuba reference of cornell-spheres (512 x 512), in the repository root's sibling `shared/`.
pub const CORNELL_REFERENCE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/reference/cornell-spheres.exr");

/// A context with the Khronos validation layer on: every test ends with [`assert_clean`].
pub fn ctx() -> Context {
    Context::new(&ContextOptions {
        validation: true,
        ..ContextOptions::default()
    })
    .expect("opening a Vulkan device with VK_LAYER_KHRONOS_validation (is vulkan-validationlayers installed?)")
}

/// Panics listing every warning and error the validation layer reported on `ctx` so far.
pub fn assert_clean(ctx: &Context) {
    let msgs = ctx.validation_messages();
    assert!(
        msgs.is_empty(),
        "the validation layer reported {} message(s):\n{}",
        msgs.len(),
        msgs.join("\n")
    );
}

/// The `ppm-vk` binary, with its runtime files and pipeline cache in a directory of this test process, so
/// tests neither read nor leave state in the user's cache.
pub fn bin() -> std::process::Command {
    let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_ppm-vk"));
    c.env("XDG_RUNTIME_DIR", std::env::temp_dir());
    c.env("PPM_VK_CACHE_DIR", pipeline_cache_dir());
    c
}

/// Where [`bin`]'s runs keep their pipeline cache.
pub fn pipeline_cache_dir() -> std::path::PathBuf {
    std::env::temp_dir()
        .join(format!("ppm-vk-tests-{}", std::process::id()))
        .join("pipeline-cache")
}

pub fn load(path: &str) -> Scene {
    Scene::load(Path::new(path)).unwrap_or_else(|e| panic!("loading {path}: {e:#}"))
}

/// cornell-spheres at `w` x `h`.
pub fn cornell(w: u32, h: u32) -> Scene {
    load(CORNELL).with_resolution(w, h)
}

/// The furnace at `w` x `h`.
pub fn furnace(w: u32, h: u32) -> Scene {
    load(FURNACE).with_resolution(w, h)
}

/// |a - b| <= rel * max(|a|, |b|) + abs.
/// The image of `scene` after `passes` passes with `settings` (the renderer dropped before it returns).
pub fn render(ctx: &Context, scene: &Scene, settings: ppm_vk_engine::Settings, passes: u32) -> ppm_vk_engine::RgbImage {
    let mut r = ppm_vk_engine::Renderer::new(ctx, scene, settings).unwrap_or_else(|e| panic!("{e:#}"));
    for _ in 0..passes {
        r.pass().unwrap_or_else(|e| panic!("{e:#}"));
    }
    r.image().unwrap_or_else(|e| panic!("{e:#}"))
}

/// [`render`] on a context of its own, which must end with no validation message, and an image without
/// a non-finite pixel.
pub fn render_clean(scene: &Scene, settings: ppm_vk_engine::Settings, passes: u32) -> ppm_vk_engine::RgbImage {
    let ctx = ctx();
    let image = render(&ctx, scene, settings, passes);
    assert_clean(&ctx);
    assert_eq!(image.count_non_finite(), 0);
    image
}

pub fn close(a: f64, b: f64, rel: f64, abs: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) + abs
}

/// How many of `cpu`'s records have a distinct twin in `gpu`: position within `pos_tol`, flux within
/// 1e-5 relative, direction code within 4 units per 16-bit half.
pub fn match_records(
    gpu: &[ppm_vk_engine::layout::Photon],
    cpu: &[ppm_vk_engine::layout::Photon],
    pos_tol: f32,
) -> usize {
    match_records_within(gpu, cpu, pos_tol, 1e-5)
}

/// [`match_records`] with flux within `flux_rel` relative.
pub fn match_records_within(
    gpu: &[ppm_vk_engine::layout::Photon],
    cpu: &[ppm_vk_engine::layout::Photon],
    pos_tol: f32,
    flux_rel: f64,
) -> usize {
    let q = |x: f32| (x / (4.0 * pos_tol)).floor() as i64;
    let mut index: std::collections::HashMap<[i64; 3], Vec<usize>> = std::collections::HashMap::new();
    for (i, p) in gpu.iter().enumerate() {
        index.entry(p.pos.map(q)).or_default().push(i);
    }
    let mut used = vec![false; gpu.len()];
    let twins = |a: &ppm_vk_engine::layout::Photon, b: &ppm_vk_engine::layout::Photon| {
        let dir_close = |x: u32, y: u32| {
            ((x & 0xffff) as i16 as i32 - (y & 0xffff) as i16 as i32).abs() <= 4
                && ((x >> 16) as i16 as i32 - (y >> 16) as i16 as i32).abs() <= 4
        };
        (glam::Vec3::from_array(a.pos) - glam::Vec3::from_array(b.pos))
            .abs()
            .max_element()
            <= pos_tol
            && (0..3).all(|c| close(a.flux[c] as f64, b.flux[c] as f64, flux_rel, 0.0))
            && dir_close(a.dir, b.dir)
    };
    let mut matched = 0;
    'records: for c in cpu {
        let k = c.pos.map(q);
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    if let Some(list) = index.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) {
                        for &i in list {
                            if !used[i] && twins(&gpu[i], c) {
                                used[i] = true;
                                matched += 1;
                                continue 'records;
                            }
                        }
                    }
                }
            }
        }
    }
    matched
}

/// A batch's records in a fixed order (by their bits), to compare two runs that trace the same photons in
/// a different order.
pub fn sorted_records(mut records: Vec<ppm_vk_engine::layout::Photon>) -> Vec<[u32; 8]> {
    let mut keys: Vec<[u32; 8]> = records
        .drain(..)
        .map(|p| {
            [
                p.pos[0].to_bits(),
                p.pos[1].to_bits(),
                p.pos[2].to_bits(),
                p.cell,
                p.flux[0].to_bits(),
                p.flux[1].to_bits(),
                p.flux[2].to_bits(),
                p.dir,
            ]
        })
        .collect();
    keys.sort_unstable();
    keys
}

/// scenes/NAME.xml, with `-D` parameters `defines`: a scene written to be rendered by Mitsuba 3 too, which
/// must load with no warning but Mitsuba's one-sided bsdfs'.
pub fn mitsuba_scene(name: &str, defines: &[(&str, &str)]) -> Scene {
    let defines: Vec<(String, String)> = defines.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
    let path = format!("{}/scenes/{name}.xml", env!("CARGO_MANIFEST_DIR"));
    let scene = Scene::load_with(path, &defines).unwrap_or_else(|e| panic!("{e:#}"));
    assert!(
        scene.warnings.iter().all(|w| w.contains("one-sided")),
        "{:?}",
        scene.warnings
    );
    scene
}

/// `scene` rendered by SPPM (`passes` of 200k photons) and its Mitsuba reference
/// scenes/references/REFERENCE.exr: (ours, Mitsuba's), the same size, validation clean.
pub fn against_mitsuba(
    scene: &Scene,
    reference: &str,
    passes: u32,
) -> (ppm_vk_engine::RgbImage, ppm_vk_engine::RgbImage) {
    let path = format!("{}/scenes/references/{reference}.exr", env!("CARGO_MANIFEST_DIR"));
    let want = ppm_vk_engine::metrics::Reference::load(Path::new(&path))
        .unwrap_or_else(|e| panic!("{e:#}"))
        .image;
    let settings = ppm_vk_engine::Settings {
        mode: ppm_vk_engine::Mode::Sppm,
        photons_per_pass: 200_000,
        ..ppm_vk_engine::Settings::default()
    };
    let ctx = ctx();
    let image = render(&ctx, scene, settings, passes);
    assert_clean(&ctx);
    assert_eq!((image.width, image.height), (want.width, want.height));
    (image, want)
}

/// Each channel's mean over the pixels in columns `cols` and rows `rows` of `image`.
pub fn window_mean(
    image: &ppm_vk_engine::RgbImage,
    cols: std::ops::Range<u32>,
    rows: std::ops::Range<u32>,
) -> [f64; 3] {
    let mut sum = [0f64; 3];
    let mut n = 0;
    for y in rows {
        for x in cols.clone() {
            n += 1;
            let p = image.pixels[(y * image.width + x) as usize];
            for (s, v) in sum.iter_mut().zip(p) {
                *s += v as f64;
            }
        }
    }
    sum.map(|s| s / n as f64)
}

/// Asserts each channel of `got` within `rel` of `want`'s (printing both and their ratio); returns the
/// largest |ratio - 1|.
pub fn assert_means_within(what: &str, got: [f64; 3], want: [f64; 3], rel: f64) -> f64 {
    let ratio = [0, 1, 2].map(|c| got[c] / want[c]);
    println!("{what}: mean {got:.5?}, Mitsuba {want:.5?}, ratio {ratio:.5?}");
    for (c, r) in ratio.iter().enumerate() {
        assert!(
            (r - 1.0).abs() < rel,
            "{what}, channel {c}: {:+.2}% off Mitsuba's",
            100.0 * (r - 1.0)
        );
    }
    ratio.iter().fold(0f64, |w, r| w.max((r - 1.0).abs()))
}

/// SHA-256 (hex) of an image's pixel values (bit for bit comparisons of two renders).
pub fn pixels_sha256(image: &ppm_vk_engine::RgbImage) -> String {
    use sha2::Digest;
    let mut h = sha2::Sha256::new();
    for v in image.pixels.iter().flatten() {
        h.update(v.to_bits().to_le_bytes());
    }
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

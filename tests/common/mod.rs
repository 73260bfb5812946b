//! Helpers shared by the integration tests: a validated context, the clean-validation check and scene
//! loading. Each test file includes this with `mod common;`, so not every helper is used by every file.
#![allow(dead_code)]

use std::path::Path;

use ppm_vk_engine::{Context, ContextOptions, Scene};

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
pub fn close(a: f64, b: f64, rel: f64, abs: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) + abs
}

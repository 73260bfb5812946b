//! Every scene in `scenes/` (the TOML scenes and the Mitsuba references' XML) loads to the same scene and
//! renders the same image, bit for bit, as when `tests/bit-identical.json` was recorded: a fixed seed, a
//! small image and a few passes, through every stage (the ray pass, photons, the grid, the gather, the
//! update, the resolve). It guards moves of code that must not change what the program does (issue 34's
//! split into crates); a change that is meant to change images records the hashes again with
//! `PPM_VK_RECORD_HASHES=1 cargo test --release --test bit_identical` and says why in its commit.

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use common::*;
use ppm_vk_engine::{DirectLight, Mode, ProbeMode, Scene, Settings};
use sha2::Digest;

const RECORD: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/bit-identical.json");
const RES: u32 = 24;

fn settings() -> Settings {
    Settings {
        photons_per_pass: 4_000,
        seed: 11,
        emission_samples: 2,
        // As many where a rough lobe is seen: the hashes were recorded with one count for every marked pixel.
        rough_samples: 2,
        light_samples: 2,
        ..Settings::default()
    }
}

/// Mitsuba files that name meshes only their reference script writes (make_reference.py splits
/// glass-on-table's demo mesh in two); scenes/glass-on-table.toml is the same scene.
const NEEDS_REFERENCE_SCRIPT: &[&str] = &["references/glass-on-table.xml"];

/// The scenes: every TOML file in scenes/ and every XML file in scenes/references/, by name.
fn scenes() -> Vec<(String, PathBuf)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut out = Vec::new();
    for (dir, ext) in [(root.clone(), "toml"), (root.join("references"), "xml")] {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == ext) {
                let name = path.strip_prefix(&root).unwrap().to_string_lossy().replace('\\', "/");
                if !NEEDS_REFERENCE_SCRIPT.contains(&name.as_str()) {
                    out.push((name, path));
                }
            }
        }
    }
    out.sort();
    out
}

fn image_sha256(image: &ppm_vk_engine::RgbImage) -> String {
    let mut h = sha2::Sha256::new();
    h.update(image.width.to_le_bytes());
    h.update(image.height.to_le_bytes());
    for p in &image.pixels {
        for v in p {
            h.update(v.to_bits().to_le_bytes());
        }
    }
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

#[test]
fn every_scene_renders_as_recorded() {
    let ctx = ctx();
    let mut now: BTreeMap<String, String> = BTreeMap::new();
    let render_one = |key: &str, scene: &Scene, s: Settings, passes: u32| {
        let image = render(&ctx, scene, s, passes);
        assert!(
            image.pixels.iter().flatten().all(|v| v.is_finite()),
            "{key}: a pixel is not finite"
        );
        image_sha256(&image)
    };
    for (name, path) in scenes() {
        let scene = Scene::load(&path).unwrap_or_else(|e| panic!("loading {name}: {e:#}"));
        now.insert(format!("{name} scene"), scene.content_sha256());
        let small = scene.with_resolution(RES, RES);
        let key = format!("{name} sppm");
        now.insert(key.clone(), render_one(&key, &small, settings(), 2));
    }
    // The other estimators on the paper's scene: PPM with the probe and the cone filter, and direct light
    // by photons.
    let cornell = cornell(RES, RES);
    let ppm = Settings {
        mode: Mode::Ppm,
        probe: ProbeMode::ScaleFree,
        cone_k: Some(1.1),
        ..settings()
    };
    let key = "cornell-spheres.toml ppm probe cone";
    now.insert(key.into(), render_one(key, &cornell, ppm, 2));
    let photons = Settings {
        direct: DirectLight::Photons,
        probe: ProbeMode::Paper,
        ..settings()
    };
    let key = "cornell-spheres.toml sppm photons paper-probe";
    now.insert(key.into(), render_one(key, &cornell, photons, 2));
    assert_clean(&ctx);

    if std::env::var_os("PPM_VK_RECORD_HASHES").is_some() {
        let text = serde_json::to_string_pretty(&now).unwrap() + "\n";
        std::fs::write(RECORD, text).unwrap();
        eprintln!("recorded {} hashes in {RECORD}", now.len());
        return;
    }
    let text = std::fs::read_to_string(RECORD)
        .unwrap_or_else(|e| panic!("{RECORD}: {e} (record it with PPM_VK_RECORD_HASHES=1)"));
    let recorded: BTreeMap<String, String> = serde_json::from_str(&text).unwrap();
    let differ: Vec<&String> = now.keys().filter(|k| recorded.get(*k) != now.get(*k)).collect();
    let gone: Vec<&String> = recorded.keys().filter(|k| !now.contains_key(*k)).collect();
    assert!(
        differ.is_empty() && gone.is_empty(),
        "not as recorded in tests/bit-identical.json: {differ:?} differ, {gone:?} no longer rendered"
    );
}

//! Checkpoints: a render stopped after 3 passes and resumed from its checkpoint file for 3 more gives the
//! image of 6 uninterrupted passes, bit for bit, in both modes with the probe on; a checkpoint of another
//! scene, setting or build is refused with a message saying which.

mod common;

use std::path::PathBuf;

use common::*;
use ppm_vk_engine::{Checkpoint, Mode, ProbeMode, Renderer, RgbImage, Scene, Settings};

const RES: u32 = 32;
const BUILD: &str = "test-build";

fn settings(mode: Mode) -> Settings {
    Settings {
        mode,
        photons_per_pass: 10_000,
        probe: ProbeMode::ScaleFree,
        emission_samples: 2,
        rough_samples: 2,
        ..Settings::default()
    }
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ppm-vk-resume-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn bits(image: &RgbImage) -> Vec<u32> {
    image.pixels.iter().flatten().map(|v| v.to_bits()).collect()
}

fn render(r: &mut Renderer, passes: u32) -> RgbImage {
    for _ in 0..passes {
        r.pass().unwrap();
    }
    r.image().unwrap()
}

fn resume_is_bit_exact(mode: Mode) {
    let ctx = ctx();
    let scene = cornell(RES, RES);
    let whole = render(&mut Renderer::new(&ctx, &scene, settings(mode)).unwrap(), 6);

    let path = scratch(&format!("{mode:?}.ckpt"));
    let mut first = Renderer::new(&ctx, &scene, settings(mode)).unwrap();
    let half = render(&mut first, 3);
    first.checkpoint(BUILD).unwrap().save(&path).unwrap();
    drop(first);
    let checkpoint = Checkpoint::load(&path).unwrap();
    assert_eq!((checkpoint.header.passes, checkpoint.header.emitted), (3, 30_000));
    let mut resumed = Renderer::resume(&ctx, &scene, settings(mode), &checkpoint, BUILD).unwrap();
    assert_eq!(resumed.probe_report(), checkpoint.header.probe.as_ref());
    assert!(
        resumed.probe_report().is_some_and(|p| p.enlarged > 0),
        "the probe must have changed radii to be tested"
    );
    let continued = render(&mut resumed, 3);
    assert_eq!((resumed.passes(), resumed.emitted()), (6, 60_000));
    // The passes after the checkpoint changed the image: the equality below is not of an idle state.
    assert_ne!(bits(&half), bits(&whole), "{mode:?}: 3 passes gave the image of 6");
    let differ = bits(&continued)
        .iter()
        .zip(bits(&whole))
        .filter(|(a, b)| *a != b)
        .count();
    assert_eq!(
        differ,
        0,
        "{mode:?}: {differ} of {} channels differ after resuming",
        RES * RES * 3
    );
    assert_clean(&ctx);
}

#[test]
fn sppm_resumes_bit_exact() {
    resume_is_bit_exact(Mode::Sppm);
}

#[test]
fn ppm_resumes_bit_exact() {
    resume_is_bit_exact(Mode::Ppm);
}

#[test]
fn foreign_checkpoints_are_refused_saying_which() {
    let ctx = ctx();
    let scene = cornell(RES, RES);
    let mut r = Renderer::new(&ctx, &scene, settings(Mode::Sppm)).unwrap();
    r.pass().unwrap();
    let checkpoint = r.checkpoint(BUILD).unwrap();
    let refusal = |scene: &Scene, settings: Settings, build: &str| match Renderer::resume(
        &ctx,
        scene,
        settings,
        &checkpoint,
        build,
    ) {
        Ok(_) => panic!("resumed a checkpoint that does not match"),
        Err(e) => format!("{e:#}"),
    };
    let e = refusal(&scene, settings(Mode::Sppm), "another-build");
    assert!(e.contains("build test-build") && e.contains("another-build"), "{e}");
    let e = refusal(&furnace(RES, RES), settings(Mode::Sppm), BUILD);
    assert!(
        e.contains("another scene") && e.contains("cornell-spheres") && e.contains("furnace"),
        "{e}"
    );
    let e = refusal(&cornell(RES, 2 * RES), settings(Mode::Sppm), BUILD);
    assert!(e.contains("another scene") && e.contains("32x64"), "{e}");
    let e = refusal(
        &scene,
        Settings {
            alpha: 0.6,
            ..settings(Mode::Sppm)
        },
        BUILD,
    );
    assert!(
        e.contains("other settings") && e.contains("alpha: 0.7 in the checkpoint, 0.6 now"),
        "{e}"
    );
    assert!(!e.contains("seed"), "only what differs is named: {e}");
    assert_clean(&ctx);
}

/// The scene hash covers mesh content, not only the scene file: moving one vertex of an OBJ changes it,
/// moving the scene's directory (mesh and material names) does not.
#[test]
fn scene_hash_covers_mesh_content() {
    let scene = load(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cornell-mesh.toml"));
    assert!(!scene.meshes.is_empty());
    let mut moved = scene.clone();
    moved.meshes[0].positions[0].x += 1e-3;
    assert_ne!(scene.content_sha256(), moved.content_sha256());
    let mut renamed = scene.clone();
    renamed.meshes[0].name = "elsewhere/mesh.obj".into();
    renamed
        .materials
        .iter_mut()
        .for_each(|m| m.name = format!("elsewhere:{}", m.name));
    assert_eq!(scene.content_sha256(), renamed.content_sha256());
}

/// ... and textures and texture coordinates: one pixel of an image, or one vertex's texture coordinate.
#[test]
fn scene_hash_covers_textures() {
    use ppm_vk_engine::scene::texture::Pattern;
    let xml = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/references/cornell-textured.xml");
    let scene = ppm_vk_engine::Scene::load_with(xml, &[("res".to_string(), "32".to_string())]).unwrap();
    let mut repainted = scene.clone();
    let bitmap = repainted.textures.iter_mut().find_map(|t| match &mut t.pattern {
        Pattern::Bitmap { pixels, .. } => Some(pixels),
        _ => None,
    });
    bitmap.expect("a bitmap texture")[0].x += 1e-3;
    assert_ne!(scene.content_sha256(), repainted.content_sha256());
    let mut shifted = scene.clone();
    let uvs = shifted
        .meshes
        .iter_mut()
        .find_map(|m| m.uvs.as_mut())
        .expect("texture coordinates");
    uvs[0].x += 1e-3;
    assert_ne!(scene.content_sha256(), shifted.content_sha256());
}

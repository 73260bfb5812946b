//! `Renderer::set_camera`: moving the view restarts the render, and the restarted render is the one a new
//! renderer of the moved view gives (the same image bit for bit after the same passes, and a checkpoint
//! of that view), without building anything again. What a viewer and an embedder rely on.

mod common;

use common::*;
use glam::Vec3;
use ppm_vk_engine::{Error, Mode, ProbeMode, Renderer, Scene, Settings};

/// cornell-spheres seen from the left and lower, looking at the glass sphere.
fn moved(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    s.camera.eye = Vec3::new(-0.6, 0.7, 2.5);
    s.camera.look_at = Vec3::new(0.1, 0.35, 0.5);
    s.camera.vfov_deg = 45.0;
    s
}

#[test]
fn a_moved_camera_renders_what_a_new_renderer_of_that_view_renders() {
    let ctx = ctx();
    let scene = cornell(32, 32);
    let other = moved(&scene);
    let sppm = Settings {
        photons_per_pass: 20_000,
        probe: ProbeMode::ScaleFree,
        ..Settings::default()
    };
    let ppm = Settings {
        mode: Mode::Ppm,
        ..sppm.clone()
    };
    for settings in [sppm, ppm] {
        let mut moving = Renderer::new(&ctx, &scene, settings.clone()).unwrap();
        let before = moving.image().unwrap();
        for _ in 0..2 {
            moving.pass().unwrap();
        }
        moving.set_camera(&other.camera).unwrap();
        assert_eq!((moving.passes(), moving.emitted()), (0, 0), "the render restarts");
        assert_eq!(moving.camera(), &other.camera);
        let mut fresh = Renderer::new(&ctx, &other, settings.clone()).unwrap();
        for _ in 0..3 {
            moving.pass().unwrap();
            fresh.pass().unwrap();
        }
        let (a, b) = (moving.image().unwrap(), fresh.image().unwrap());
        assert!(a.mean()[0] > 0.0, "{:?}: a black image", settings.mode);
        let same = a
            .pixels
            .iter()
            .zip(&b.pixels)
            .all(|(x, y)| x.map(f32::to_bits) == y.map(f32::to_bits));
        assert!(
            same,
            "{:?}: the moved renderer's image differs from a new renderer's",
            settings.mode
        );
        // Another view, not the first one's image (nothing of it stays).
        assert_ne!(a.pixels, before.pixels);
        // Its checkpoint is of the moved view: it resumes with the moved scene, not with the first.
        let checkpoint = moving.checkpoint("test").unwrap();
        checkpoint.check(&other, &settings, "test").unwrap();
        let refused = checkpoint.check(&scene, &settings, "test").unwrap_err();
        println!(
            "{:?}: bit for bit after 3 passes; a checkpoint of the first view: {refused:#}",
            settings.mode
        );
    }
    assert_clean(&ctx);
}

#[test]
fn a_camera_the_renderer_cannot_take_is_refused_and_the_render_goes_on() {
    let ctx = ctx();
    let scene = cornell(16, 16);
    let settings = Settings {
        photons_per_pass: 10_000,
        ..Settings::default()
    };
    let mut r = Renderer::new(&ctx, &scene, settings).unwrap();
    r.pass().unwrap();
    let mut bigger = scene.camera;
    bigger.width = 32;
    let mut parallel = scene.camera;
    parallel.up = parallel.look_at - parallel.eye;
    let mut nan = scene.camera;
    nan.eye.x = f32::NAN;
    let mut wide = scene.camera;
    wide.vfov_deg = 180.0;
    for (camera, field) in [
        (bigger, "camera.resolution"),
        (parallel, "camera.up"),
        (nan, "camera.eye"),
        (wide, "camera.vfov"),
    ] {
        match r.set_camera(&camera) {
            Err(Error::Scene { field: f, message, .. }) => {
                assert_eq!(f, field, "{message}");
                println!("{field}: {message}");
            }
            other => panic!("{field}: expected a scene error, got {other:?}"),
        }
    }
    // Nothing was restarted: the render continues where it was.
    assert_eq!(r.passes(), 1);
    r.pass().unwrap();
    assert_eq!(r.passes(), 2);
    assert_clean(&ctx);
}

/// `Settings::split_submissions` (the viewer's: a batch's trace, lookup and gather each submitted on their
/// own) renders the same image bit for bit, on an analytic scene and a BVH mesh scene, and a cancel between
/// those submissions leaves the estimate as the passes before it left it.
#[test]
fn split_submissions_render_the_same_bits_and_cancel_between_stages() {
    let ctx = ctx();
    for scene in [
        cornell(32, 32),
        load("scenes/glass-on-table.toml").with_resolution(32, 32),
    ] {
        let settings = Settings {
            photons_per_pass: 20_000,
            ..Settings::default()
        };
        let split = Settings {
            split_submissions: true,
            ..settings.clone()
        };
        let mut whole = Renderer::new(&ctx, &scene, settings).unwrap();
        let mut parts = Renderer::new(&ctx, &scene, split).unwrap();
        for _ in 0..2 {
            whole.pass().unwrap();
            parts.pass().unwrap();
        }
        let bits = |r: &mut Renderer| -> Vec<[u32; 3]> {
            r.image().unwrap().pixels.iter().map(|p| p.map(f32::to_bits)).collect()
        };
        assert!(
            bits(&mut whole) == bits(&mut parts),
            "{}: split submissions changed the image",
            scene.name
        );
        // Cancelled from another thread, wherever in a pass that lands (before it, or between its stages):
        // nothing of the cancelled pass stays, and the passes go on as a render without the cancel does.
        for delay_ms in [3, 11, 29] {
            let token = parts.cancel_token();
            let canceller = std::thread::spawn(move || {
                std::thread::sleep(std::time::Duration::from_millis(delay_ms));
                token.cancel();
            });
            loop {
                match parts.pass() {
                    Ok(_) => whole.pass().map(drop).unwrap(),
                    Err(Error::Cancelled) => break,
                    Err(e) => panic!("{e}"),
                }
            }
            canceller.join().unwrap();
            parts.cancel_token().reset();
            let same = bits(&mut whole) == bits(&mut parts);
            assert!(same, "{}: cancelled after {delay_ms} ms, the image differs", scene.name);
        }
        parts.pass().unwrap();
        whole.pass().unwrap();
        assert!(
            bits(&mut whole) == bits(&mut parts),
            "{}: a pass after the cancels",
            scene.name
        );
    }
    assert_clean(&ctx);
}

//! An embedding program can tell the engine's errors apart and act on their fields: a scene error's
//! line and field, a device limit, a missing file's path, a cancelled pass.

mod common;

use std::thread;
use std::time::Duration;

use common::{assert_clean, cornell, ctx, CORNELL};
use ppm_vk_engine::{CancelToken, Error, Renderer, Scene, Settings};

#[test]
fn a_bad_scene_is_a_scene_error_with_its_line_and_field() {
    let text = std::fs::read_to_string(CORNELL).unwrap();
    // The first sphere's radius, made negative where the file writes it.
    let (line, at) = text
        .lines()
        .enumerate()
        .find(|(_, l)| l.trim_start().starts_with("radius"))
        .unwrap();
    let bad = text.replacen(at, "radius = -1.0", 1);
    match Scene::parse(&bad, "cornell.toml") {
        Err(Error::Scene {
            file,
            line: l,
            column,
            field,
            message,
        }) => {
            assert_eq!(
                (file.as_str(), l, field.as_str()),
                ("cornell.toml", line + 1, "sphere[0].radius")
            );
            assert_eq!(column, "radius = ".len() + 1, "the column of the value");
            assert!(message.contains("positive"), "{message}");
        }
        other => panic!("expected Error::Scene, got {other:?}"),
    }
    // The same check on a scene built in code: no line, the scene's name for a file.
    let mut scene = cornell(8, 8);
    scene.spheres[1].radius = f32::NAN;
    match scene.validate() {
        Err(Error::Scene {
            file, line: 0, field, ..
        }) => {
            assert_eq!((file.as_str(), field.as_str()), ("cornell-spheres", "sphere[1].radius"));
        }
        other => panic!("expected Error::Scene, got {other:?}"),
    }
}

#[test]
fn a_missing_file_is_an_io_error_with_its_path() {
    let path = std::env::temp_dir().join("ppm-vk-no-such-scene.toml");
    match Scene::load(&path) {
        Err(Error::Io { path: p, error }) => {
            assert_eq!(p, path);
            assert_eq!(error.kind(), std::io::ErrorKind::NotFound);
        }
        other => panic!("expected Error::Io, got {other:?}"),
    }
}

#[test]
fn settings_out_of_range_and_device_limits_are_told_apart() {
    let ctx = ctx();
    // Each setting out of its range is refused before any work, the error naming its field.
    let refused = |field: &str, value: String, settings: Settings| match Renderer::new(&ctx, &cornell(8, 8), settings) {
        Err(Error::Settings { field: f, .. }) if f == field => {}
        other => panic!("expected Error::Settings for {field} {value}, got {:?}", other.err()),
    };
    let s = Settings::default;
    refused("alpha", "1.5".into(), Settings { alpha: 1.5, ..s() });
    for grow in [0.5, 2.5, f32::NAN] {
        refused(
            "probe_grow",
            grow.to_string(),
            Settings {
                probe_grow: grow,
                ..s()
            },
        );
    }
    for z in [-1.0, f32::NAN, f32::INFINITY] {
        refused("shrink_z", z.to_string(), Settings { shrink_z: z, ..s() });
    }
    for share in [-0.1, 0.96, 1.0, f32::NAN] {
        refused(
            "caustic_photons",
            share.to_string(),
            Settings {
                caustic_photons: share,
                ..s()
            },
        );
    }
    for n in [0, ppm_vk_engine::settings::MAX_EMISSION_SAMPLES + 1] {
        refused(
            "pilot_samples",
            n.to_string(),
            Settings {
                pilot_samples: n,
                ..s()
            },
        );
    }
    let n = ppm_vk_engine::settings::MAX_EMISSION_SAMPLES + 1;
    refused(
        "rough_samples",
        n.to_string(),
        Settings {
            rough_samples: n,
            ..s()
        },
    );
    // 4096 x 4096 pixels with 8 hit points each: 2^27 hit points, 6 GiB of hit points alone, past the
    // device's memory (lavapipe: 2048 MiB). Per-pixel buffers are bound in tiles, so no one binding's
    // range limits them: the memory does.
    let settings = Settings {
        hit_slots: 8,
        ..Settings::default()
    };
    let limit = ctx.info().memory_bytes;
    let hit_points = 4096u64 * 4096 * 8 * std::mem::size_of::<ppm_vk_engine::layout::HitPoint>() as u64;
    if limit == 0 || limit > hit_points {
        println!(
            "the device's {} MiB would hold the hit points: the memory limit is not reached",
            limit >> 20
        );
        assert_clean(&ctx);
        return;
    }
    match Renderer::new(&ctx, &cornell(4096, 4096), settings) {
        Err(Error::Limit {
            what,
            value: Some(v),
            limit: l,
            lower,
        }) => {
            assert_eq!(l, limit);
            assert!(v > l, "{what}: {v} should exceed {l}");
            assert!(lower.contains("resolution"), "{lower}");
        }
        other => panic!("expected Error::Limit, got {:?}", other.err()),
    }
    assert_clean(&ctx);
}

#[test]
fn a_pass_can_be_cancelled_from_another_thread() {
    let ctx = ctx();
    let settings = Settings {
        photons_per_pass: 20_000,
        ..Settings::default()
    };
    let mut renderer = Renderer::new(&ctx, &cornell(32, 32), settings).unwrap();
    renderer.pass().unwrap();
    let token = CancelToken::new();
    renderer.set_cancel(token.clone());
    let canceller = thread::spawn(move || {
        thread::sleep(Duration::from_millis(50));
        token.cancel();
    });
    // Passes until the other thread's cancel lands: it must end the loop with Error::Cancelled.
    let mut done = 0;
    let outcome = loop {
        match renderer.pass() {
            Ok(_) => done += 1,
            Err(e) => break e,
        }
        assert!(done < 100_000, "the cancel never arrived");
    };
    canceller.join().unwrap();
    assert!(matches!(outcome, Error::Cancelled), "{outcome:?}");
    // The passes before the cancel stay: the count and the image are theirs.
    assert_eq!(renderer.passes(), 1 + done);
    assert!(
        matches!(renderer.pass(), Err(Error::Cancelled)),
        "stays cancelled until reset"
    );
    renderer.cancel_token().reset();
    renderer.pass().unwrap();
    assert_eq!(renderer.passes(), 2 + done);
    let image = renderer.image().unwrap();
    assert!(image.mean()[0] > 0.0);
    assert_clean(&ctx);
}

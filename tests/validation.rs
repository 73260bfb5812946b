//! The Vulkan validation layer stays silent through a whole render, the layer is really listening, and bad
//! input comes back as errors (never panics) that say what is wrong and where.

mod common;

use common::*;
use ppm_vk_device::vk;
use ppm_vk_engine::{Renderer, Scene, Settings};

#[test]
fn context_with_validation_opens() {
    let ctx = ctx();
    let info = ctx.info();
    println!(
        "device [{}] {} ({}), Vulkan {}, driver {}",
        info.index, info.name, info.kind, info.api_version, info.driver
    );
    assert!(info.missing.is_empty(), "the chosen device lacks {:?}", info.missing);
    assert!(ctx.limits().max_storage_buffer_range > 0);
    assert_clean(&ctx);
}

/// The layer must be live, or every `assert_clean` in this suite would prove nothing: a buffer of size
/// zero breaks VUID-VkBufferCreateInfo-size-00912, which the layer reports from vkCreateBuffer itself.
#[test]
fn validation_layer_reports_misuse() {
    let ctx = ctx();
    assert_clean(&ctx);
    let info = vk::BufferCreateInfo::default()
        .size(0)
        .usage(vk::BufferUsageFlags::STORAGE_BUFFER)
        .sharing_mode(vk::SharingMode::EXCLUSIVE);
    let device = ctx.device();
    // SAFETY: deliberately invalid (size 0) for the layer to catch; whatever the driver returns is
    // destroyed right away and nothing uses it.
    if let Ok(buffer) = unsafe { device.create_buffer(&info, None) } {
        unsafe { device.destroy_buffer(buffer, None) };
    }
    let msgs = ctx.validation_messages();
    println!("the layer said: {msgs:#?}");
    assert!(
        !msgs.is_empty(),
        "a zero-sized buffer passed the validation layer unreported: is the layer loaded?"
    );
    assert!(
        msgs.iter().any(|m| m.contains("00912") || m.contains("size")),
        "unexpected messages: {msgs:?}"
    );
}

#[test]
fn small_render_is_validation_clean() {
    let ctx = ctx();
    let mut r = Renderer::new(
        &ctx,
        &cornell(16, 16),
        Settings {
            photons_per_pass: 10_000,
            ..Settings::default()
        },
    )
    .unwrap();
    for i in 1..=2 {
        let stats = r.pass().unwrap();
        assert_eq!(stats.index, i);
        assert_eq!(stats.emitted_total, 10_000 * i);
        assert!(stats.records > 0, "pass {i} left no records");
        for stage in ["photon", "lookup", "gather", "update"] {
            // A stage may be timed as a whole or in steps (`lookup/count`, ...): stage_ms sums both.
            assert!(
                stats.stage_ms(stage) > 0.0,
                "pass {i}: no {stage} timing in {:?}",
                stats.stages
            );
        }
    }
    let image = r.image().unwrap();
    assert_eq!((image.width, image.height), (16, 16));
    assert_eq!(image.count_non_finite(), 0);
    assert!(image.mean().iter().all(|&m| m > 0.0), "black image {:?}", image.mean());
    // The furnace too (six lights, no spheres), with the cone filter on.
    let mut r = Renderer::new(
        &ctx,
        &furnace(16, 16),
        Settings {
            photons_per_pass: 10_000,
            cone_k: Some(1.1),
            ..Settings::default()
        },
    )
    .unwrap();
    r.pass().unwrap();
    r.pass().unwrap();
    assert_eq!(r.image().unwrap().count_non_finite(), 0);
    drop(r);
    assert_clean(&ctx);
}

#[test]
fn bad_settings_are_errors() {
    let ctx = ctx();
    let scene = cornell(16, 16);
    let base = Settings {
        photons_per_pass: 10_000,
        ..Settings::default()
    };
    let cases = [
        (
            Settings {
                alpha: 1.5,
                ..base.clone()
            },
            "alpha",
        ),
        (
            Settings {
                alpha: 0.0,
                ..base.clone()
            },
            "alpha",
        ),
        (
            Settings {
                alpha: f32::NAN,
                ..base.clone()
            },
            "alpha",
        ),
        (
            Settings {
                photons_per_pass: 0,
                ..base.clone()
            },
            "photons",
        ),
        (
            Settings {
                cone_k: Some(0.5),
                ..base.clone()
            },
            "cone",
        ),
        (
            Settings {
                initial_radius: Some(-1.0),
                ..base.clone()
            },
            "radius",
        ),
        (
            Settings {
                hit_slots: 0,
                ..base.clone()
            },
            "hit slots",
        ),
        (
            Settings {
                hit_slots: 9,
                ..base.clone()
            },
            "hit slots",
        ),
        (
            Settings {
                max_photon_depth: 0,
                ..base.clone()
            },
            "depth",
        ),
    ];
    for (settings, what) in cases {
        // An error, not a panic (a panic would fail this test), naming the setting.
        match Renderer::new(&ctx, &scene, settings.clone()) {
            Ok(_) => panic!("Renderer::new accepted {settings:?}"),
            Err(e) => {
                let msg = format!("{e:#}");
                assert!(
                    msg.contains(what),
                    "error for {settings:?} does not mention {what:?}: {msg}"
                );
            }
        }
    }
    assert_clean(&ctx);
}

#[test]
fn bad_scene_is_an_error_naming_the_line() {
    let text = std::fs::read_to_string(CORNELL).unwrap();
    // The blue sphere's radius, the only "radius = 0.3" line.
    let line = text
        .lines()
        .position(|l| l.trim() == "radius = 0.3")
        .expect("the blue sphere's radius line")
        + 1;
    let bad = text.replacen("radius = 0.3", "radius = nan", 1);
    let err = Scene::parse(&bad, "cornell-nan.toml").expect_err("a NaN radius was accepted");
    let msg = format!("{err:#}");
    println!("{msg}");
    assert!(
        msg.starts_with(&format!("cornell-nan.toml:{line}:")),
        "error does not name line {line}: {msg}"
    );
    assert!(msg.contains("sphere[1].radius") && msg.contains("NaN"), "{msg}");

    // The unmodified text parses, so the error above is the radius's alone.
    Scene::parse(&text, "cornell.toml").unwrap();
    // A few more: a negative radius, an emission that is not finite, a missing camera.
    assert!(Scene::parse(&text.replacen("radius = 0.3", "radius = -0.3", 1), "x").is_err());
    assert!(Scene::parse(
        &text.replacen("emission = [34.0, 30.0, 24.0]", "emission = [inf, 30.0, 24.0]", 1),
        "x"
    )
    .is_err());
    assert!(Scene::parse(&text.replacen("[camera]", "[kamera]", 1), "x").is_err());
}

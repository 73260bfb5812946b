//! Every kind of light against Mitsuba 3, from one XML file that both renderers read (scenes/*.xml; the
//! references, their spp and times, and what each leaves out: scenes/references/README-lights.md). The
//! mean per channel within 1% of the reference's, at the reference's resolution.

mod common;

use std::path::Path;

use common::*;
use ppm_vk_engine::metrics::Reference;
use ppm_vk_engine::scene::Scene;
use ppm_vk_engine::{Mode, RgbImage, Settings};

/// scenes/NAME.xml rendered with `passes` passes of 200k photons, and its reference.
fn render_against(name: &str, passes: u32) -> (RgbImage, RgbImage) {
    render_against_with(name, passes, Settings::default())
}

fn render_against_with(name: &str, passes: u32, settings: Settings) -> (RgbImage, RgbImage) {
    let root = env!("CARGO_MANIFEST_DIR");
    let reference = Reference::load(Path::new(&format!("{root}/scenes/references/{name}.exr")))
        .unwrap_or_else(|e| panic!("{name}: {e:#}"));
    let scene = Scene::load(Path::new(&format!("{root}/scenes/{name}.xml"))).unwrap_or_else(|e| panic!("{e:#}"));
    let settings = Settings {
        mode: Mode::Sppm,
        photons_per_pass: 200_000,
        ..settings
    };
    let ctx = ctx();
    let image = render(&ctx, &scene, settings, passes);
    assert_clean(&ctx);
    assert_eq!(
        (image.width, image.height),
        (reference.image.width, reference.image.height)
    );
    (image, reference.image)
}

/// The image's mean per channel against the reference's plus `missing` (what the reference is known to
/// leave out, per channel), within `tol`.
fn check_mean(name: &str, image: &RgbImage, reference: &RgbImage, missing: f64, tol: f64) {
    let (got, want) = (image.mean(), reference.mean().map(|m| m + missing));
    println!("{name}: mean {got:.5?}, Mitsuba {want:.5?}");
    for c in 0..3 {
        let rel = got[c] / want[c] - 1.0;
        assert!(
            rel.abs() < tol,
            "{name}, channel {c}: {:+.2}% off Mitsuba's",
            100.0 * rel
        );
    }
}

/// The sun and a dim sky over a tilted plane and a box (measured: within 0.01%).
#[test]
fn sun_plane_matches_mitsuba() {
    let (image, reference) = render_against("sun-plane", 8);
    check_mean("sun-plane", &image, &reference, 0.0, 0.01);
}

/// A constant sky over a diffuse and a glass sphere on a floor (measured: within 0.01%).
#[test]
fn env_constant_matches_mitsuba() {
    let (image, reference) = render_against("env-constant", 8);
    check_mean("env-constant", &image, &reference, 0.0, 0.01);
}

/// A room lit through its window by an environment map with a sun in it (measured: within 0.1%).
#[test]
fn env_window_matches_mitsuba() {
    let (image, reference) = render_against("env-window", 12);
    check_mean("env-window", &image, &reference, 0.0, 0.01);
}

/// A point light in a box with a mirror sphere (measured: +0.1 to +0.2%; the reference's hybrid
/// integrator leaves out under 0.1%, README-lights.md).
#[test]
fn point_box_matches_mitsuba() {
    let (image, reference) = render_against("point-box", 12);
    check_mean("point-box", &image, &reference, 0.0, 0.01);
}

/// A spot's caustic through a glass sphere (measured: +0.6% against the reference alone, which leaves
/// out 5.4e-4 per channel, 0.55% of the mean: light from the spot through the glass seen through the glass,
/// README-lights.md; added back here).
#[test]
fn spot_caustic_matches_mitsuba() {
    let (image, reference) = render_against("spot-caustic", 12);
    check_mean("spot-caustic", &image, &reference, 5.41e-4, 0.01);
}

/// Veach's setting: four glowing spheres of radii 1 cm to 0.5 m over rough aluminium plates (alpha 0.05
/// to 0.35), with every plate a glossy hit point (`--glossy-hits 0.04`), where shadow rays sample the
/// spheres (measured: -0.5%). With the default (plates below alpha 0.15 sampled through) an eye path finds
/// the 1 cm sphere (radiance 5000) in the two sharpest plates only by chance, and the image's mean is
/// heavy-tailed (-1% to -2.4% after 24 to 64 passes): next-event estimation at every glossy vertex (issue
/// 38) is what closes that.
#[test]
fn glowing_spheres_match_mitsuba() {
    let settings = Settings {
        glossy_hits: Some(0.04),
        ..Settings::default()
    };
    let (image, reference) = render_against_with("glowing-spheres", 24, settings);
    check_mean("glowing-spheres", &image, &reference, 0.0, 0.01);
}

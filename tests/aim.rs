//! Photons aimed at what casts caustics (`Settings::caustic_photons`, photon/targets.glsl): a share of every
//! area light's photons leaves inside the cones of the spheres around the mirrors and glass, each weighed
//! by the mixture's density. Checked against what does not share its code: Mitsuba's references of
//! glass-on-table (its torus casts a caustic a few millimetres wide, reached by 2% of the light's photons)
//! and of cornell-spheres (its regions' means), and the twin's weights in crates/reference/src/targets.rs.

mod common;

use common::*;
use ppm_vk_engine::metrics::{compare, Reference, Region};
use ppm_vk_engine::{RgbImage, Scene, Settings};

fn render_aimed(scene: &Scene, share: f32, passes: u32) -> RgbImage {
    let settings = Settings {
        photons_per_pass: 250_000,
        caustic_photons: share,
        ..Settings::default()
    };
    render_clean(scene, settings, passes)
}

#[test]
fn aimed_photons_sharpen_a_narrow_caustic() {
    let path = format!("{}/scenes/references/glass-on-table.exr", env!("CARGO_MANIFEST_DIR"));
    let reference = Reference::load(std::path::Path::new(&path)).unwrap();
    let scene = load(&format!("{}/scenes/glass-on-table.toml", env!("CARGO_MANIFEST_DIR"))).with_resolution(128, 128);
    // The torus's foot, in the reference's 256 x 256 pixels (docs/accuracy.md's region).
    let torus = Region::new("torus", 80, 110, 96, 40);
    let small = reference.at_resolution(128, 128).unwrap().image;
    let mut errors = Vec::new();
    for share in [0.0, 0.5] {
        let image = render_aimed(&scene, share, 24);
        let whole = compare(&image, &reference, None, true).unwrap();
        let foot = compare(&image, &reference, Some(&torus), true).unwrap();
        println!(
            "caustic_photons {share}: relMSE {:.5}, the torus's foot {:.5}",
            whole.rel_mse, foot.rel_mse
        );
        // Unbiased either way: the image's mean within 1% of Mitsuba's.
        assert_means_within(&format!("caustic_photons {share}"), image.mean(), small.mean(), 0.01);
        errors.push((whole.rel_mse, foot.rel_mse));
    }
    let ((off, off_foot), (on, on_foot)) = (errors[0], errors[1]);
    // Measured 0.107 -> 0.054 at the torus's foot and 0.0080 -> 0.0043 in all, at equal passes (each pass
    // dearer: at equal time on lavapipe aiming loses, docs/accuracy.md).
    assert!(
        on_foot < 0.7 * off_foot,
        "the torus's foot: {on_foot} aimed against {off_foot}"
    );
    assert!(on < 0.8 * off, "relMSE {on} aimed against {off}");
}

#[test]
fn aiming_most_photons_keeps_every_regions_mean() {
    // 90% of the photons into the mirror and glass spheres' cones: the walls, the floor and the caustic
    // keep Mitsuba's means (the weights, not the share, carry the light).
    let reference = Reference::load(std::path::Path::new(CORNELL_REFERENCE)).unwrap();
    // Measured within 0.7% in all and 1.6% in the caustic.
    let image = render_aimed(&load(CORNELL).with_resolution(64, 64), 0.9, 16);
    let small = reference.at_resolution(64, 64).unwrap().image;
    assert_means_within("caustic_photons 0.9", image.mean(), small.mean(), 0.01);
    for r in load(CORNELL).regions.iter().map(|r| r.pixels(64, 64)) {
        let (cols, rows) = (r.x0..r.x0 + r.w, r.y0..r.y0 + r.h);
        let got = window_mean(&image, cols.clone(), rows.clone());
        let want = window_mean(&small, cols, rows);
        assert_means_within(&format!("caustic_photons 0.9, region {}", r.name), got, want, 0.05);
    }
}

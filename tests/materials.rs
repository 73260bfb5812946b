//! The materials against Mitsuba 3, each on a scene file both renderers read: the same XML, rendered by
//! ppm-vk's Mitsuba reader and by Mitsuba's path tracer (scenes/references/, with the script that made
//! each reference).

mod common;

use std::path::Path;

use common::*;
use ppm_vk_engine::metrics::{compare, Reference};
use ppm_vk_engine::{Mode, Scene, Settings};

const REFERENCES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/references");

/// cornell-spheres with its mirror sphere of Mitsuba's gold (`conductor`, material "Au"): 128 x 128 (the
/// 256 x 256 reference block-averaged by 2), SPPM, 16 passes of 100k photons. The mean per channel within
/// 1% of Mitsuba's (measured: within 0.07%), and the image's relMSE under 0.008 (measured 0.0035, most of
/// it the 16 passes' noise), which the same scene with the sphere a plain mirror (no Fresnel term) exceeds
/// (measured 0.0152): the control at the end.
#[test]
fn a_gold_sphere_matches_its_mitsuba_reference() {
    let xml = Path::new(REFERENCES).join("cornell-gold.xml");
    let defines = [("res".to_string(), "128".to_string())];
    let scene = Scene::load_with(&xml, &defines).unwrap_or_else(|e| panic!("{e:#}"));
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let reference = Reference::load(&Path::new(REFERENCES).join("cornell-gold.exr")).unwrap();
    let ctx = ctx();
    let image = render(&ctx, &scene, r_settings(), 16);
    let e = compare(&image, &reference, None, true).unwrap();
    let (mean, want) = (image.mean(), reference.at_resolution(128, 128).unwrap().image.mean());
    println!("mean {mean:?} vs {want:?}, relMSE {:.5}, RMSE {:.4}", e.rel_mse, e.rmse);
    for c in 0..3 {
        let rel = mean[c] / want[c] - 1.0;
        assert!(
            rel.abs() < 0.01,
            "channel {c}: mean {:+.2}% off the reference",
            100.0 * rel
        );
    }
    const BOUND: f64 = 0.008;
    assert!(e.rel_mse < BOUND, "relMSE {}", e.rel_mse);
    // The control: the same scene with the sphere a plain mirror (reflectance 0.95, no Fresnel term), as
    // ../shared/reference/cornell-spheres.xml has it, is far from the gold reference.
    let mirror = Scene::load_with(
        concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/reference/cornell-spheres.xml"),
        &defines,
    )
    .unwrap_or_else(|e| panic!("{e:#}"));
    let m = compare(&render(&ctx, &mirror, r_settings(), 16), &reference, None, true).unwrap();
    println!("the mirror instead: relMSE {:.5}", m.rel_mse);
    assert!(
        m.rel_mse > BOUND,
        "the bound cannot tell gold from a mirror: {}",
        m.rel_mse
    );
    assert_clean(&ctx);
}

fn r_settings() -> Settings {
    Settings {
        mode: Mode::Sppm,
        photons_per_pass: 100_000,
        ..Settings::default()
    }
}

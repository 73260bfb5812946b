//! The materials against Mitsuba 3, each on a scene file both renderers read: the same XML, rendered by
//! ppm-vk's Mitsuba reader and by Mitsuba's path tracer (scenes/references/, with the script that made
//! each reference).

mod common;

use std::path::Path;

use common::*;
use glam::Vec3;
use ppm_vk_engine::metrics::{compare, Reference, Region};
use ppm_vk_engine::scene::{Microfacet, Surface};
use ppm_vk_engine::{DirectLight, Mode, RgbImage, Scene, Settings};

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
    println!("relMSE {:.5}, RMSE {:.4}", e.rel_mse, e.rmse);
    assert_mean_within_1_percent(&image, &reference);
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

/// scenes/references/NAME.xml read at 128 x 128 (its reference block-averaged by 2), with no warning, and
/// its Mitsuba reference NAME.exr.
fn reference_scene(name: &str) -> (Scene, Reference) {
    let xml = Path::new(REFERENCES).join(format!("{name}.xml"));
    let defines = [("res".to_string(), "128".to_string())];
    let scene = Scene::load_with(&xml, &defines).unwrap_or_else(|e| panic!("{e:#}"));
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let reference = Reference::load(&Path::new(REFERENCES).join(format!("{name}.exr"))).unwrap();
    (scene, reference)
}

/// `what`'s relMSE `e` under `bound`, and its control's above it: the bound tells the two apart
/// (`control_is` says what the control is).
fn assert_bound_separates(what: &str, e: f64, control: f64, bound: f64, control_is: &str) {
    assert!(e < bound, "{what}: relMSE {e} (bound {bound})");
    assert!(
        control > bound,
        "{what}: the bound {bound} cannot tell it from {control_is}: {control}"
    );
}

/// The image's mean per channel within 1% of the reference's (taken at the image's resolution).
fn assert_mean_within_1_percent(image: &RgbImage, reference: &Reference) {
    let want = reference.at_resolution(image.width, image.height).unwrap().image.mean();
    let mean = image.mean();
    println!("mean {mean:?} vs {want:?}");
    for c in 0..3 {
        let rel = mean[c] / want[c] - 1.0;
        assert!(
            rel.abs() < 0.01,
            "channel {c}: mean {:+.2}% off the reference",
            100.0 * rel
        );
    }
}

fn r_settings() -> Settings {
    Settings {
        mode: Mode::Sppm,
        photons_per_pass: 100_000,
        ..Settings::default()
    }
}

/// scenes/references/cornell-coated.xml: cornell-gold with a white plastic floor (Mitsuba's default coat),
/// a blue plastic sphere (index 1.5, nonlinear, specular_reflectance 0.8) and a thin tinted glass pane
/// (thindielectric, specular_transmittance 0.95 0.75 0.5) in front of it, against Mitsuba's path tracer on
/// the same XML (make_reference.py). 128 x 128, SPPM, 32 passes of 100k photons, direct light by shadow
/// rays. The mean per channel within 1% (measured: within 0.03%) and the relMSE under a bound that each
/// of two controls exceeds:
/// the plastics made diffuse of their diffuse_reflectance (no coat), and the pane made invisible (scored
/// on the pane's part of the image).
#[test]
fn plastic_and_a_thin_pane_match_their_mitsuba_reference() {
    let (scene, reference) = reference_scene("cornell-coated");
    // The pane and the sphere behind it, in the reference's 256 x 256 pixels.
    let pane = Region {
        name: "pane".into(),
        x0: 150,
        y0: 120,
        w: 70,
        h: 90,
    };
    let ctx = ctx();
    let score = |scene: &Scene| {
        let image = render(&ctx, scene, r_settings(), 32);
        let all = compare(&image, &reference, None, true).unwrap();
        let region = compare(&image, &reference, Some(&pane), true).unwrap();
        (image, all.rel_mse, region.rel_mse)
    };
    let (image, rel_mse, pane_rel_mse) = score(&scene);
    println!("relMSE {rel_mse:.5}, on the pane {pane_rel_mse:.5}");
    assert_mean_within_1_percent(&image, &reference);
    // Measured 0.0021 on the whole and 0.0017 on the pane (most of it the 32 passes' noise); the controls
    // 0.0085 and 0.030.
    const BOUND: f64 = 0.005;
    const PANE_BOUND: f64 = 0.006;
    assert!(rel_mse < BOUND, "relMSE {rel_mse}");
    assert!(pane_rel_mse < PANE_BOUND, "relMSE on the pane {pane_rel_mse}");

    let mut uncoated = scene.clone();
    for m in &mut uncoated.materials {
        if let Surface::Plastic { diffuse, .. } = m.surface {
            m.surface = Surface::Diffuse { albedo: diffuse };
        }
    }
    let (_, control, _) = score(&uncoated);
    println!("the plastics diffuse: relMSE {control:.5}");
    assert!(control > BOUND, "the bound cannot tell plastic from diffuse: {control}");
    let mut paneless = scene.clone();
    for m in &mut paneless.materials {
        if let Surface::ThinDielectric { ior, .. } = m.surface {
            m.surface = Surface::ThinDielectric {
                ior,
                reflectance: Vec3::ZERO,
                transmittance: Vec3::ONE,
            };
        }
    }
    let (_, _, control) = score(&paneless);
    println!("the pane invisible: relMSE on it {control:.5}");
    assert!(
        control > PANE_BOUND,
        "the bound cannot tell the pane from none: {control}"
    );
    assert_clean(&ctx);
}

/// scenes/references/cornell-rough.xml: cornell-gold with the gold sphere a rough conductor (GGX, alpha
/// 0.2, "Au") and the glass sphere rough glass (Beckmann, alpha 0.1), against Mitsuba's path tracer on the
/// same XML (16384 spp). 128 x 128, SPPM, 32 passes of 100k photons, direct light by shadow rays. The mean
/// per channel within 1% and the relMSE on each sphere's part of the image under a bound that the control,
/// the same spheres smooth, exceeds.
#[test]
fn rough_metal_and_rough_glass_match_their_mitsuba_reference() {
    let (scene, reference) = reference_scene("cornell-rough");
    // The spheres, in the reference's 256 x 256 pixels: the gold one (left, back) and the glass one (front).
    let regions = [
        Region {
            name: "rough gold".into(),
            x0: 40,
            y0: 120,
            w: 90,
            h: 90,
        },
        Region {
            name: "rough glass".into(),
            x0: 100,
            y0: 140,
            w: 90,
            h: 90,
        },
    ];
    let ctx = ctx();
    let score = |scene: &Scene| {
        let image = render(&ctx, scene, r_settings(), 32);
        let all = compare(&image, &reference, None, true).unwrap().rel_mse;
        let parts = regions
            .each_ref()
            .map(|r| compare(&image, &reference, Some(r), true).unwrap().rel_mse);
        (image, all, parts)
    };
    let (image, rel_mse, parts) = score(&scene);
    println!("relMSE {rel_mse:.5}, on the spheres {parts:?}");
    assert_mean_within_1_percent(&image, &reference);
    let mut smooth = scene.clone();
    for m in &mut smooth.materials {
        m.surface = match m.surface {
            Surface::RoughConductor {
                reflectance, eta, k, ..
            } => Surface::Conductor { reflectance, eta, k },
            Surface::RoughGlass { ior, .. } => Surface::Glass { ior },
            s => s,
        };
    }
    let (_, control_all, control) = score(&smooth);
    println!("the spheres smooth: relMSE {control_all:.5}, on the spheres {control:?}");
    // Measured 0.0215 on the gold sphere and 0.0125 on the glass one (the noise of 32 passes: what a
    // sphere shows of the light it shows through its sampled lobe), 0.0046 on the whole; the controls
    // 0.086, 0.052 and 0.017.
    const BOUNDS: [f64; 2] = [0.04, 0.03];
    for k in 0..2 {
        let what = format!("the {} sphere", regions[k].name);
        assert_bound_separates(&what, parts[k], control[k], BOUNDS[k], "a smooth one");
    }
    assert!(
        rel_mse < 0.01 && control_all > 0.01,
        "relMSE {rel_mse}, the control {control_all}"
    );
    assert_clean(&ctx);
}

/// scenes/references/cornell-roughplastic.xml: cornell-coated with both plastics rough (Mitsuba's
/// roughplastic: the floor GGX alpha 0.2, the blue sphere Beckmann alpha 0.1), against Mitsuba's path tracer
/// on the same XML (16384 spp). 128 x 128, SPPM, 32 passes of 100k photons. The mean per channel within 1%,
/// and the relMSE under a bound that the control, the same plastics smooth, exceeds.
#[test]
fn rough_plastic_matches_its_mitsuba_reference() {
    let (scene, reference) = reference_scene("cornell-roughplastic");
    let ctx = ctx();
    let image = render(&ctx, &scene, r_settings(), 32);
    let e = compare(&image, &reference, None, true).unwrap();
    println!("relMSE {:.5}", e.rel_mse);
    assert_mean_within_1_percent(&image, &reference);
    let mut smooth = scene.clone();
    for m in &mut smooth.materials {
        if let Surface::Plastic { ref mut rough, .. } = m.surface {
            *rough = None;
        }
    }
    let c = compare(&render(&ctx, &smooth, r_settings(), 32), &reference, None, true).unwrap();
    println!("the plastics smooth: relMSE {:.5}", c.rel_mse);
    // Measured 0.0020 (the mean within 0.11%), the control 0.044.
    const BOUND: f64 = 0.005;
    assert_bound_separates("rough plastic", e.rel_mse, c.rel_mse, BOUND, "smooth plastic");
    assert_clean(&ctx);
}

/// A furnace of rough metal: a closed sphere of rough aluminium (GGX, alpha 0.3, twosided) lit from
/// inside by a small light out of view, with no diffuse surface at all, so every pixel is light that
/// reached the eye through glossy bounces only (43% of it after one, 5% after more than ten; Mitsuba's
/// single-scattering microfacets keep about 0.76 per bounce), against Mitsuba's path tracer on the same
/// XML (scenes/references/furnace-rough.xml, 16384 spp). 64 x 64, 64 passes: the mean within 1%, the
/// relMSE under a bound that the control, the same sphere a little rougher (alpha 0.4), exceeds; and the
/// same with glossy hit points on the sphere (Settings::glossy_hits), where the photons carry the light.
#[test]
fn a_rough_metal_furnace_matches_its_mitsuba_reference() {
    let xml = Path::new(REFERENCES).join("furnace-rough.xml");
    let scene = Scene::load(&xml).unwrap_or_else(|e| panic!("{e:#}"));
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let reference = Reference::load(&Path::new(REFERENCES).join("furnace-rough.exr")).unwrap();
    let ctx = ctx();
    let through = Settings {
        glossy_hits: None,
        ..r_settings()
    };
    let image = render(&ctx, &scene, through.clone(), 64);
    let e = compare(&image, &reference, None, true).unwrap();
    println!("sampled through: relMSE {:.6}", e.rel_mse);
    assert_mean_within_1_percent(&image, &reference);
    let mut rougher = scene.clone();
    for m in &mut rougher.materials {
        if let Surface::RoughConductor { ref mut rough, .. } = m.surface {
            *rough = Microfacet::isotropic(rough.ggx, 0.4);
        }
    }
    let control = render(&ctx, &rougher, through, 64);
    let c = compare(&control, &reference, None, true).unwrap();
    println!("alpha 0.4: mean {:?}, relMSE {:.6}", control.mean(), c.rel_mse);
    // Measured 0.00021 (the mean within 0.16%; 0.018 when most pixels took 1 light-sampling path a pass:
    // now the pilot marks every pixel as seeing rough metal, and each takes all 16, and its first rough
    // vertex splits in 4), the control 0.103 (its mean 34% lower).
    const BOUND: f64 = 0.003;
    assert_bound_separates("alpha 0.3", e.rel_mse, c.rel_mse, BOUND, "alpha 0.4");

    // Glossy hit points: the same furnace lit by photons alone (but the direct light's shadow rays), each
    // weighed by the rough BRDF in the gather: an independent check of that estimator, whose every
    // record lies on the rough metal.
    let glossy = Settings {
        glossy_hits: Some(0.0),
        ..r_settings()
    };
    let image = render(&ctx, &scene, glossy, 32);
    let g = compare(&image, &reference, None, true).unwrap();
    println!("glossy hit points: relMSE {:.6}", g.rel_mse);
    assert_mean_within_1_percent(&image, &reference);
    // Measured 0.00012 (the mean within 0.02%), in half the passes of the sampled-through render above.
    assert!(g.rel_mse < 0.001, "relMSE {}", g.rel_mse);
    assert_clean(&ctx);
}

/// A white plastic floor (Mitsuba's default coat, diffuse_reflectance 0.5) under a small square light,
/// seen from straight above: its radiance has a closed form, the coat's reflection of the light
/// (specular_reflectance F(1) Le: the camera's rays reflect back up into it) plus the base's
/// D (1 - F(1)) / pi Le times the integral over the light of (1 - F(cos_i)) cos_i cos_l / d^2, the latter
/// by a 512 x 512 midpoint rule here. 60 passes of 200k photons, PPM. Both direct-light modes: by photons the records' (1 - F(cos_i))
/// carries the base's share, by shadow rays the light sample's. F and D are the host's
/// (ppm_vk_materials::plastic), checked against Mitsuba's plastic (reference::plastic's tests).
#[test]
fn plastic_under_a_square_light_matches_its_closed_form() {
    use ppm_vk_materials::plastic::{self, coat_fresnel, diffuse_factor};
    let scene = Scene::parse(
        &OPEN_FLOOR.replace("diffuse = [0.5, 0.5, 0.5]", "plastic = { diffuse = [0.5, 0.5, 0.5] }"),
        "open-plastic-floor.toml",
    )
    .unwrap_or_else(|e| panic!("{e:#}"));
    let (le, half, ior) = (10.0f64, 0.1f64, 1.49f32 / 1.000277);
    let fresnel = |c: f64| coat_fresnel(c as f32, ior) as f64;
    let n = 512;
    let cell = 2.0 * half / n as f64;
    let mut integral = 0.0;
    for i in 0..n {
        for j in 0..n {
            let (x, z) = (-half + (i as f64 + 0.5) * cell, -half + (j as f64 + 0.5) * cell);
            let d2 = x * x + z * z + 1.0;
            let cos = 1.0 / d2.sqrt(); // at the floor and at the light alike
            integral += (1.0 - fresnel(cos)) * cos * cos / d2 * cell * cell;
        }
    }
    let d = diffuse_factor(Vec3::splat(0.5), ior, false, plastic::coat(ior, None).internal).x as f64;
    let coat = fresnel(1.0) * le;
    let base = d * (1.0 - fresnel(1.0)) / std::f64::consts::PI * le * integral;
    let want = coat + base;
    println!("closed form {want:.5}: the coat's reflection {coat:.5}, the base {base:.5}");
    let ctx = ctx();
    for (direct, got) in under_the_square_light(&ctx, &scene) {
        println!("{direct:?}: {got:?}, the base {:.5}", got[0] - coat);
        for (c, got) in got.iter().enumerate() {
            // The coat's reflection is exact in each sample (the camera's rays all reflect into the light),
            // so what is left is the base's: by photons within 2.5% (their noise and the radius's 0.25%
            // falloff bias, as the diffuse floor's in tests/stability.rs), by shadow rays 1%. A base term
            // missing the coat's (1 - F(cos_i)) is 4% high.
            let tol = if direct == DirectLight::Sample { 0.01 } else { 0.025 };
            let rel = (got - coat) / base - 1.0;
            assert!(
                rel.abs() < tol,
                "{direct:?}, channel {c}: the base {:+.2}% off",
                100.0 * rel
            );
        }
    }
    assert_clean(&ctx);
}

/// cornell-aniso's two rough spheres, in its reference's 256 x 256 pixels.
fn cornell_aniso_regions() -> [Region; 2] {
    [
        Region::new("gold", 40, 120, 90, 90),
        Region::new("glass", 100, 140, 90, 90),
    ]
}

/// scenes/references/cornell-aniso.xml: an anisotropic gold sphere (GGX, alpha 0.05 along its longitude and
/// 0.4 across) and an anisotropic rough glass mesh (Beckmann 0.05 / 0.3 along each triangle's first edge,
/// smooth-shaded) against Mitsuba's path tracer on the same XML (8192 spp). 128 x 128, SPPM, 32 passes of
/// 100k photons. The mean per channel within 1%, and the relMSE on each sphere under a bound that the
/// control exceeds: the same lobes turned a quarter turn (alpha_u and alpha_v swapped), which is what a
/// tangent across Mitsuba's would render.
#[test]
fn anisotropic_roughness_matches_its_mitsuba_reference() {
    let (scene, reference) = reference_scene("cornell-aniso");
    let regions = cornell_aniso_regions();
    let mut turned = scene.clone();
    for m in &mut turned.materials {
        if let Surface::RoughConductor { ref mut rough, .. } | Surface::RoughGlass { ref mut rough, .. } = m.surface {
            std::mem::swap(&mut rough.alpha, &mut rough.alpha_v);
        }
    }
    let ctx = ctx();
    let image = render(&ctx, &scene, r_settings(), 32);
    assert_mean_within_1_percent(&image, &reference);
    let control = render(&ctx, &turned, r_settings(), 32);
    // Measured: gold 0.0019, glass 0.0034 (the mean within 0.17%; 0.0098 and 0.012 before rough vertices
    // split the eye paths and took more light samples); turned a quarter 2.0 and 0.64.
    for (region, bound) in regions.iter().zip([0.02, 0.025]) {
        let e = compare(&image, &reference, Some(region), true).unwrap();
        let c = compare(&control, &reference, Some(region), true).unwrap();
        println!(
            "{}: relMSE {:.5}, turned a quarter {:.5}",
            region.name, e.rel_mse, c.rel_mse
        );
        assert_bound_separates(&region.name, e.rel_mse, c.rel_mse, bound, "its lobes' quarter turn");
    }
    assert_clean(&ctx);
}

/// SPPM's split at rough vertices (ray.comp, `Settings::rough_splits`): an eye path's first rough vertex
/// draws 4 directions of its lobe, each a hit point weighted 1/4. Their sum is one sample of the light
/// through the lobe, so on cornell-aniso (128 x 128, 16 passes of 100k photons) the image mean with the
/// split and with one direction each lie within 1% of Mitsuba's and within 0.5% of each other, and the
/// split lowers the relMSE on both rough spheres at equal passes.
/// The same for more eye paths in the pixels where the pilot saw a rough lobe (`Settings::rough_samples`
/// 32 against the default, emission_samples' 16): the counts are fixed before the samples they count are
/// drawn, so the mean is the same, and the spheres' error is lower.
#[test]
fn rough_splits_and_samples_keep_the_mean_and_lower_the_spheres_error() {
    let (scene, reference) = reference_scene("cornell-aniso");
    let regions = cornell_aniso_regions();
    let ctx = ctx();
    let four = render(&ctx, &scene, r_settings(), 16);
    let one = Settings {
        rough_splits: 1,
        ..r_settings()
    };
    let one = render(&ctx, &scene, one, 16);
    assert_eq!(r_settings().rough_pixel_samples(), r_settings().emission_samples);
    let more = Settings {
        rough_samples: 32,
        ..r_settings()
    };
    let more = render(&ctx, &scene, more, 16);
    assert_mean_within_1_percent(&four, &reference);
    assert_mean_within_1_percent(&one, &reference);
    assert_mean_within_1_percent(&more, &reference);
    let m4 = four.mean();
    for (name, other) in [("one direction", &one), ("32 samples", &more)] {
        let m = other.mean();
        for c in 0..3 {
            let rel = m4[c] / m[c] - 1.0;
            assert!(
                rel.abs() < 0.005,
                "channel {c}: the default's mean {:+.2}% off {name}'s",
                100.0 * rel
            );
        }
    }
    // Measured: split against one direction, gold 0.00357 against 0.00551, glass 0.00657 against 0.01011
    // (0.65x both); 32 samples against 16, gold 0.00260 (0.73x), glass 0.00464 (0.71x).
    for (region, most) in regions.iter().zip([0.8, 0.8]) {
        let e4 = compare(&four, &reference, Some(region), true).unwrap().rel_mse;
        let e1 = compare(&one, &reference, Some(region), true).unwrap().rel_mse;
        let e32 = compare(&more, &reference, Some(region), true).unwrap().rel_mse;
        println!(
            "{}: relMSE split in 4 {e4:.5}, one direction {e1:.5} ({:.2}x); 32 samples {e32:.5} ({:.2}x)",
            region.name,
            e4 / e1,
            e32 / e4
        );
        assert!(
            e4 < most * e1,
            "{}: the split's relMSE {e4} is not below {most} x {e1}",
            region.name
        );
        assert!(
            e32 < e4,
            "{}: 32 samples' relMSE {e32} is not below 16's {e4}",
            region.name
        );
    }
    assert_clean(&ctx);
}

/// scenes/references/cornell-smooth.xml: cornell-spheres with its glass and blue spheres coarse icospheres
/// (320 triangles) smooth-shaded by their vertex normals, against Mitsuba's path tracer on the same XML
/// (8192 spp). 128 x 128, SPPM, 32 passes of 100k photons. The mean per channel within 1%, and the relMSE
/// of the image and of the glass sphere under bounds that the control, the same meshes shaded flat
/// (`face_normals`), exceeds.
#[test]
fn smooth_shading_matches_its_mitsuba_reference() {
    let xml = Path::new(REFERENCES).join("cornell-smooth.xml");
    let load = |face_normals: &str| {
        let defines = [
            ("res".to_string(), "128".to_string()),
            ("face_normals".to_string(), face_normals.to_string()),
        ];
        let scene = Scene::load_with(&xml, &defines).unwrap_or_else(|e| panic!("{e:#}"));
        assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
        scene
    };
    let reference = Reference::load(&Path::new(REFERENCES).join("cornell-smooth.exr")).unwrap();
    // In the reference's 256 x 256 pixels.
    let glass = Region::new("glass", 100, 145, 80, 75);
    let ctx = ctx();
    let image = render(&ctx, &load("false"), r_settings(), 32);
    let e = compare(&image, &reference, None, true).unwrap();
    let eg = compare(&image, &reference, Some(&glass), true).unwrap();
    println!("relMSE {:.5}, glass sphere {:.5}", e.rel_mse, eg.rel_mse);
    assert_mean_within_1_percent(&image, &reference);
    let flat = render(&ctx, &load("true"), r_settings(), 32);
    let c = compare(&flat, &reference, None, true).unwrap();
    let cg = compare(&flat, &reference, Some(&glass), true).unwrap();
    println!("shaded flat: relMSE {:.5}, glass sphere {:.5}", c.rel_mse, cg.rel_mse);
    // Measured 0.0023 and 0.0052 (the mean within 0.2%); flat 0.016 and 0.125.
    const BOUND: f64 = 0.006;
    const GLASS_BOUND: f64 = 0.03;
    assert_bound_separates("the image", e.rel_mse, c.rel_mse, BOUND, "flat shading");
    assert_bound_separates("the glass sphere", eg.rel_mse, cg.rel_mse, GLASS_BOUND, "flat shading");
    assert_clean(&ctx);
}

/// scenes/references/cornell-tilted.xml: the Cornell box without spheres, its floor two triangles whose
/// vertex normals all lean 30 degrees towards +x, against Mitsuba's path tracer on the same XML (16384
/// spp). The ceiling sees no light but what the floor and walls reflect, so the light photons carry off
/// the floor must follow the shading normal: Veach's correction at their floor bounce (shading.glsl).
/// 128 x 128, SPPM, 32 passes of 100k photons, both direct-light modes: the mean per channel within 1%
/// and the relMSE under a bound that the control, the floor shaded flat, exceeds. Measured 0.00125 by
/// shadow rays and 0.0023 by photons (means within 0.02%); with the correction taken out of shading.glsl
/// (a build for the purpose) 0.0032 and 0.016, the means 1.6% and 3.2% high.
#[test]
fn photons_off_a_tilted_shading_normal_match_their_mitsuba_reference() {
    let (scene, reference) = reference_scene("cornell-tilted");
    assert!(scene.meshes[0].normals.is_some(), "the floor is smooth-shaded");
    let mut flat = scene.clone();
    flat.meshes[0].normals = None;
    let ctx = ctx();
    for (direct, bound) in [(DirectLight::Sample, 0.002), (DirectLight::Photons, 0.005)] {
        let settings = Settings { direct, ..r_settings() };
        let image = render(&ctx, &scene, settings.clone(), 32);
        let e = compare(&image, &reference, None, true).unwrap();
        println!("{direct:?}: relMSE {:.5}", e.rel_mse);
        assert_mean_within_1_percent(&image, &reference);
        let c = compare(&render(&ctx, &flat, settings, 32), &reference, None, true).unwrap();
        println!("{direct:?}, the floor flat: relMSE {:.5}", c.rel_mse);
        assert_bound_separates(&format!("{direct:?}"), e.rel_mse, c.rel_mse, bound, "a flat floor");
    }
    assert_clean(&ctx);
}

/// The mean of an OPEN_FLOOR scene seen from straight above, after 60 PPM passes of 200k photons (radius
/// 0.05), with direct light by photons, then by shadow rays.
fn under_the_square_light(ctx: &ppm_vk_engine::Context, scene: &Scene) -> Vec<(DirectLight, [f64; 3])> {
    [DirectLight::Photons, DirectLight::Sample]
        .into_iter()
        .map(|direct| {
            let settings = Settings {
                mode: Mode::Ppm,
                photons_per_pass: 200_000,
                initial_radius: Some(0.05),
                direct,
                ..Settings::default()
            };
            (direct, render(ctx, scene, settings, 60).mean())
        })
        .collect()
}

/// Smooth shading against a closed form: OPEN_FLOOR's floor made two triangles whose vertex normals all
/// lean 30 degrees (ns = (sin 30, cos 30, 0) against the true normal +y), seen from straight above. Its
/// radiance is rho / pi Le times the integral over the light of cos_s cos_y / d^2, cos_s the light's
/// direction against ns (by a 512 x 512 midpoint rule): 13% below the flat floor's. By photons that is
/// Veach's correction on their records (|wi . ns| / |wi . ng|, shading.glsl), by shadow rays the shading
/// cosine; a record without the correction gives the flat floor's value.
#[test]
fn smooth_shading_under_a_square_light_matches_its_closed_form() {
    let mut scene = Scene::parse(OPEN_FLOOR, "open-floor.toml").unwrap_or_else(|e| panic!("{e:#}"));
    let floor = scene.quads.remove(0);
    let lean = 30f32.to_radians();
    let ns = Vec3::new(lean.sin(), lean.cos(), 0.0);
    let (o, u, v) = (floor.origin, floor.edge_u, floor.edge_v);
    scene.meshes.push(ppm_vk_engine::scene::Mesh {
        name: "leaning floor".into(),
        positions: vec![o, o + u, o + u + v, o + v],
        normals: Some(vec![ns; 4]),
        uvs: None,
        indices: vec![[0, 1, 2], [0, 2, 3]],
        materials: vec![floor.material; 2],
    });
    let (le, half, rho) = (10.0f64, 0.1f64, 0.5f64);
    let ns = ns.as_dvec3();
    let n = 512;
    let cell = 2.0 * half / n as f64;
    let (mut smooth, mut flat) = (0.0, 0.0);
    for i in 0..n {
        for j in 0..n {
            let (x, z) = (-half + (i as f64 + 0.5) * cell, -half + (j as f64 + 0.5) * cell);
            let d2 = x * x + z * z + 1.0;
            let w = glam::DVec3::new(x, 1.0, z) / d2.sqrt();
            let cos_y = w.y; // at the light, and the true cosine at the floor
            smooth += w.dot(ns).max(0.0) * cos_y / d2 * cell * cell;
            flat += w.y * cos_y / d2 * cell * cell;
        }
    }
    let want = rho / std::f64::consts::PI * le * smooth;
    let flat = rho / std::f64::consts::PI * le * flat;
    println!("closed form {want:.5} (the flat floor's {flat:.5})");
    let ctx = ctx();
    for (direct, got) in under_the_square_light(&ctx, &scene) {
        println!("{direct:?}: {got:?}");
        for (c, got) in got.iter().enumerate() {
            // As the plastic floor's: by photons within 2.5% (their noise and the radius's falloff bias),
            // by shadow rays 1%; the flat floor's value is 15% above.
            let tol = if direct == DirectLight::Sample { 0.01 } else { 0.025 };
            let rel = got / want - 1.0;
            assert!(rel.abs() < tol, "{direct:?}, channel {c}: {:+.2}% off", 100.0 * rel);
        }
    }
    assert_clean(&ctx);
}

/// scenes/references/cornell-textured.xml: cornell-gold with a bitmap floor (an 8-bit sRGB PNG, bilinear,
/// repeated 3 x 2 times), a checkerboard back wall, the blue sphere a plastic whose diffuse_reflectance is
/// the bitmap (nearest, mirrored) and a small box mesh with the bitmap on its faces (OBJ texture
/// coordinates), against Mitsuba's path tracer on the same XML (textures.py made the images and the box,
/// make_reference.py the reference). 128 x 128, SPPM, 32 passes of 100k photons. The mean per channel
/// within 1% (measured: within 0.03%), and the relMSE under a bound (measured 0.0024) that the control
/// exceeds (measured 0.28): every texture replaced by a constant, its mean (the same light reflected on
/// average, not the same picture).
#[test]
fn textures_match_their_mitsuba_reference() {
    use ppm_vk_engine::scene::texture::Pattern;
    let xml = Path::new(REFERENCES).join("cornell-textured.xml");
    let defines = [("res".to_string(), "128".to_string())];
    let scene = Scene::load_with(&xml, &defines).unwrap_or_else(|e| panic!("{e:#}"));
    // The one approximation: the plastic's texture has white pixels, above what its coat lets a photon's
    // diffuse bounce keep (docs/mitsuba.md); they are lowered to the bound, 5% on a few pixels.
    assert!(
        scene.warnings.len() == 1 && scene.warnings[0].contains("pixels lowered to at most"),
        "{:?}",
        scene.warnings
    );
    assert!(scene.textures.len() >= 3 && scene.meshes.iter().any(|m| m.uvs.is_some()));
    let reference = Reference::load(&Path::new(REFERENCES).join("cornell-textured.exr")).unwrap();
    let ctx = ctx();
    let image = render(&ctx, &scene, r_settings(), 32);
    let rel_mse = compare(&image, &reference, None, true).unwrap().rel_mse;
    println!("relMSE {rel_mse:.5}");
    assert_mean_within_1_percent(&image, &reference);
    const BOUND: f64 = 0.005;
    assert!(rel_mse < BOUND, "relMSE {rel_mse}");
    let mut flat = scene.clone();
    for t in &mut flat.textures {
        let mean = match &t.pattern {
            Pattern::Bitmap { pixels, .. } => pixels.iter().sum::<Vec3>() / pixels.len() as f32,
            Pattern::Checkerboard { color0, color1 } => 0.5 * (*color0 + *color1),
        };
        t.pattern = Pattern::Checkerboard {
            color0: mean,
            color1: mean,
        };
    }
    let control = compare(&render(&ctx, &flat, r_settings(), 32), &reference, None, true)
        .unwrap()
        .rel_mse;
    println!("the textures flat: relMSE {control:.5}");
    assert!(
        control > BOUND,
        "the bound cannot tell a texture from its mean: {control}"
    );
    assert_clean(&ctx);
}

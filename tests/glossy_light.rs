//! The light rough metal reflects straight from a light (shaders/ray/glossy_light.glsl): shadow rays at
//! the rough vertices eye paths sample through, weighed against the lobe's own direction by multiple
//! importance sampling. Checked against the integral of the BRDF times the light, by quadrature here
//! (scenes/glossy-plane.xml: a rough plane under a square light), against the closed form of a point
//! light's highlight (which no sampled direction meets: before shadow rays at rough vertices it was
//! missing), and for the three ways of taking it (`GlossyLight`): the same image, the combined one with
//! the lowest error. (GPU against the CPU twin: tests/kernels.rs, `..._with_glossy_light`.)

mod common;

use common::*;
use glam::{Vec2, Vec3};
use ppm_vk_engine::{GlossyLight, RgbImage, Scene, Settings};
use ppm_vk_materials::conductor::fresnel_conductor;
use ppm_vk_materials::math::fresnel_dielectric;
use ppm_vk_materials::Microfacet;

const RES: u32 = 40;
/// The plane's complex index (scenes/glossy-plane.xml).
const ETA: Vec3 = Vec3::new(0.2, 0.9, 1.1);
const K: Vec3 = Vec3::new(3.9, 2.4, 2.2);
/// The square light: centre, half side, height (it faces -y).
const LIGHT_CENTRE: Vec3 = Vec3::new(0.0, 1.0, -1.0);
const LIGHT_HALF: f32 = 0.3;
const POINT: Vec3 = Vec3::new(0.4, 0.8, -0.3);

fn scene(alpha: f32, radiance: f32, intensity: f32) -> Scene {
    let (a, r, i) = (alpha.to_string(), radiance.to_string(), intensity.to_string());
    let res = RES.to_string();
    mitsuba_scene(
        "glossy-plane",
        &[("alpha", &a), ("radiance", &r), ("intensity", &i), ("res", &res)],
    )
}

fn settings(glossy_light: GlossyLight) -> Settings {
    Settings {
        photons_per_pass: 2_000,
        seed: 5,
        emission_samples: 16,
        light_samples: 16,
        // Every rough lobe sampled through (no glossy hit points), whatever its roughness.
        glossy_hits: None,
        glossy_light,
        ..Settings::default()
    }
}

/// The plane's surface: the scene's rough metal, or a rough plastic of black base (its coat alone: index
/// 1.5, specular_reflectance 1).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Plane {
    Metal,
    Coat,
}

/// The GGX plane's BRDF times cos_l, for unit directions towards the eye `v` and the light `l` (plane
/// normal +y), from the materials crate's distribution and Fresnel (each checked against Mitsuba's there).
fn brdf_cos(plane: Plane, alpha: f32, v: Vec3, l: Vec3) -> Vec3 {
    let mf = Microfacet::isotropic(true, alpha);
    // Local frame: z the normal.
    let local = |w: Vec3| Vec3::new(w.x, w.z, w.y);
    let (lv, ll) = (local(v), local(l));
    if lv.z <= 0.0 || ll.z <= 0.0 {
        return Vec3::ZERO;
    }
    let h = (lv + ll).normalize();
    let c = lv.dot(h).clamp(0.0, 1.0);
    let f = match plane {
        Plane::Metal => fresnel_conductor(c, ETA, K),
        Plane::Coat => Vec3::splat(fresnel_dielectric(c, 1.0 / 1.5).0),
    };
    f * (mf.d(h) * mf.g1(lv, h) * mf.g1(ll, h) / (4.0 * lv.z))
}

/// The camera ray through point `j` of pixel (px, py), as a pinhole camera of the scene's.
fn camera_ray(scene: &Scene, px: u32, py: u32, j: Vec2) -> Vec3 {
    let c = &scene.camera;
    let forward = (c.look_at - c.eye).normalize();
    let right = forward.cross(c.up).normalize();
    let up = right.cross(forward);
    let t = (c.vfov_deg.to_radians() * 0.5).tan();
    let aspect = c.width as f32 / c.height as f32;
    let sx = (2.0 * (px as f32 + j.x) / c.width as f32 - 1.0) * aspect * t;
    let sy = (1.0 - 2.0 * (py as f32 + j.y) / c.height as f32) * t;
    (forward + sx * right + sy * up).normalize()
}

/// The plane's radiance seen along `d` from the eye: the BRDF times the square light (radiance `le`,
/// by an n x n midpoint rule over its area) and the point light (intensity `i`, closed form); 0 where
/// the ray meets the light's black back or misses the plane.
fn radiance(scene: &Scene, plane: Plane, alpha: f32, le: f32, i: f32, d: Vec3, n: u32) -> Vec3 {
    let eye = scene.camera.eye;
    // The light's square at y = 1 hides the plane behind it (the eye is above it).
    let t_light = (LIGHT_CENTRE.y - eye.y) / d.y;
    let at = eye + t_light * d;
    if t_light > 0.0 && (at.x - LIGHT_CENTRE.x).abs() < LIGHT_HALF && (at.z - LIGHT_CENTRE.z).abs() < LIGHT_HALF {
        return Vec3::ZERO;
    }
    let t = -eye.y / d.y;
    let x = eye + t * d;
    if t <= 0.0 || x.x.abs() > 2.0 || x.z.abs() > 2.0 {
        return Vec3::ZERO;
    }
    let v = -d;
    let mut sum = Vec3::ZERO;
    if le > 0.0 {
        let side = 2.0 * LIGHT_HALF;
        let da = side * side / (n * n) as f32;
        for a in 0..n {
            for b in 0..n {
                let y = LIGHT_CENTRE
                    + Vec3::new(
                        side * ((a as f32 + 0.5) / n as f32 - 0.5),
                        0.0,
                        side * ((b as f32 + 0.5) / n as f32 - 0.5),
                    );
                let w = y - x;
                let d2 = w.dot(w);
                let l = w / d2.sqrt();
                let cos_y = l.y; // the light faces -y: cos between its normal and -l
                sum += brdf_cos(plane, alpha, v, l) * (le * cos_y / d2 * da);
            }
        }
    }
    if i > 0.0 {
        let w = POINT - x;
        let d2 = w.dot(w);
        sum += brdf_cos(plane, alpha, v, w / d2.sqrt()) * (i / d2);
    }
    sum
}

/// The expected image: each pixel the mean of `radiance` over s x s points of it.
fn expected(scene: &Scene, plane: Plane, alpha: f32, le: f32, i: f32, s: u32, n: u32) -> Vec<Vec3> {
    let mut out = Vec::new();
    for py in 0..RES {
        for px in 0..RES {
            let mut p = Vec3::ZERO;
            for a in 0..s {
                for b in 0..s {
                    let j = Vec2::new((a as f32 + 0.5) / s as f32, (b as f32 + 0.5) / s as f32);
                    p += radiance(scene, plane, alpha, le, i, camera_ray(scene, px, py, j), n);
                }
            }
            out.push(p / (s * s) as f32);
        }
    }
    out
}

fn sum(pixels: impl Iterator<Item = Vec3>) -> [f64; 3] {
    pixels.fold([0f64; 3], |s, p| {
        [s[0] + p.x as f64, s[1] + p.y as f64, s[2] + p.z as f64]
    })
}

/// Mean over pixels of the squared error over the squared expected value (plus 0.01, as docs/accuracy.md's
/// relMSE), on the pixels where the expected value is not 0.
fn rel_mse(image: &RgbImage, want: &[Vec3]) -> f64 {
    let mut total = 0.0;
    let mut n = 0;
    for (p, w) in image.pixels.iter().zip(want) {
        for c in 0..3 {
            let (g, e) = (p[c] as f64, w[c] as f64);
            if e > 0.0 {
                total += (g - e).powi(2) / (e * e + 0.01);
                n += 1;
            }
        }
    }
    total / n as f64
}

/// The square light's glossy reflection, both strategies combined and each alone, against quadrature:
/// on a sharp lobe (alpha 0.05: the lobe's direction meets the light often, a point on the light seldom
/// lies in the lobe) and a broad one (alpha 0.3: the reverse). The image's sum within 1.5% of the
/// integral each way, and the combined one's error the lowest or within 15% of the lowest.
#[test]
fn glossy_reflection_of_a_square_light_matches_quadrature() {
    let ctx = ctx();
    for (alpha, passes) in [(0.05f32, 40u32), (0.3, 40)] {
        let s = scene(alpha, 5.0, 0.0);
        let want = expected(&s, Plane::Metal, alpha, 5.0, 0.0, 4, 48);
        let total = sum(want.iter().copied());
        let mut errors = Vec::new();
        for mode in [GlossyLight::Mis, GlossyLight::Bsdf, GlossyLight::Lights] {
            let image = render(&ctx, &s, settings(mode), passes);
            let got = sum(image.pixels.iter().map(|p| Vec3::from(*p)));
            let err = rel_mse(&image, &want);
            let ratio = [0, 1, 2].map(|c| got[c] / total[c]);
            println!("alpha {alpha}, {mode:?}: sum / quadrature {ratio:.4?}, relMSE {err:.5}");
            errors.push((err, ratio));
        }
        for (mode, (_, ratio)) in ["MIS", "BSDF", "lights"].iter().zip(&errors) {
            for (c, r) in ratio.iter().enumerate() {
                assert!((r - 1.0).abs() < 0.015, "alpha {alpha}, {mode}, channel {c}: {r}");
            }
        }
        let errors: Vec<f64> = errors.iter().map(|e| e.0).collect();
        let least = errors.iter().copied().fold(f64::MAX, f64::min);
        assert!(
            errors[0] <= 1.15 * least,
            "alpha {alpha}: MIS error {} against {errors:?}",
            errors[0]
        );
    }
    assert_clean(&ctx);
}

/// A point light over rough metal: its highlight, f I cos / d^2 per point, which only a shadow ray can
/// find. Every mode takes it by shadow rays; each within 1% of the closed form.
#[test]
fn point_light_highlight_on_rough_metal_matches_its_closed_form() {
    let ctx = ctx();
    let alpha = 0.1f32;
    let s = scene(alpha, 0.0, 2.0);
    let want = expected(&s, Plane::Metal, alpha, 0.0, 2.0, 4, 1);
    let total = sum(want.iter().copied());
    for mode in [GlossyLight::Mis, GlossyLight::Bsdf, GlossyLight::Lights] {
        let image = render(&ctx, &s, settings(mode), 10);
        let got = sum(image.pixels.iter().map(|p| Vec3::from(*p)));
        let ratio = [0, 1, 2].map(|c| got[c] / total[c]);
        println!("{mode:?}: sum / closed form {ratio:.4?}");
        for (c, r) in ratio.iter().enumerate() {
            assert!((r - 1.0).abs() < 0.01, "{mode:?}, channel {c}: {r}");
        }
    }
    assert_clean(&ctx);
}

/// A rough plastic's coat is a rough vertex too: the plane made a rough plastic of black base (so its coat
/// alone reflects, index 1.5, GGX 0.1) under both lights, in each mode, against quadrature and the point
/// light's closed form (the coat's dielectric Fresnel term in place of the metal's), within 1.5%.
#[test]
fn a_rough_plastic_coat_reflects_both_lights_as_quadrature() {
    use ppm_vk_engine::scene::{Microfacet, Surface};
    let ctx = ctx();
    let alpha = 0.1f32;
    let mut s = scene(alpha, 5.0, 2.0);
    let plane = s
        .quads
        .iter()
        .map(|q| q.material)
        .find(|&m| matches!(s.materials[m as usize].surface, Surface::RoughConductor { .. }));
    let plane = plane.expect("the rough plane") as usize;
    s.materials[plane].surface = Surface::Plastic {
        diffuse: Vec3::ZERO,
        specular: Vec3::ONE,
        ior: 1.5,
        nonlinear: false,
        rough: Some(Microfacet::isotropic(true, alpha)),
    };
    s.validate().unwrap_or_else(|e| panic!("{e:#}"));
    let want = expected(&s, Plane::Coat, alpha, 5.0, 2.0, 4, 48);
    let total = sum(want.iter().copied());
    for mode in [GlossyLight::Mis, GlossyLight::Bsdf, GlossyLight::Lights] {
        let image = render(&ctx, &s, settings(mode), 20);
        let got = sum(image.pixels.iter().map(|p| Vec3::from(*p)));
        let ratio = [0, 1, 2].map(|c| got[c] / total[c]);
        println!(
            "coat, {mode:?}: sum / quadrature {ratio:.4?}, relMSE {:.5}",
            rel_mse(&image, &want)
        );
        for (c, r) in ratio.iter().enumerate() {
            assert!((r - 1.0).abs() < 0.015, "coat, {mode:?}, channel {c}: {r}");
        }
    }
    assert_clean(&ctx);
}

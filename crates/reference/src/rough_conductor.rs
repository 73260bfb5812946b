//! CPU twin of shaders/materials/rough_conductor.glsl: Mitsuba's `roughconductor`, smooth-conductor facets
//! (conductor.rs) oriented by a microfacet distribution (microfacet.rs; the math of both, its density and
//! its bound are ppm_vk_materials'). f(wi, wo) = F(wi.h) D(h) G1(wi, h)
//! G1(wo, h) / (4 cos_i cos_o) times specular_reflectance, h the half vector; sampled by the visible
//! normals, whose weight f cos_o / pdf is F(wi.h) G1(wo, h) specular_reflectance. Checked against Mitsuba's
//! own roughconductor in the tests below (values, densities, directional albedo), and its sampler against
//! its density by a chi-square test.

use glam::{Vec2, Vec3};
use ppm_vk_kernels::layout::{Material, SURFACE_ROUGH_CONDUCTOR};

use ppm_vk_materials::conductor::fresnel_conductor;
use ppm_vk_materials::math::{frame, onb, reflect, to_local, v3};
use ppm_vk_materials::rough_conductor::bound;
use ppm_vk_materials::Microfacet;

use super::microfacet;
use super::trace::offset_ray;
use ppm_vk_engine::lower::GpuScene;

/// The BSDF times cos_o, in the local frame (wi, wo pointing away from the surface).
pub fn eval(m: &Material, mf: &Microfacet, wi: Vec3, wo: Vec3) -> Vec3 {
    if wi.z <= 0.0 || wo.z <= 0.0 {
        return Vec3::ZERO;
    }
    let h = (wi + wo).normalize();
    let f = v3(m.color) * fresnel_conductor(wi.dot(h).clamp(0.0, 1.0), v3(m.lobe_a), v3(m.lobe_b));
    f * (mf.d(h) * mf.g1(wi, h) * mf.g1(wo, h) / (4.0 * wi.z))
}

/// A direction wo and its weight f cos_o / pdf, or None where the reflection goes below the surface.
pub fn sample(m: &Material, mf: &Microfacet, wi: Vec3, u: Vec2) -> Option<(Vec3, Vec3)> {
    if wi.z <= 0.0 {
        return None;
    }
    let h = mf.sample_visible(wi, u);
    let wo = reflect(-wi, h);
    if wo.z <= 0.0 {
        return None;
    }
    let f = v3(m.color) * fresnel_conductor(wi.dot(h), v3(m.lobe_a), v3(m.lobe_b));
    Some((wo, f * mf.g1(wo, h)))
}

/// `rough_conductor_terms`: D G1(wi) G1(wo) / cos_i and F per channel, for unit wi, wo leaving the surface
/// of unit normal n (world space); 0 where either is below it.
pub fn terms(m: &Material, wi: Vec3, wo: Vec3, n: Vec3) -> (f32, Vec3) {
    let (t, b) = onb(n);
    let (li, lo) = (to_local(wi, t, b, n), to_local(wo, t, b, n));
    if li.z <= 0.0 || lo.z <= 0.0 {
        return (0.0, Vec3::ZERO);
    }
    let mf = microfacet::of(m);
    let h = (li + lo).normalize();
    let f = fresnel_conductor(li.dot(h).clamp(0.0, 1.0), v3(m.lobe_a), v3(m.lobe_b));
    (mf.d(h) * mf.g1(li, h) * mf.g1(lo, h) / li.z, f)
}

/// `rough_conductor_hit_weight`: a glossy hit point's weight, throughput times ks times the bound over 4
/// cos_o.
pub fn hit_weight(m: &Material, thr: Vec3, cos_o: f32) -> Vec3 {
    thr * v3(m.color) * (bound(&microfacet::of(m)) / (4.0 * cos_o))
}

/// `rough_conductor_ratio`: what a photon arriving along -wi gives a glossy hit point seen from wo, per
/// unit flux: f(wi, wo) over the hit point's weight per unit throughput, at most 1 per channel.
pub fn ratio(m: &Material, wi: Vec3, wo: Vec3, n: Vec3) -> Vec3 {
    let (s, f) = terms(m, wi, wo, n);
    (f * (s / bound(&microfacet::of(m)))).min(Vec3::ONE)
}

/// rough_conductor.glsl's `glossy_hit`: an isotropic rough conductor of roughness at least
/// `glossy_alpha`, its alpha not a texture.
pub fn glossy_hit(g: &GpuScene, m: &Material) -> bool {
    m.surface == SURFACE_ROUGH_CONDUCTOR
        && m.alpha_u >= g.params.glossy_alpha
        && m.alpha_u == m.alpha_v
        && m.alpha_texture == 0
}

/// common/lobe_bounce.glsl, a rough conductor: the new origin, direction and weight of a path
/// arriving along `d` at `pos` (`nf` facing it); a zero weight ends the path.
/// One bounce at `pos` (common/lobe_bounce.glsl); `dpdu` the tangent (frame).
pub fn bounce(g: &GpuScene, m: &Material, pos: Vec3, nf: Vec3, dpdu: Vec3, u: Vec2, d: Vec3) -> (Vec3, Vec3, Vec3) {
    let (t, b) = frame(nf, dpdu);
    let wi = -to_local(d, t, b, nf);
    match sample(m, &microfacet::of(m), wi, u) {
        Some((wo, w)) => (offset_ray(g, pos, nf), (wo.x * t + wo.y * b + wo.z * nf).normalize(), w),
        None => (pos, d, Vec3::ZERO),
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use ppm_vk_kernels::layout::{MICROFACET_BECKMANN, MICROFACET_GGX};
    use ppm_vk_materials::conductor::named;
    use ppm_vk_materials::rough_conductor::pdf;
    use ppm_vk_materials::testing::{chi_square, dir, distributions, hemisphere, json_rgb as rgb, v};

    /// A case of rough-bsdfs.json as the material the kernels read (isotropic or not: the twin takes
    /// both).
    pub(crate) fn material(bsdf: &serde_json::Value) -> Material {
        let num = |k: &str| bsdf.get(k).map(|v| v.as_f64().unwrap() as f32);
        let alpha = num("alpha").unwrap_or(0.1);
        let (eta, k) = match bsdf.get("material") {
            Some(name) => named(name.as_str().unwrap()).unwrap(),
            None => match (bsdf.get("eta"), bsdf.get("k")) {
                (Some(e), Some(k)) => (rgb(e), rgb(k)),
                _ => named("none").unwrap(),
            },
        };
        Material {
            color: bsdf.get("specular_reflectance").map_or(Vec3::ONE, rgb).to_array(),
            lobe_a: eta.to_array(),
            lobe_b: k.to_array(),
            alpha_u: num("alpha_u").unwrap_or(alpha),
            alpha_v: num("alpha_v").unwrap_or(alpha),
            distribution: match bsdf.get("distribution").and_then(|d| d.as_str()) {
                Some("ggx") => MICROFACET_GGX,
                _ => MICROFACET_BECKMANN,
            },
            ..Default::default()
        }
    }

    fn json() -> serde_json::Value {
        let text = include_str!("../../../scenes/references/rough-bsdfs.json");
        serde_json::from_str(text).unwrap()
    }

    /// Mitsuba's roughconductor in 6 cases (both distributions, anisotropic ones, named metals and
    /// given eta, k): the BSDF's value and density at 25-26 outgoing directions for each of 6 incident
    /// ones, and the directional albedo (the mean of 2^20 of Mitsuba's sampled weights) against ours,
    /// integrated here by quadrature of `eval` (independent of our sampler).
    #[test]
    fn rough_conductor_matches_mitsubas() {
        let (mut worst_value, mut worst_pdf, mut worst_albedo) = (0f32, 0f32, 0f64);
        let mut checked = 0;
        for case in json()["roughconductor"].as_array().unwrap() {
            let bsdf = &case["bsdf"];
            let m = material(bsdf);
            let mf = microfacet::of(&m);
            for s in case["samples"].as_array().unwrap() {
                let wi = v(&s["wi"]);
                for e in s["eval"].as_array().unwrap() {
                    let wo = v(&e["wo"]);
                    let want = rgb(&e["value"]);
                    let got = eval(&m, &mf, wi, wo);
                    let err = (got - want).abs().max_element() / want.max_element().max(1e-3);
                    worst_value = worst_value.max(err);
                    assert!(err < 2e-3, "{bsdf} wi {wi} wo {wo}: {got} against Mitsuba's {want}");
                    let want = e["pdf"].as_f64().unwrap() as f32;
                    let got = pdf(&mf, wi, wo);
                    let err = (got - want).abs() / want.max(1e-3);
                    worst_pdf = worst_pdf.max(err);
                    assert!(err < 2e-3, "{bsdf} wi {wi} wo {wo}: pdf {got} against Mitsuba's {want}");
                    checked += 1;
                }
                let n = if mf.alpha.min(mf.alpha_v) < 0.1 { 1500 } else { 500 };
                let ours = [0, 1, 2].map(|c| hemisphere(n, |wo| eval(&m, &mf, wi, wo)[c] as f64));
                let want = rgb(&s["albedo"]);
                let se = rgb(&s["albedo_stderr"]);
                for c in 0..3 {
                    let diff = (ours[c] - want[c] as f64).abs();
                    worst_albedo = worst_albedo.max(diff);
                    assert!(
                        diff < 4.0 * se[c] as f64 + 2e-3,
                        "{bsdf} at wi {wi}: albedo {ours:?} against Mitsuba's {want} (stderr {se})"
                    );
                }
            }
        }
        assert!(checked > 100, "only {checked} values checked");
        println!(
            "{checked} values: largest relative differences value {worst_value:.2e}, pdf {worst_pdf:.2e}; \
             albedo within {worst_albedo:.2e}"
        );
    }

    /// The sampler against its density (chi-square), and the weight it returns against eval / pdf at the
    /// sampled direction, which must agree: that equality is what makes the sampled bounce unbiased.
    #[test]
    fn sampling_matches_eval_and_pdf() {
        let m0 = Material {
            color: [0.9, 0.8, 0.7],
            lobe_a: [0.2, 0.9, 1.5],
            lobe_b: [3.9, 2.4, 1.8],
            ..Default::default()
        };
        for mf in distributions() {
            let m = Material {
                alpha_u: mf.alpha,
                alpha_v: mf.alpha_v,
                distribution: if mf.ggx { MICROFACET_GGX } else { MICROFACET_BECKMANN },
                ..m0
            };
            for c in [0.9, 0.4, 0.1] {
                let wi = dir(c, 0.3);
                let label = format!("{mf:?} at cos {c}");
                let mut worst = 0f32;
                let (stat, dof) = chi_square(
                    &label,
                    300_000,
                    false,
                    |u| {
                        let (wo, w) = sample(&m, &mf, wi, u)?;
                        let p = pdf(&mf, wi, wo);
                        let want = eval(&m, &mf, wi, wo) / p;
                        worst = worst.max(((w - want).abs() / want.max_element()).max_element());
                        Some(wo)
                    },
                    |wo| pdf(&mf, wi, wo) as f64,
                );
                assert!(worst < 1e-3, "{label}: weight differs from eval / pdf by {worst}");
                println!("{label}: chi-square {stat:.1} on {dof}; weight within {worst:.1e} of eval / pdf");
            }
        }
    }

    /// The glossy hit point's bound: f(wi, wo) 4 cos_o over ks times the bound is at most 1 (the kernel's
    /// min(ratio, 1) is then only a guard against rounding), over both distributions, alpha from 1e-3 to
    /// 3, and directions down to grazing, where G1(wi) / cos_i takes its supremum (printed: how close to 1
    /// the ratio comes, i.e. how much fixed-point range the bound leaves unused). Its first version took
    /// D's peak at the normal, which rough Beckmann (alpha > 0.71) and GGX (alpha > 1) exceed: this test
    /// found ratios of 1.13 at Beckmann alpha 1.
    #[test]
    fn glossy_ratio_is_at_most_one() {
        let n = Vec3::Z;
        for ggx in [false, true] {
            for alpha in [1e-3, 0.01, 0.05, 0.2, 0.6, 1.0, 1.5, 2.0, 3.0] {
                let m = Material {
                    color: [1.0; 3],
                    lobe_a: [0.0; 3],
                    lobe_b: [1.0; 3], // eta 0, k 1: F = 1 at every angle
                    alpha_u: alpha,
                    alpha_v: alpha,
                    distribution: if ggx { MICROFACET_GGX } else { MICROFACET_BECKMANN },
                    ..Default::default()
                };
                let mut most = 0f32;
                for i in 0..400 {
                    let ci = 1.0 - (i as f32 / 400.0).powi(2) * (1.0 - 1e-6);
                    for j in 0..100 {
                        let co = (j as f32 + 0.5) / 100.0;
                        // wo at the mirror azimuth, where the half vector comes closest to the normal.
                        let (wi, wo) = (dir(ci, 0.0), dir(co, std::f32::consts::PI));
                        let (s, f) = terms(&m, wi, wo, n);
                        let r = (f * (s / bound(&microfacet::of(&m)))).max_element();
                        most = most.max(r);
                    }
                }
                assert!(most <= 1.0 + 1e-5, "ggx {ggx} alpha {alpha}: ratio {most}");
                println!("ggx {ggx} alpha {alpha}: largest ratio {most:.4}");
            }
        }
    }

    /// Reciprocity: f(wi, wo) = f(wo, wi), f = eval / cos_o.
    #[test]
    fn reciprocal() {
        let m = Material {
            color: [1.0; 3],
            lobe_a: [0.2, 0.9, 1.5],
            lobe_b: [3.9, 2.4, 1.8],
            alpha_u: 0.3,
            alpha_v: 0.3,
            distribution: MICROFACET_GGX,
            ..Default::default()
        };
        let mf = microfacet::of(&m);
        for (a, b) in [(0.9, 0.2), (0.5, 0.7), (0.1, 0.95)] {
            let (wi, wo) = (dir(a, 0.4), dir(b, 2.9));
            let f1 = eval(&m, &mf, wi, wo) / wo.z;
            let f2 = eval(&m, &mf, wo, wi) / wi.z;
            assert!(
                ((f1 - f2).abs() / f1.max_element()).max_element() < 1e-5,
                "{f1} vs {f2}"
            );
        }
    }
}

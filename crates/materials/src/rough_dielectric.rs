//! Mitsuba's `roughdielectric` (Walter et al. 2007; shaders/materials/rough_dielectric.glsl),
//! smooth-dielectric facets oriented by a microfacet distribution (microfacet.rs). Sampled by the visible
//! normals, then reflection with the facet's Fresnel probability or refraction; the weight is G1(wo, h) on
//! either branch. Radiance crossing the interface is not scaled by 1 / eta^2 (as for smooth glass, the
//! factors of a path's entry and exit cancel): Mitsuba's radiance-mode values below carry it, and the
//! tests account for it. Checked against Mitsuba's own roughdielectric in the tests below (values,
//! densities, albedos per lobe), and its sampler against its density by a chi-square test. A bounce at a
//! hit is the CPU twin's (the engine's reference/rough_dielectric.rs).

use glam::{Vec2, Vec3};

use crate::math::{fresnel_dielectric, reflect};
use crate::Microfacet;

/// The facet's Fresnel reflectance for wi at cosine `c` = wi.h to a facet normal h on the outside's side
/// (c < 0: wi inside), `ior` inside over outside.
fn fresnel(c: f32, ior: f32) -> f32 {
    let eta = if c > 0.0 { 1.0 / ior } else { ior }; // incident over transmitted
    fresnel_dielectric(c.abs().min(1.0), eta).0
}

/// The half vector of (wi, wo) on the outside's side, and eta (transmitted over incident index; 1 for a
/// reflection), in Mitsuba's frame: z the outside normal, wi and wo on either side.
fn half(ior: f32, wi: Vec3, wo: Vec3) -> (Vec3, f32, bool) {
    let reflect = wi.z * wo.z > 0.0;
    let eta = if wi.z > 0.0 { ior } else { 1.0 / ior };
    let h = (wi + wo * if reflect { 1.0 } else { eta }).normalize();
    (h * h.z.signum(), eta, reflect)
}

/// The BSDF times |cos_o| in radiance mode, as Mitsuba's eval returns it (Mitsuba's frame).
pub fn eval(mf: &Microfacet, ior: f32, wi: Vec3, wo: Vec3) -> f32 {
    if wi.z == 0.0 || wo.z == 0.0 {
        return 0.0;
    }
    let (h, eta, reflect) = half(ior, wi, wo);
    let g = mf.g1(wi, h) * mf.g1(wo, h);
    let (d, f) = (mf.d(h), fresnel(wi.dot(h), ior));
    if reflect {
        f * d * g / (4.0 * wi.z.abs())
    } else {
        let den = wi.dot(h) + eta * wo.dot(h);
        ((1.0 - f) * d * g * wi.dot(h) * wo.dot(h) / (wi.z * den * den)).abs()
    }
}

/// The density of the sampled wo (Mitsuba's frame): the visible normals' density seen from wi's side,
/// times the branch's probability and the Jacobian of h to wo. (Our sampler turns the frame over by z
/// alone, Mitsuba by the whole vector: D and G1 are even in (x, y), so the densities are the same.)
pub fn pdf(mf: &Microfacet, ior: f32, wi: Vec3, wo: Vec3) -> f32 {
    if wi.z == 0.0 || wo.z == 0.0 {
        return 0.0;
    }
    let (h, eta, reflect) = half(ior, wi, wo);
    // No facet sends wi to wo unless each sees it from its own side (what G1 checks in eval).
    if wi.dot(h) * wi.z <= 0.0 || wo.dot(h) * wo.z <= 0.0 {
        return 0.0;
    }
    let f = fresnel(wi.dot(h), ior);
    let (jac, branch) = if reflect {
        (1.0 / (4.0 * wo.dot(h)), f)
    } else {
        let den = wi.dot(h) + eta * wo.dot(h);
        (eta * eta * wo.dot(h) / (den * den), 1.0 - f)
    };
    // Seen from wi's side: h faces the outside, so from inside the whole of wi turns over.
    (mf.visible_pdf(wi * wi.z.signum(), h) * branch * jac).abs()
}

/// Our sampler, in the frame whose z faces wi (wi.z > 0): `front` if wi is outside. The new direction and
/// the weight G1(wo, h) (without the 1 / eta^2 of radiance), or None where it leaves on the wrong side.
pub fn sample(mf: &Microfacet, ior: f32, front: bool, wi: Vec3, u: f32, u2: Vec2) -> Option<(Vec3, f32)> {
    if wi.z <= 0.0 {
        return None;
    }
    let h = mf.sample_visible(wi, u2);
    let eta = if front { 1.0 / ior } else { ior };
    let cos_i = wi.dot(h);
    let (f, cos_t) = fresnel_dielectric(cos_i, eta);
    let wo = if u < f {
        let wo = reflect(-wi, h);
        if wo.z <= 0.0 {
            return None;
        }
        wo
    } else {
        let wo = (-eta * wi + (eta * cos_i - cos_t) * h).normalize();
        if wo.z >= 0.0 {
            return None;
        }
        wo
    };
    Some((wo, mf.g1(wo, h)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::{chi_square, dir, distributions, hemisphere, json_rgb as rgb, v};

    fn flip(w: Vec3) -> Vec3 {
        Vec3::new(w.x, w.y, -w.z)
    }

    /// Our sampler seen in Mitsuba's frame: wi on either side.
    fn sample_any(mf: &Microfacet, ior: f32, wi: Vec3, u: f32, u2: Vec2) -> Option<(Vec3, f32)> {
        let front = wi.z > 0.0;
        let local = if front { wi } else { flip(wi) };
        let (wo, w) = sample(mf, ior, front, local, u, u2)?;
        Some((if front { wo } else { flip(wo) }, w))
    }

    /// Mitsuba's radiance-mode weight of a sample: ours, over eta^2 where it refracts.
    fn radiance_weight(ior: f32, wi: Vec3, wo: Vec3, w: f32) -> f32 {
        match wi.z * wo.z > 0.0 {
            true => w,
            false => {
                let eta = if wi.z > 0.0 { ior } else { 1.0 / ior };
                w / (eta * eta)
            }
        }
    }

    #[test]
    fn rough_dielectric_matches_mitsubas() {
        let text = include_str!("../../../scenes/references/rough-bsdfs.json");
        let json: serde_json::Value = serde_json::from_str(text).unwrap();
        let (mut worst_value, mut worst_pdf, mut worst_albedo) = (0f32, 0f32, 0f64);
        let mut checked = 0;
        for case in json["roughdielectric"].as_array().unwrap() {
            let bsdf = &case["bsdf"];
            let num = |k: &str| bsdf.get(k).map(|v| v.as_f64().unwrap() as f32);
            let alpha = num("alpha").unwrap_or(0.1);
            let mf = Microfacet {
                ggx: bsdf.get("distribution").and_then(|d| d.as_str()) == Some("ggx"),
                alpha: num("alpha_u").unwrap_or(alpha),
                alpha_v: num("alpha_v").unwrap_or(alpha),
            };
            let ior = num("int_ior").unwrap_or(1.5046) / num("ext_ior").unwrap_or(1.000277);
            let ks = bsdf.get("specular_reflectance").map_or(Vec3::ONE, rgb);
            let kt = bsdf.get("specular_transmittance").map_or(Vec3::ONE, rgb);
            for s in case["samples"].as_array().unwrap() {
                let wi = v(&s["wi"]);
                for e in s["eval"].as_array().unwrap() {
                    let wo = v(&e["wo"]);
                    let tint = if wi.z * wo.z > 0.0 { ks } else { kt };
                    let want = rgb(&e["value"]);
                    let got = tint * eval(&mf, ior, wi, wo);
                    let err = (got - want).abs().max_element() / want.max_element().max(1e-3);
                    worst_value = worst_value.max(err);
                    assert!(err < 2e-3, "{bsdf} wi {wi} wo {wo}: {got} against Mitsuba's {want}");
                    let want = e["pdf"].as_f64().unwrap() as f32;
                    let got = pdf(&mf, ior, wi, wo);
                    let err = (got - want).abs() / want.max(1e-3);
                    worst_pdf = worst_pdf.max(err);
                    assert!(err < 2e-3, "{bsdf} wi {wi} wo {wo}: pdf {got} against Mitsuba's {want}");
                    checked += 1;
                }
                // Each lobe's albedo by quadrature of eval over its hemisphere.
                let n = 700;
                let r = hemisphere(n, |w| eval(&mf, ior, wi, if wi.z > 0.0 { w } else { flip(w) }) as f64);
                let t = hemisphere(n, |w| eval(&mf, ior, wi, if wi.z > 0.0 { flip(w) } else { w }) as f64);
                for (key, ours, tint) in [("reflect_albedo", r, ks), ("transmit_albedo", t, kt)] {
                    let want = rgb(&s[key]);
                    let se = rgb(&s[&format!("{key}_stderr")]);
                    for c in 0..3 {
                        let o = ours * tint[c] as f64;
                        let diff = (o - want[c] as f64).abs();
                        worst_albedo = worst_albedo.max(diff);
                        assert!(
                            diff < 4.0 * se[c] as f64 + 2e-3,
                            "{bsdf} at wi {wi}: {key} {o} against Mitsuba's {want} (stderr {se})"
                        );
                    }
                }
            }
        }
        assert!(checked > 100, "only {checked} values checked");
        println!(
            "{checked} values: largest relative differences value {worst_value:.2e}, pdf {worst_pdf:.2e}; \
             albedo within {worst_albedo:.2e}"
        );
    }

    /// Both lobes' sampler against the density (chi-square over the whole sphere), and its weight
    /// against eval / pdf.
    #[test]
    fn sampling_matches_eval_and_pdf() {
        for mf in distributions() {
            for (ior, c) in [(1.5, 0.9), (1.5, 0.3), (1.5, -0.8), (1.5, -0.5), (1.33, -0.2)] {
                let wi = dir(c, 0.3);
                let label = format!("{mf:?}, ior {ior}, at cos {c}");
                let mut worst = 0f32;
                let mut rng = crate::rng::Rng::new(7, 11);
                let (stat, dof) = chi_square(
                    &label,
                    300_000,
                    true,
                    |u2| {
                        let (wo, w) = sample_any(&mf, ior, wi, rng.float(), u2)?;
                        let p = pdf(&mf, ior, wi, wo);
                        if p > 1e-6 {
                            let want = eval(&mf, ior, wi, wo) / p;
                            worst = worst.max((radiance_weight(ior, wi, wo, w) - want).abs() / want.max(1e-3));
                        }
                        Some(wo)
                    },
                    |wo| pdf(&mf, ior, wi, wo) as f64,
                );
                assert!(worst < 2e-3, "{label}: weight differs from eval / pdf by {worst}");
                println!("{label}: chi-square {stat:.1} on {dof}; weight within {worst:.1e} of eval / pdf");
            }
        }
    }
}

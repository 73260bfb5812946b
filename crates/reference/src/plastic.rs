//! CPU twin of shaders/materials/plastic.glsl: Mitsuba's `plastic`, a diffuse base under a smooth dielectric
//! coat. Its BSDF is a specular lobe, `specular_reflectance` times the coat's Fresnel term F(cos_i), and a
//! diffuse lobe `D (1 - F(cos_i)) (1 - F(cos_o)) / pi` whose factor D = diffuse_reflectance / (1 - fdr_int)
//! / eta^2 (`nonlinear`: diffuse_reflectance / (1 - diffuse_reflectance fdr_int) / eta^2) counts the light
//! the coat reflects back into the base (fdr_int, the coat's diffuse reflectance from inside). The diffuse
//! lobe is a product of a term of the incoming and one of the outgoing direction, which is what lets the
//! photon estimate carry it without evaluating a BSDF per photon: a photon leaves its record with its flux
//! times (1 - F(cos_i)), and the hit point weighs what it gathers by D (1 - F(cos_o)) / pi. D and the
//! photons' bound are the host's (ppm_vk_materials::plastic). Checked against Mitsuba's own plastic in the tests
//! below.

use glam::{Vec2, Vec3};
use ppm_vk_kernels::layout::Material;
use ppm_vk_materials::math::{cosine_direction, fresnel_dielectric, onb, reflect, to_local, v3};
use ppm_vk_materials::plastic::coat_fresnel;

use super::microfacet;
use super::rng::Rng;
use super::trace::offset_ray;
use ppm_vk_engine::lower::GpuScene;

/// plastic.glsl's `plastic_lobes`: seen from (or lit from) incidence `cos_o`, the specular lobe's weight
/// specular_reflectance F(cos_o) and the diffuse lobe's D (1 - F(cos_o)), whose f_r is that over pi times
/// (1 - F) of the other direction.
pub fn lobes(m: &Material, cos_o: f32) -> (Vec3, Vec3) {
    let f = coat_fresnel(cos_o, m.ior);
    (v3(m.lobe_a) * f, v3(m.color) * (1.0 - f))
}

/// plastic.glsl's `coat_transmittance`: 1 - F (table 0) or the rough coat's table in the texture texels.
pub fn coat_transmittance(g: &GpuScene, table: u32, cos_i: f32, ior: f32) -> f32 {
    if table == 0 {
        return 1.0 - coat_fresnel(cos_i, ior);
    }
    let x = cos_i.clamp(0.0, 1.0) * 63.0;
    let k = (x as u32).min(62);
    let a = x - k as f32;
    let value = |k: u32| f32::from_bits(g.textures[(table - 1 + k / 4) as usize][(k % 4) as usize]);
    let (t0, t1) = (value(k), value(k + 1));
    t0 + (t1 - t0) * a
}

/// plastic.glsl's `plastic_lobes`: for a path arriving along `d` (`nf` facing it), the coat's reflected
/// direction and weight (a rough coat draws its normal from `rng`) and the diffuse lobe's D t(cos_o).
pub fn plastic_lobes(g: &GpuScene, m: &Material, nf: Vec3, rng: &mut Rng, d: Vec3) -> (Vec3, Vec3, Vec3) {
    let cos_o = -d.dot(nf);
    let diff = v3(m.color) * coat_transmittance(g, m.table, cos_o, m.ior);
    if m.table == 0 {
        return (reflect(d, nf), v3(m.lobe_a) * coat_fresnel(cos_o, m.ior), diff);
    }
    let u = Vec2::new(rng.float(), rng.float());
    let (t, b) = onb(nf);
    let wi = -to_local(d, t, b, nf);
    let mf = microfacet::of(m);
    let h = mf.sample_visible(wi, u);
    let wo = reflect(-wi, h);
    let spec = match wi.z > 0.0 && wo.z > 0.0 {
        true => v3(m.lobe_a) * (coat_fresnel(wi.dot(h), m.ior) * mf.g1(wo, h)),
        false => Vec3::ZERO,
    };
    ((wo.x * t + wo.y * b + wo.z * nf).normalize(), spec, diff)
}

/// common/lobe_bounce.glsl's bounce off a plastic (its plastic branch): the photon's new (origin, direction, weight) off plastic
/// `m`, or None where it is absorbed. A rough coat draws two more numbers from `rng`.
pub fn scatter(
    g: &GpuScene,
    m: &Material,
    pos: Vec3,
    nf: Vec3,
    [u, u1, u2]: [f32; 3],
    rng: &mut Rng,
    d: Vec3,
) -> Option<(Vec3, Vec3, Vec3)> {
    let ks = v3(m.lobe_a);
    let bound = m.lobe_b[0];
    if m.table == 0 {
        let fi = coat_fresnel(-d.dot(nf), m.ior);
        let ps = ks.max_element() * fi;
        let (d, w) = if u < ps {
            (reflect(d, nf), ks / ks.max_element())
        } else if u < ps + (1.0 - fi) * bound {
            let d = cosine_direction(nf, u1, u2);
            (d, v3(m.color) * ((1.0 - coat_fresnel(d.dot(nf), m.ior)) / bound))
        } else {
            return None;
        };
        return Some((offset_ray(g, pos, nf), d, w));
    }
    let v = Vec2::new(rng.float(), rng.float());
    let (t, b) = onb(nf);
    let wi = -to_local(d, t, b, nf);
    if wi.z <= 0.0 {
        return None;
    }
    let mf = microfacet::of(m);
    let h = mf.sample_visible(wi, v);
    let cos_h = wi.dot(h);
    let (fi, cos_t) = fresnel_dielectric(cos_h, 1.0 / m.ior);
    let ps = ks.max_element() * fi;
    let (d, w, g1) = if u < ps {
        let wo = reflect(-wi, h);
        let g1 = if wo.z > 0.0 { mf.g1(wo, h) } else { 0.0 };
        (
            (wo.x * t + wo.y * b + wo.z * nf).normalize(),
            ks / ks.max_element() * g1,
            g1,
        )
    } else if u < ps + (1.0 - fi) * bound {
        let e = 1.0 / m.ior;
        let wt = (-e * wi + (e * cos_h - cos_t) * h).normalize();
        let g1 = if wt.z < 0.0 { mf.g1(wt, h) } else { 0.0 };
        let d = cosine_direction(nf, u1, u2);
        let w = v3(m.color) * (coat_transmittance(g, m.table, d.dot(nf), m.ior) / bound * g1);
        (d, w, g1)
    } else {
        return None;
    };
    (g1 > 0.0).then(|| (offset_ray(g, pos, nf), d, w))
}

#[cfg(test)]
mod tests {
    use super::*;
    use ppm_vk_materials::math::PI;
    use ppm_vk_materials::plastic::{coat, diffuse_bound, diffuse_factor};

    fn json() -> serde_json::Value {
        let text = include_str!("../../../scenes/references/coated-bsdfs.json");
        serde_json::from_str(text).unwrap()
    }

    use ppm_vk_materials::testing::json_rgb as rgb;

    /// A case of coated-bsdfs.json as the material the kernels read.
    fn material(case: &serde_json::Value) -> (Material, Vec3, f32, bool) {
        let diffuse = case.get("diffuse_reflectance").map_or(Vec3::splat(0.5), rgb);
        let specular = case.get("specular_reflectance").map_or(Vec3::ONE, rgb);
        let int = case.get("int_ior").map_or(1.49, |v| v.as_f64().unwrap() as f32);
        let ext = case.get("ext_ior").map_or(1.000277, |v| v.as_f64().unwrap() as f32);
        let nonlinear = case.get("nonlinear").is_some_and(|v| v.as_bool().unwrap());
        let ior = int / ext;
        let m = Material {
            color: diffuse_factor(diffuse, ior, nonlinear, coat(ior, None).internal).to_array(),
            ior,
            lobe_a: specular.to_array(),
            lobe_b: [diffuse_bound(diffuse, ior, nonlinear, &coat(ior, None)), 0.0, 0.0],
            ..Default::default()
        };
        (m, diffuse, ior, nonlinear)
    }

    /// Mitsuba's plastic at 7 x 7 (incident, outgoing) cosines in 4 cases: the specular lobe's weight, the
    /// BSDF's value (times cos_o), and the diffuse lobe's directional albedo, Mitsuba's eval integrated
    /// over the hemisphere, against ours in closed form: D (1 - F(cos_i)) (1 - fdr_ext') with
    /// 1 - fdr_ext' = 2 int (1 - F(mu)) mu dmu, integrated here by the same midpoint rule.
    #[test]
    fn plastic_matches_mitsubas() {
        let mut worst = [0f32; 3];
        for case in json()["plastic"].as_array().unwrap() {
            let (m, _, ior, _) = material(&case["bsdf"]);
            let n = 4096;
            let escape: f32 = (0..n)
                .map(|k| {
                    let mu = (k as f32 + 0.5) / n as f32;
                    2.0 * (1.0 - coat_fresnel(mu, ior)) * mu / n as f32
                })
                .sum();
            for s in case["samples"].as_array().unwrap() {
                let cos_i = s["cos"].as_f64().unwrap() as f32;
                let (spec, diff) = lobes(&m, cos_i);
                let rel = |a: Vec3, b: Vec3| ((a - b).abs() / b.max(Vec3::splat(1e-6))).max_element();
                let e = rel(spec, rgb(&s["specular"]));
                worst[0] = worst[0].max(e);
                assert!(
                    e < 1e-4,
                    "{}: specular at cos {cos_i}: {spec} against {}",
                    case["bsdf"],
                    s["specular"]
                );
                for ev in s["eval"].as_array().unwrap() {
                    let cos_o = ev["cos_o"].as_f64().unwrap() as f32;
                    let ours = diff * (1.0 - coat_fresnel(cos_o, ior)) / PI * cos_o;
                    let e = rel(ours, rgb(&ev["value"]));
                    worst[1] = worst[1].max(e);
                    assert!(
                        e < 1e-4,
                        "{}: eval at ({cos_i}, {cos_o}): {ours} against {}",
                        case["bsdf"],
                        ev["value"]
                    );
                }
                let albedo = diff * escape;
                let e = rel(albedo, rgb(&s["diffuse_albedo"]));
                worst[2] = worst[2].max(e);
                assert!(
                    e < 1e-4,
                    "{}: albedo at {cos_i}: {albedo} against {}",
                    case["bsdf"],
                    s["diffuse_albedo"]
                );
            }
        }
        println!(
            "largest relative differences: specular {:.2e}, eval {:.2e}, albedo {:.2e}",
            worst[0], worst[1], worst[2]
        );
    }
}

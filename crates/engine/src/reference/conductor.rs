//! CPU twin of shaders/common/conductor.glsl: the specular reflectors (mirror, and Mitsuba's `conductor`
//! with its Fresnel term). Checked against Mitsuba's own conductor in the tests below.

use glam::Vec3;
use ppm_vk_kernels::layout::{Material, SURFACE_CONDUCTOR, SURFACE_MIRROR};

use super::trace::v3;

/// The unpolarised Fresnel reflectance of a metal of complex index `eta + i k` at incidence `cos_i`, per
/// channel (Mitsuba's `fresnel_conductor`, after K. D. Moeller, "Optics", 1988).
pub fn fresnel_conductor(cos_i: f32, eta: Vec3, k: Vec3) -> Vec3 {
    let c2 = cos_i * cos_i;
    let s2 = 1.0 - c2;
    let s4 = s2 * s2;
    let t1 = eta * eta - k * k - Vec3::splat(s2);
    let a2b2 = sqrt((t1 * t1 + 4.0 * k * k * eta * eta).max(Vec3::ZERO));
    let a = sqrt((0.5 * (a2b2 + t1)).max(Vec3::ZERO));
    let t2 = 2.0 * cos_i * a;
    let rs = (a2b2 + Vec3::splat(c2) - t2) / (a2b2 + Vec3::splat(c2) + t2);
    let t3 = a2b2 * c2 + Vec3::splat(s4);
    let t4 = t2 * s2;
    let rp = rs * (t3 - t4) / (t3 + t4);
    0.5 * (rs + rp)
}

fn sqrt(v: Vec3) -> Vec3 {
    Vec3::new(v.x.sqrt(), v.y.sqrt(), v.z.sqrt())
}

pub fn is_reflector(surface: u32) -> bool {
    surface == SURFACE_MIRROR || surface == SURFACE_CONDUCTOR
}

/// What a specular bounce off `m` at incidence `cos_i` leaves of the throughput or flux.
pub fn reflector_weight(m: &Material, cos_i: f32) -> Vec3 {
    match m.surface {
        SURFACE_MIRROR => v3(m.color),
        _ => v3(m.color) * fresnel_conductor(cos_i.clamp(0.0, 1.0), v3(m.lobe_a), v3(m.lobe_b)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::conductors;

    /// Mitsuba 3's conductor, sampled at several angles (scenes/references/conductor_fresnel.py wrote the
    /// file): its weight is specular_reflectance times its Fresnel term, which ours must match.
    #[test]
    fn fresnel_matches_mitsubas_conductor() {
        let text = include_str!("../../../../scenes/references/conductor-fresnel.json");
        let json: serde_json::Value = serde_json::from_str(text).unwrap();
        let rgb = crate::reference::json_rgb;
        let mut checked = 0;
        for case in json["cases"].as_array().unwrap() {
            let bsdf = &case["bsdf"];
            let (eta, k) = match bsdf.get("material") {
                Some(name) => conductors::named(name.as_str().unwrap()).unwrap(),
                None => match (bsdf.get("eta"), bsdf.get("k")) {
                    (Some(e), Some(k)) => (rgb(e), rgb(k)),
                    _ => conductors::named("none").unwrap(),
                },
            };
            let reflectance = bsdf.get("specular_reflectance").map_or(Vec3::ONE, rgb);
            for s in case["samples"].as_array().unwrap() {
                let cos = s["cos"].as_f64().unwrap() as f32;
                let want = rgb(&s["weight"]);
                let got = reflectance * fresnel_conductor(cos, eta, k);
                let err = (got - want).abs().max_element();
                assert!(
                    err < 2e-5 + 2e-5 * want.max_element(),
                    "{bsdf} at cos {cos}: {got} against Mitsuba's {want}"
                );
                checked += 1;
            }
        }
        assert_eq!(checked, 64);
    }

    #[test]
    fn fresnel_limits() {
        // Grazing: everything is reflected; a dielectric (k = 0) at normal incidence: ((n-1)/(n+1))^2.
        let f = fresnel_conductor(0.0, Vec3::new(0.2, 1.5, 3.0), Vec3::new(3.0, 0.0, 1.0));
        assert!((f - Vec3::ONE).abs().max_element() < 1e-6, "{f}");
        let f = fresnel_conductor(1.0, Vec3::splat(1.5), Vec3::ZERO);
        assert!((f.x - 0.04).abs() < 1e-6, "{f}");
        // Mitsuba's default material ("none": eta 0, k 1) is a perfect mirror at every angle.
        let (eta, k) = conductors::named("none").unwrap();
        for c in [1.0, 0.5, 0.1, 0.0] {
            assert!((fresnel_conductor(c, eta, k) - Vec3::ONE).abs().max_element() < 1e-6);
        }
    }
}

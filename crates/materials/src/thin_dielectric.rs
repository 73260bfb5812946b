//! Mitsuba's `thindielectric` (shaders/materials/thin_dielectric.glsl): a pane thin enough that light leaves
//! it where it entered: it reflects with probability R' = 2 R / (1 + R) (R the Fresnel reflectance at its
//! face, R' summing the light reflected inside it any number of times) and passes straight through
//! otherwise, each branch weighted by specular_reflectance or specular_transmittance (the branch at a hit
//! is the CPU twin's, the engine's reference/thin_dielectric.rs). Checked against Mitsuba's own in the
//! tests below.

use crate::math::fresnel_dielectric;

/// The probability of reflection at incidence `cos_i` (either side: the pane is symmetric).
pub fn reflectance(cos_i: f32, ior: f32) -> f32 {
    let r = fresnel_dielectric(cos_i.abs().min(1.0), 1.0 / ior).0;
    r * 2.0 / (1.0 + r)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thin_dielectric_matches_mitsubas() {
        let text = include_str!("../../../scenes/references/coated-bsdfs.json");
        let json: serde_json::Value = serde_json::from_str(text).unwrap();
        let num = |v: Option<&serde_json::Value>, default: f32| v.map_or(default, |v| v.as_f64().unwrap() as f32);
        let mut worst = 0f32;
        for case in json["thindielectric"].as_array().unwrap() {
            let b = &case["bsdf"];
            let ior = num(b.get("int_ior"), 1.5046) / num(b.get("ext_ior"), 1.000277);
            for s in case["samples"].as_array().unwrap() {
                let cos = s["cos"].as_f64().unwrap() as f32;
                let want = s["reflect_prob"].as_f64().unwrap() as f32;
                let got = reflectance(cos, ior);
                worst = worst.max((got / want - 1.0).abs());
                assert!((got / want - 1.0).abs() < 1e-4, "{b}: cos {cos}: {got} against {want}");
                assert_eq!(reflectance(-cos, ior), got, "the pane is the same from both sides");
            }
        }
        println!("largest relative difference {worst:.2e}");
    }
}

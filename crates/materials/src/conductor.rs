//! Mitsuba's `conductor` (shaders/materials/conductor.glsl): the unpolarised Fresnel reflectance of a metal,
//! and the conductors Mitsuba 3 names (`<string name="material" value="Au"/>`), with the RGB `eta` and `k`
//! its RGB variants use: the values Mitsuba's `scalar_rgb` variant loads from its spectral data (3.9.1;
//! printed by scenes/references/conductor_fresnel.py, which also records the Fresnel weights the tests
//! compare with). `none` is Mitsuba's default: a perfect mirror (eta 0, k 1: reflectance 1 at every angle).
//! Checked against Mitsuba's own conductor in the tests below.

use glam::Vec3;

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

/// `(name, eta, k)`, per RGB channel.
const NAMED: &[(&str, [f32; 3], [f32; 3])] = &[
    ("none", [0.0, 0.0, 0.0], [1.0, 1.0, 1.0]),
    ("a-C", [2.94405, 2.22714, 1.96816], [0.887465, 0.799299, 0.81529]),
    ("Ag", [0.155276, 0.116728, 0.138388], [4.82835, 3.12222, 2.1469]),
    ("Al", [1.6575, 0.880405, 0.521244], [9.22381, 6.2695, 4.837]),
    ("AlAs", [3.6053, 3.23294, 2.21632], [0.000679437, 0.0, 0.00751271]),
    ("AlSb", [0.0, 4.13937, 4.66925], [0.0, 0.0940091, 1.30057]),
    ("Au", [0.143036, 0.375307, 1.44205], [3.983, 2.38556, 1.60336]),
    ("Be", [4.18501, 3.18503, 2.78406], [3.83547, 3.01012, 2.86899]),
    ("Cr", [4.36967, 2.91651, 1.6549], [5.20655, 4.23131, 3.7547]),
    ("CsI", [2.1449, 1.70232, 1.66243], [0.0, 0.0, 0.0]),
    ("Cu", [0.201005, 0.92375, 1.10222], [3.91326, 2.45305, 2.14209]),
    ("Cu2O", [3.55177, 2.94987, 2.75188], [0.114207, 0.193897, 0.606134]),
    ("CuO", [3.24754, 2.44781, 2.21022], [0.52109, 0.570031, 0.722179]),
    ("d-C", [2.70872, 2.31883, 2.2289], [0.0, 0.0, 0.0]),
    ("Hg", [2.39894, 1.44003, 0.90957], [6.32759, 4.37192, 3.42176]),
    ("HgTe", [4.77904, 3.2312, 2.6599], [1.63161, 1.58081, 1.72929]),
    ("Ir", [3.0863, 2.08219, 1.61791], [5.59215, 4.06709, 3.26731]),
    ("K", [0.0640432, 0.0464098, 0.0381849], [2.1042, 1.34894, 0.913126]),
    ("Li", [0.265791, 0.195618, 0.220949], [3.54015, 2.31112, 1.66861]),
    ("MgO", [2.08958, 1.65072, 1.59488], [4.3327e-12, 0.0, 2.49865e-11]),
    ("Mo", [4.48397, 3.52513, 2.77631], [4.11144, 3.42083, 3.15061]),
    (
        "Na_palik",
        [0.0602694, 0.0561409, 0.0619884],
        [3.17927, 2.11249, 1.57904],
    ),
    ("Nb", [3.42007, 2.79009, 2.39563], [3.44139, 2.73767, 2.57975]),
    ("Ni_palik", [2.3673, 1.66337, 1.46708], [4.49881, 3.05015, 2.34544]),
    ("Rh", [2.58579, 1.86022, 1.55426], [6.78226, 4.70299, 3.97607]),
    ("Se", [4.05831, 2.84294, 2.82085], [0.75405, 0.638444, 0.521808]),
    ("SiC", [3.17234, 2.52597, 2.47937], [7.53766e-07, 0.0, 1.01925e-05]),
    ("SnTe", [4.52425, 1.98164, 1.28159], [0.0, 0.0, 0.0]),
    ("Ta", [2.06272, 2.39294, 2.62793], [2.40836, 1.74149, 1.94703]),
    ("Te", [7.39023, 4.4821, 2.63711], [3.25602, 3.52706, 3.29205]),
    ("ThF4", [1.83071, 1.44223, 1.38765], [0.0, 0.0, 0.0]),
    ("TiC", [3.70053, 2.83742, 2.58229], [3.26564, 2.35159, 2.17279]),
    ("TiN", [1.64845, 1.15052, 1.37982], [3.36833, 1.9435, 1.10207]),
    ("TiO2", [3.45661, 2.80174, 2.90517], [0.000105265, 0.0, 0.000652887]),
    ("VC", [3.65757, 2.75274, 2.53267], [3.0683, 2.19869, 1.96319]),
    ("V_palik", [4.27758, 3.51295, 2.76107], [3.4913, 2.88945, 3.11152]),
    ("VN", [2.8656, 2.11919, 1.94009], [3.03224, 2.05612, 1.61631]),
    ("W", [4.37082, 3.30025, 2.99841], [3.50064, 2.60487, 2.27323]),
];

/// The RGB `(eta, k)` of a conductor Mitsuba names, or `None`.
pub fn named(name: &str) -> Option<(Vec3, Vec3)> {
    NAMED
        .iter()
        .find(|(n, _, _)| *n == name)
        .map(|&(_, eta, k)| (Vec3::from(eta), Vec3::from(k)))
}

/// Every name [`named`] knows, for error messages.
pub fn names() -> impl Iterator<Item = &'static str> {
    NAMED.iter().map(|(n, _, _)| *n)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mitsuba 3's conductor, sampled at several angles (scenes/references/conductor_fresnel.py wrote the
    /// file): its weight is specular_reflectance times its Fresnel term, which ours must match.
    #[test]
    fn fresnel_matches_mitsubas_conductor() {
        let text = include_str!("../../../scenes/references/conductor-fresnel.json");
        let json: serde_json::Value = serde_json::from_str(text).unwrap();
        let rgb = crate::testing::json_rgb;
        let mut checked = 0;
        for case in json["cases"].as_array().unwrap() {
            let bsdf = &case["bsdf"];
            let (eta, k) = match bsdf.get("material") {
                Some(name) => named(name.as_str().unwrap()).unwrap(),
                None => match (bsdf.get("eta"), bsdf.get("k")) {
                    (Some(e), Some(k)) => (rgb(e), rgb(k)),
                    _ => named("none").unwrap(),
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
        let (eta, k) = named("none").unwrap();
        for c in [1.0, 0.5, 0.1, 0.0] {
            assert!((fresnel_conductor(c, eta, k) - Vec3::ONE).abs().max_element() < 1e-6);
        }
    }
}

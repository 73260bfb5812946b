//! Mitsuba's `roughplastic` as its RGB variants evaluate it: a diffuse base under a rough dielectric coat.
//! Its specular lobe is the coat's microfacet reflection, ks F(wi.h) D(h) G(wi, wo) / (4 cos_i cos_o); its
//! diffuse lobe D' t(cos_i) t(cos_o) / (pi eta^2), with t the coat's transmittance from outside, tabulated
//! over the cosine as Mitsuba tabulates it (64 points, a Gauss-Legendre quadrature over its visible-normal
//! sampler), and D' the base's reflectance with what the coat reflects back into it (Mitsuba's internal
//! reflectance, the same kind of table from inside). The diffuse lobe is a product of a term per direction,
//! as smooth plastic's is (plastic.rs). This module computes the tables on the host; it is checked
//! against Mitsuba's own roughplastic below. The kernels do not render it yet: the readers render
//! roughplastic as smooth plastic, with a warning.

use glam::{Vec2, Vec3};

use crate::math::{fresnel_dielectric, reflect, PI};
use crate::Microfacet;

/// Points of Mitsuba's transmittance table over the cosine (MI_ROUGH_TRANSMITTANCE_RES).
pub const TABLE_POINTS: usize = 64;

/// Gauss-Legendre nodes and weights on [-1, 1] (Newton's method on the Legendre polynomial, in f64).
fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| {
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 0.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                    p0 = p1;
                    p1 = p2;
                }
                dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let dx = p1 / dp;
                x -= dx;
                if dx.abs() < 1e-15 {
                    break;
                }
            }
            (x, 2.0 / ((1.0 - x * x) * dp * dp))
        })
        .collect()
}

/// Mitsuba's visible-normal sampler, with its own warp of the unit square (for GGX the concentric disk
/// of its `sample_visible_11`; for Beckmann the same slope inversion as microfacet.rs): the
/// tables integrate over it, so the same quadrature nodes land where Mitsuba's do.
fn mitsuba_visible_normal(mf: &Microfacet, wi: Vec3, u: Vec2) -> Vec3 {
    if !mf.ggx {
        return mf.sample_visible(wi, u);
    }
    let v = Vec3::new(mf.alpha * wi.x, mf.alpha_v * wi.y, wi.z).normalize();
    let sin_theta = (1.0 - v.z * v.z).max(0.0).sqrt();
    let (cos_phi, sin_phi) = if sin_theta > 0.0 {
        (v.x / sin_theta, v.y / sin_theta)
    } else {
        (1.0, 0.0)
    };
    // Shirley and Chiu's concentric map of the square to the disk.
    let (a, b) = (2.0 * u.x - 1.0, 2.0 * u.y - 1.0);
    let (r, phi) = if a == 0.0 && b == 0.0 {
        (0.0, 0.0)
    } else if a * a > b * b {
        (a, PI / 4.0 * (b / a))
    } else {
        (b, PI / 2.0 - PI / 4.0 * (a / b))
    };
    let (px, mut py): (f32, f32) = (r * phi.cos(), r * phi.sin());
    let s = 0.5 * (1.0 + v.z);
    py = (1.0 - px * px).max(0.0).sqrt() * (1.0 - s) + py * s;
    let z = (1.0 - px * px - py * py).max(0.0).sqrt();
    let norm = 1.0 / (sin_theta * py + v.z * z);
    let slope = Vec2::new(v.z * py - sin_theta * z, px) * norm;
    let slope = Vec2::new(
        cos_phi * slope.x - sin_phi * slope.y,
        sin_phi * slope.x + cos_phi * slope.y,
    ) * Vec2::new(mf.alpha, mf.alpha_v);
    Vec3::new(-slope.x, -slope.y, 1.0).normalize()
}

/// The Gauss-Legendre nodes Mitsuba's eval_reflectance and eval_transmittance integrate with for a
/// relative index `eta`: 32 per axis where eta > 1, else 128.
fn coat_nodes(eta: f32) -> Vec<(f64, f64)> {
    gauss_legendre(if eta > 1.0 { 32 } else { 128 })
}

/// The coat's albedo seen from wi (wi.z > 0) for a relative index `eta` (transmitted over incident):
/// its reflection (`reflect`) or its transmission, each weighed by G1 of the outgoing direction, as
/// Mitsuba's eval_reflectance and eval_transmittance integrate it over `nodes` (coat_nodes(eta)).
fn coat_albedo(mf: &Microfacet, wi: Vec3, eta: f32, reflection: bool, nodes: &[(f64, f64)]) -> f64 {
    let mut sum = 0.0;
    for &(x, wx) in nodes {
        for &(y, wy) in nodes {
            let u = Vec2::new((0.5 * x + 0.5) as f32, (0.5 * y + 0.5) as f32);
            let m = mitsuba_visible_normal(mf, wi, u);
            let cos_i = wi.dot(m);
            let (f, cos_t) = fresnel_dielectric(cos_i, 1.0 / eta);
            let (value, wo) = if reflection {
                (f, reflect(-wi, m))
            } else {
                let e = 1.0 / eta;
                (1.0 - f, (-e * wi + (e * cos_i - cos_t) * m).normalize())
            };
            let ok = if reflection { wo.z > 0.0 } else { wo.z < 0.0 };
            if ok {
                sum += 0.25 * wx * wy * (value * mf.g1(wo, m)) as f64;
            }
        }
    }
    sum
}

/// The coat's tables: its transmittance from outside at the cosines k / 63 (the first 1e-6), and its
/// internal diffuse reflectance (twice the mean of R_int(mu) mu over the same cosines, as Mitsuba takes
/// it).
pub fn tables(ggx: bool, alpha: f32, ior: f32) -> (Vec<f32>, f32) {
    let mf = Microfacet {
        ggx,
        alpha,
        alpha_v: alpha,
    };
    let (outside, inside) = (coat_nodes(ior), coat_nodes(1.0 / ior));
    let mut transmittance = Vec::with_capacity(TABLE_POINTS);
    let mut internal = 0.0;
    for k in 0..TABLE_POINTS {
        let mu = (k as f32 / (TABLE_POINTS - 1) as f32).max(1e-6);
        let wi = Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
        transmittance.push(coat_albedo(&mf, wi, ior, false, &outside) as f32);
        internal += coat_albedo(&mf, wi, 1.0 / ior, true, &inside) * mu as f64;
    }
    (transmittance, (2.0 * internal / TABLE_POINTS as f64) as f32)
}

/// Mitsuba's lerp_gather: the table at cosine `x` in [0, 1], linearly interpolated.
pub fn lookup(table: &[f32], x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0) * (table.len() - 1) as f32;
    let i = (x as usize).min(table.len() - 2);
    let a = x - i as f32;
    table[i] * (1.0 - a) + table[i + 1] * a
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::{json_rgb as rgb, v};

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        for n in [32, 128] {
            let nodes = gauss_legendre(n);
            let w: f64 = nodes.iter().map(|&(_, w)| w).sum();
            assert!((w - 2.0).abs() < 1e-12, "{n}: weights sum to {w}");
            let x6: f64 = nodes.iter().map(|&(x, w)| w * x.powi(6)).sum();
            assert!((x6 - 2.0 / 7.0).abs() < 1e-12, "{n}: int x^6 = {x6}");
        }
    }

    /// Mitsuba's roughplastic in 4 cases: its diffuse lobe at 33 incident cosines seen from straight
    /// above (which traces its transmittance table, times t(1) and D' / (pi eta^2)), and its whole value
    /// (coat and base) at 25 directions for each of 6 incident cosines, against ours from the tables.
    #[test]
    fn rough_plastic_matches_mitsubas() {
        let text = include_str!("../../../scenes/references/roughplastic-bsdf.json");
        let json: serde_json::Value = serde_json::from_str(text).unwrap();
        let (mut worst_diffuse, mut worst_value) = (0f32, 0f32);
        for case in json["roughplastic"].as_array().unwrap() {
            let bsdf = &case["bsdf"];
            let num = |k: &str| bsdf.get(k).map(|v| v.as_f64().unwrap() as f32);
            let ggx = bsdf.get("distribution").and_then(|d| d.as_str()) == Some("ggx");
            let alpha = num("alpha").unwrap_or(0.1);
            let ior = num("int_ior").unwrap_or(1.49) / num("ext_ior").unwrap_or(1.000277);
            let diffuse = bsdf.get("diffuse_reflectance").map_or(Vec3::splat(0.5), rgb);
            let ks = bsdf.get("specular_reflectance").map_or(Vec3::ONE, rgb);
            let nonlinear = bsdf.get("nonlinear").is_some_and(|v| v.as_bool().unwrap());
            let (t, internal) = tables(ggx, alpha, ior);
            let d = crate::plastic::diffuse_factor(diffuse, ior, nonlinear, internal);
            for row in case["diffuse_directional"].as_array().unwrap() {
                let mu = row["mu"].as_f64().unwrap() as f32;
                let want = rgb(&row["value"]);
                let got = d * (lookup(&t, mu) * lookup(&t, 1.0) / PI);
                let err = ((got - want).abs() / want.max(Vec3::splat(1e-4))).max_element();
                worst_diffuse = worst_diffuse.max(err);
                assert!(err < 2e-3, "{bsdf} diffuse at mu {mu}: {got} against Mitsuba's {want}");
            }
            let mf = Microfacet {
                ggx,
                alpha,
                alpha_v: alpha,
            };
            for s in case["samples"].as_array().unwrap() {
                let wi = v(&s["wi"]);
                for e in s["eval"].as_array().unwrap() {
                    let wo = v(&e["wo"]);
                    let want = rgb(&e["value"]);
                    let mut got = Vec3::ZERO;
                    if wi.z > 0.0 && wo.z > 0.0 {
                        let h = (wi + wo).normalize();
                        let f = fresnel_dielectric(wi.dot(h).min(1.0), 1.0 / ior).0;
                        let spec = f * mf.d(h) * mf.g1(wi, h) * mf.g1(wo, h) / (4.0 * wi.z);
                        got = ks * spec + d * (lookup(&t, wi.z) * lookup(&t, wo.z) * wo.z / PI);
                    }
                    let err = (got - want).abs().max_element() / want.max_element().max(1e-3);
                    worst_value = worst_value.max(err);
                    assert!(err < 2e-3, "{bsdf} wi {wi} wo {wo}: {got} against Mitsuba's {want}");
                }
            }
        }
        println!("largest relative differences: diffuse lobe {worst_diffuse:.2e}, value {worst_value:.2e}");
    }
}

//! The host's side of Mitsuba's `plastic` (shaders/materials/plastic.glsl; the CPU twin of its kernel
//! code is the engine's reference/plastic.rs): the coat's Fresnel term, the diffuse lobe's factor D the
//! material table holds, and the bound on a photon's diffuse bounce that keeps it from gaining flux.

use std::collections::HashMap;

use glam::Vec3;

use crate::math::fresnel_dielectric;
use crate::Microfacet;

/// The coat's Fresnel reflectance for light arriving from outside at incidence `cos_i`, `ior` the
/// index inside over the index outside.
pub fn coat_fresnel(cos_i: f32, ior: f32) -> f32 {
    fresnel_dielectric(cos_i.clamp(0.0, 1.0), 1.0 / ior).0
}

/// The coat's Fresnel reflectance at normal incidence, ((ior - 1) / (ior + 1))^2: its least.
fn normal_fresnel(ior: f32) -> f32 {
    ((ior - 1.0) / (ior + 1.0)).powi(2)
}

/// Mitsuba's `fresnel_diffuse_reflectance`: the hemispherical average of the Fresnel reflectance for a
/// relative index `eta`, by the fits Mitsuba uses (Egan and Hilgeman 1973 below 1, d'Eon and Irving 2011
/// above, a polynomial in 1 / eta).
pub fn fresnel_diffuse_reflectance(eta: f32) -> f32 {
    if eta < 1.0 {
        0.0636 / eta + eta * (eta * -1.4399 + 0.7099) + 0.6681
    } else {
        let c = [0.919317, -3.4793, 6.75335, -7.80989, 4.98554, -1.36881];
        c.iter().rev().fold(0.0, |acc, &x| acc / eta + x)
    }
}

/// What the kernels need of a plastic's coat (smooth: Mitsuba's `plastic`; rough: `roughplastic`,
/// rough_plastic.rs): its transmittance from outside over the cosine as a table (rough; smooth
/// coats transmit 1 - F, computed in the kernel), its internal diffuse reflectance (fdr_int, or the rough
/// coat's), and the most it transmits at any angle.
#[derive(Clone, Debug, PartialEq)]
pub struct Coat {
    pub table: Option<Vec<f32>>,
    pub internal: f32,
    pub most: f32,
}

/// The coat of index `ior` (inside over outside), rough with `rough`.
pub fn coat(ior: f32, rough: Option<Microfacet>) -> Coat {
    match rough {
        None => Coat {
            table: None,
            internal: fresnel_diffuse_reflectance(1.0 / ior),
            most: 1.0 - normal_fresnel(ior),
        },
        Some(r) => {
            let (table, internal) = crate::rough_plastic::tables(r.ggx, r.alpha, ior);
            let most = table.iter().fold(0.0f32, |a, &t| a.max(t));
            Coat {
                table: Some(table),
                internal,
                most,
            }
        }
    }
}

/// The coats of one scene, each made once by [`coat`] and shared by every material with the same one: a
/// rough coat's tables take over a million visible-normal samples. Keyed by the index and (a rough coat)
/// the distribution and alpha, all [`coat`] reads, so a cached coat is the one [`coat`] would make.
///
/// Who holds one, passed by `&mut`, no global: a scene reader for the whole file (the Mitsuba reader's
/// bsdfs bound their diffuse reflectance with it, then the scene's validation reads the same one), and
/// the engine's lowering for the whole scene. Loading and lowering do not share one: that would take a
/// loader that hands its cache out and a renderer that takes it (new public API on both), or a field of
/// `Scene` (which would change its `Debug` and every literal of it); so a load plus a lowering make each
/// distinct coat twice.
#[derive(Debug, Default)]
pub struct Coats {
    made: HashMap<(u32, Option<(bool, u32)>), Coat>,
}

impl Coats {
    /// [`coat`]`(ior, rough)`, made the first time it is asked for.
    pub fn coat(&mut self, ior: f32, rough: Option<Microfacet>) -> &Coat {
        let key = (ior.to_bits(), rough.map(|r| (r.ggx, r.alpha.to_bits())));
        self.made.entry(key).or_insert_with(|| coat(ior, rough))
    }
}

/// The diffuse lobe's factor D per channel (`Material::color` of a plastic), `internal` the coat's
/// internal diffuse reflectance ([`Coat::internal`]).
pub fn diffuse_factor(diffuse: Vec3, ior: f32, nonlinear: bool, internal: f32) -> Vec3 {
    let inner = if nonlinear {
        Vec3::ONE - diffuse * internal
    } else {
        Vec3::splat(1.0 - internal)
    };
    diffuse / inner / (ior * ior)
}

/// The largest weight a cosine-sampled diffuse bounce gives: max D times the most the coat transmits
/// (`Material::lobe_b[0]`). The photons choose the diffuse lobe with (1 - F(cos_i)) times this.
pub fn diffuse_bound(diffuse: Vec3, ior: f32, nonlinear: bool, coat: &Coat) -> f32 {
    diffuse_factor(diffuse, ior, nonlinear, coat.internal).max_element() * coat.most
}

/// The largest diffuse_reflectance per channel for which [`diffuse_bound`] stays at most 1, so that no
/// photon leaves a plastic with more flux than it arrived with (the fixed-point sums rely on it). Mitsuba's
/// model allows more (up to 1): above this the per-sample weight of a cosine-sampled bounce exceeds 1
/// although the albedo does not.
pub fn max_diffuse_reflectance(ior: f32, nonlinear: bool, coat: &Coat) -> f32 {
    // D most = 1, with D = rd / inner / ior^2.
    let c = ior * ior / coat.most;
    let rd = if nonlinear {
        c / (1.0 + c * coat.internal)
    } else {
        c * (1.0 - coat.internal)
    };
    rd.min(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn json() -> serde_json::Value {
        let text = include_str!("../../../scenes/references/coated-bsdfs.json");
        serde_json::from_str(text).unwrap()
    }

    #[test]
    fn diffuse_fresnel_fits_match_mitsubas() {
        for row in json()["fresnel_diffuse_reflectance"].as_array().unwrap() {
            let eta = row["eta"].as_f64().unwrap() as f32;
            let want = row["fdr"].as_f64().unwrap() as f32;
            let got = fresnel_diffuse_reflectance(eta);
            assert!((got - want).abs() < 1e-5, "eta {eta}: {got} against Mitsuba's {want}");
        }
    }

    /// The bound the photons rely on: no cosine-sampled diffuse bounce weighs more than diffuse_bound, and
    /// at max_diffuse_reflectance the bound is 1.
    #[test]
    fn the_diffuse_bound_holds() {
        for (ior, nonlinear) in [(1.49, false), (1.5, true), (1.2, false), (2.5, true)] {
            let c = coat(ior, None);
            let rd = max_diffuse_reflectance(ior, nonlinear, &c);
            let b = diffuse_bound(Vec3::splat(rd), ior, nonlinear, &c);
            assert!((b - 1.0).abs() < 1e-4 || rd == 1.0, "ior {ior}: bound {b} at {rd}");
            let d = diffuse_factor(Vec3::splat(rd), ior, nonlinear, c.internal).x;
            for k in 0..=100 {
                let w = d * (1.0 - coat_fresnel(k as f32 / 100.0, ior));
                assert!(w <= b * (1.0 + 1e-6), "weight {w} above the bound {b}");
            }
        }
    }
    /// A coat asked for again is the one made the first time, which is [`coat`]'s: one per distinct index,
    /// distribution and alpha.
    #[test]
    fn coats_are_made_once() {
        let mut coats = Coats::default();
        let rough = Some(Microfacet::isotropic(true, 0.3));
        assert_eq!(*coats.coat(1.5, rough), coat(1.5, rough));
        coats.coat(1.5, rough);
        coats.coat(1.5, None);
        coats.coat(1.5, Some(Microfacet::isotropic(false, 0.3)));
        assert_eq!(coats.made.len(), 3);
    }
}

//! The host's side of Mitsuba's `plastic` (shaders/common/plastic.glsl; its CPU twin is
//! reference/plastic.rs): the diffuse lobe's factor D the material table holds, and the bound on a
//! photon's diffuse bounce that keeps it from gaining flux.

use glam::Vec3;

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
/// scene/rough_plastic.rs): its transmittance from outside over the cosine as a table (rough; smooth
/// coats transmit 1 - F, computed in the kernel), its internal diffuse reflectance (fdr_int, or the rough
/// coat's), and the most it transmits at any angle.
#[derive(Clone, Debug, PartialEq)]
pub struct Coat {
    pub table: Option<Vec<f32>>,
    pub internal: f32,
    pub most: f32,
}

/// The coat of index `ior` (inside over outside), rough with `rough`.
pub fn coat(ior: f32, rough: Option<crate::scene::Microfacet>) -> Coat {
    match rough {
        None => Coat {
            table: None,
            internal: fresnel_diffuse_reflectance(1.0 / ior),
            most: 1.0 - normal_fresnel(ior),
        },
        Some(r) => {
            let (table, internal) = super::rough_plastic::tables(r.ggx, r.alpha, ior);
            let most = table.iter().fold(0.0f32, |a, &t| a.max(t));
            Coat {
                table: Some(table),
                internal,
                most,
            }
        }
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

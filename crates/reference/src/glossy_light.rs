//! CPU twin of shaders/ray/glossy_light.glsl: the light a rough vertex reflects straight from an emitter,
//! by a shadow ray to one light and by the lobe's own sampled direction, weighed by the power heuristic
//! (`RenderParams::glossy_light` chooses both, the lobe alone or the shadow rays alone).

use glam::Vec3;
use ppm_vk_kernels::layout::{
    Material, GLOSSY_LIGHT_BSDF, GLOSSY_LIGHT_LIGHTS, GLOSSY_LIGHT_MIS, LIGHT_SPHERE, SURFACE_PLASTIC,
    SURFACE_ROUGH_CONDUCTOR, SURFACE_ROUGH_GLASS,
};
use ppm_vk_materials::conductor::fresnel_conductor;
use ppm_vk_materials::math::{frame, fresnel_dielectric, to_local, v3, PI};
use ppm_vk_materials::plastic::coat_fresnel;

use crate::lights::{
    choose_emitter, emitter_point, emitter_radiance, environment_pdf, first_emitter, is_area, light_sample, LightSample,
};
use crate::normal_map::Bump;
use crate::rng::Rng;
use crate::rough_conductor::glossy_hit;
use crate::trace::{intersect_scene, offset_ray, Hit};
use crate::{mask, microfacet, shading};
use ppm_vk_engine::lower::GpuScene;

/// `rough_vertex`: eye paths sample through material `m` and take its light here (a rough conductor
/// that holds no hit point, rough glass).
pub fn rough_vertex(g: &GpuScene, m: &Material) -> bool {
    match m.surface {
        SURFACE_ROUGH_CONDUCTOR => !glossy_hit(g, m),
        SURFACE_ROUGH_GLASS => true,
        _ => false,
    }
}

/// `rough_coat`: a plastic with a rough coat, whose reflection eye paths follow.
pub fn rough_coat(m: &Material) -> bool {
    m.surface == SURFACE_PLASTIC && m.table != 0
}

/// `rough_lobe`: the density with which the rough bounce at `h` (seen from `wo`) samples unit direction
/// `l`, and the bounce's weight f |cos_l| / pdf there.
pub fn rough_lobe(m: &Material, h: &Hit, nf: Vec3, front: bool, wo: Vec3, l: Vec3) -> (f32, Vec3) {
    let dpdu = if m.alpha_u != m.alpha_v { h.dpdu } else { Vec3::ZERO };
    let (t, b) = frame(nf, dpdu);
    let (lo, li) = (to_local(wo, t, b, nf), to_local(l, t, b, nf));
    if !(lo.z > 0.0) {
        return (0.0, Vec3::ZERO);
    }
    let mf = microfacet::of(m);
    if m.surface == SURFACE_PLASTIC {
        if !(li.z > 0.0) {
            return (0.0, Vec3::ZERO);
        }
        let hv = (lo + li).normalize();
        let weight = v3(m.lobe_a) * (coat_fresnel(lo.dot(hv), m.ior) * mf.g1(li, hv));
        return (mf.visible_pdf(lo, hv) / (4.0 * li.dot(hv)), weight);
    }
    if m.surface == SURFACE_ROUGH_CONDUCTOR {
        if !(li.z > 0.0) {
            return (0.0, Vec3::ZERO);
        }
        let hv = (lo + li).normalize();
        let weight = v3(m.color) * fresnel_conductor(lo.dot(hv), v3(m.lobe_a), v3(m.lobe_b)) * mf.g1(li, hv);
        return (mf.visible_pdf(lo, hv) / (4.0 * li.dot(hv)), weight);
    }
    let eta = if front { 1.0 / m.ior } else { m.ior };
    let (hv, jacobian);
    if li.z > 0.0 {
        hv = (lo + li).normalize();
        jacobian = 1.0 / (4.0 * li.dot(hv));
    } else {
        let h2 = (li + eta * lo).normalize();
        hv = if h2.z < 0.0 { -h2 } else { h2 };
        let den = eta * lo.dot(hv) + li.dot(hv);
        jacobian = li.dot(hv).abs() / (den * den);
        if !(li.dot(hv) < 0.0) {
            return (0.0, Vec3::ZERO);
        }
    }
    let cos_o = lo.dot(hv);
    if !(cos_o > 0.0) {
        return (0.0, Vec3::ZERO);
    }
    let (f, _) = fresnel_dielectric(cos_o, eta);
    let weight = Vec3::splat(mf.g1(li, hv));
    let branch = if li.z > 0.0 { f } else { 1.0 - f };
    (mf.visible_pdf(lo, hv) * branch * jacobian, weight)
}

/// `power_heuristic`.
fn power_heuristic(p: f32, q: f32) -> f32 {
    let (p2, q2) = (p * p, q * q);
    if p2 + q2 > 0.0 {
        p2 / (p2 + q2)
    } else {
        0.0
    }
}

/// `area_light_density`: p_l' of point y (normal ny, radiance le) seen from x, per unit solid angle.
fn area_light_density(g: &GpuScene, x: Vec3, y: Vec3, ny: Vec3, le: Vec3) -> f32 {
    let v = y - x;
    let d2 = v.dot(v);
    let cos_y = ny.dot(v).abs() * (1.0 / d2.sqrt());
    if cos_y > 0.0 {
        PI * (le.x + le.y + le.z) / g.params.light_power * (d2 / cos_y)
    } else {
        0.0
    }
}

/// glossy_light.glsl's `rough_light_ray`, traced at once: the shadow ray's part at rough vertex `h`,
/// seen from `wo`; `lit` set if it reached a light.
#[allow(clippy::too_many_arguments)]
pub fn rough_light(
    g: &GpuScene,
    m: &Material,
    h: &Hit,
    nf: Vec3,
    ng: Vec3,
    front: bool,
    wo: Vec3,
    bump: &Bump,
    rng: &mut Rng,
    lit: &mut bool,
) -> Vec3 {
    let mode = g.params.glossy_light;
    let e = choose_emitter(g, rng.float());
    let a = rng.float();
    let b = rng.float();
    if e.kind == LIGHT_SPHERE {
        return Vec3::ZERO;
    }
    let (o, w, d, li);
    let mut pl = -1.0;
    if is_area(&e) {
        if mode == GLOSSY_LIGHT_BSDF {
            return Vec3::ZERO;
        }
        let point = emitter_point(&e, a, b);
        o = offset_ray(g, h.pos, if (point - h.pos).dot(nf) >= 0.0 { nf } else { -nf });
        let y = offset_ray(g, point, e.normal);
        let mut w2 = y - o;
        let d2 = w2.dot(w2);
        d = d2.sqrt();
        w2 /= d;
        w = w2;
        let cos_y = -e.normal.dot(w);
        if !(cos_y > 0.0) || !(d2 > 0.0) {
            return Vec3::ZERO;
        }
        let tex = emitter_radiance(g, &e, a, b);
        let le = e.value * tex;
        li = e.flux * tex * (cos_y / (PI * d2));
        if mode == GLOSSY_LIGHT_MIS {
            pl = area_light_density(g, h.pos, point, e.normal, le);
        }
    } else {
        let mut o2 = offset_ray(g, h.pos, nf);
        let Some(mut s) = light_sample(g, &e, o2, a, b) else {
            return Vec3::ZERO;
        };
        if s.w.dot(nf) < 0.0 {
            o2 = offset_ray(g, h.pos, -nf);
            let Some(s2) = light_sample(g, &e, o2, a, b) else {
                return Vec3::ZERO;
            };
            s = s2;
        }
        let LightSample {
            w: w2,
            dist,
            li: li2,
            pdf,
        } = s;
        if pdf > 0.0 && mode == GLOSSY_LIGHT_BSDF {
            return Vec3::ZERO;
        }
        if pdf > 0.0 && mode == GLOSSY_LIGHT_MIS {
            pl = pdf;
        }
        (o, w, d, li) = (o2, w2, dist, li2);
    }
    if !shading::valid(w, ng, nf) {
        return Vec3::ZERO;
    }
    let (pb, fw) = rough_lobe(m, h, nf, front, wo, w);
    if !(pb > 0.0) {
        return Vec3::ZERO;
    }
    let weight = if pl < 0.0 { 1.0 } else { power_heuristic(pl, pb) };
    if intersect_scene(g, o, w, 0.0, d, mask::key(g, rng)).is_some() {
        return Vec3::ZERO;
    }
    let l = fw * (pb * weight) * li * bump.shadowing(w);
    *lit |= l.max_element() > 0.0;
    l
}

/// `lobe_weight`: the weight of emission `le` met at hit `h` by a ray a rough vertex at `x` sampled with
/// density `pb` (0: not after a rough vertex).
pub fn lobe_weight(g: &GpuScene, pb: f32, x: Vec3, h: &Hit, le: Vec3) -> f32 {
    let mode = g.params.glossy_light;
    if !(pb > 0.0) || mode == GLOSSY_LIGHT_BSDF || h.sphere {
        return 1.0;
    }
    if mode == GLOSSY_LIGHT_LIGHTS {
        return 0.0;
    }
    power_heuristic(pb, area_light_density(g, x, h.pos, h.normal, le))
}

/// `escape_weight`: the same where the ray leaves the scene towards the environment.
pub fn escape_weight(g: &GpuScene, pb: f32, d: Vec3) -> f32 {
    let mode = g.params.glossy_light;
    if !g.has_environment || !(pb > 0.0) || mode == GLOSSY_LIGHT_BSDF {
        return 1.0;
    }
    if mode == GLOSSY_LIGHT_LIGHTS {
        return 0.0;
    }
    let e = first_emitter(g);
    power_heuristic(pb, environment_pdf(g, &e, d) * e.cdf)
}

/// `lobe_density`: the density with which the rough bounce at `h` sampled `d` (from `wo`); 0 where the
/// weights are not taken.
pub fn lobe_density(g: &GpuScene, m: &Material, h: &Hit, nf: Vec3, front: bool, wo: Vec3, d: Vec3) -> f32 {
    if g.params.glossy_light == GLOSSY_LIGHT_BSDF {
        return 0.0;
    }
    rough_lobe(m, h, nf, front, wo, d).0
}

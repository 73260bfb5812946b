// The light a rough vertex reflects straight from an emitter: next-event estimation at every rough
// vertex an eye path samples through (rough conductors below params.glossy_alpha, rough glass, a rough
// plastic's coat where the path follows it), combined
// with the lobe's own sampled direction by multiple importance sampling (Veach 1997, the power heuristic),
// as a path tracer does. In ray.comp's path notation these paths are E S* S_rough L, part of term (a):
// before, only the direction the lobe sampled could meet the light, one per vertex and eye path, which
// on a narrow lobe under a small light is rare and bright (the speckle on rough metal), and never met a
// point light or the sun at all. Now each rough vertex also sends a shadow ray to one light (chosen by
// power, a point uniform on it, as direct_light_ray), and the emission that the next ray meets is weighed
// against it:
//   shadow ray:  f cos Le / p_l  times  w_l = p_l'^2 / (p_l'^2 + p_b^2)
//   lobe's ray:  f cos Le / p_b  times  w_b = p_b^2 / (p_l'^2 + p_b^2)
// p_b is the lobe's density of the direction (rough_lobe), p_l the shadow ray's, both per unit solid
// angle. The weights need only sum to one on every path (Veach's condition), so p_l' may be any density
// that both sides compute alike: for an area light it is pi Le(y) / light_power per unit area at the
// point y met (the density of choosing lights by power and points uniformly, where the light table's
// rounding and a radiance texture's mean make the true one differ), times d^2 / cos_y; for the
// environment the true one. Delta lights only a shadow ray reaches (weight 1); glowing spheres only the
// lobe (the shadow ray takes none: weight 0 there, 1 on the lobe's side). The weight of emission met
// after a delta vertex (mirror, smooth glass, the camera) stays 1: no shadow ray samples those paths.
// params.glossy_light chooses both strategies (GLOSSY_LIGHT_MIS), the lobe alone (as before) or the
// shadow rays alone; all three estimate the same light. The photons are unchanged: they leave no record
// at rough vertices, so the partition of ray.comp holds. CPU twin: crates/reference/src/glossy_light.rs.
#ifndef GLOSSY_LIGHT_GLSL
#define GLOSSY_LIGHT_GLSL

// Whether eye paths sample through material m here and take its light by this file: a rough conductor
// that holds no hit point, rough glass. (A rough plastic's coat too, where ray.comp follows it:
// rough_coat.)
bool rough_vertex(Material m, uint i) {
    if (HAS_ROUGH_CONDUCTORS && m.surface == SURFACE_ROUGH_CONDUCTOR) return !glossy_hit(i);
    return HAS_ROUGH_GLASS && m.surface == SURFACE_ROUGH_GLASS;
}

// Whether material m (table: material_table(i)) is a plastic with a rough coat, whose reflection eye
// paths follow and whose light this file takes as a rough vertex's.
bool rough_coat(Material m, uint table) {
    return HAS_ROUGH_PLASTICS && m.surface == SURFACE_PLASTIC && table != 0u;
}

// The lobe of rough material i (`m` as apply_texture left it) at hit h, seen from wo (unit, towards the
// eye, on nf's side), for unit direction l: the density with which its bounce (lobe_bounce.glsl) samples l,
// per unit solid angle, and the bounce's weight f |cos_l| / pdf there (so f |cos_l| = pdf weight). 0
// where the bounce cannot reach l. front: h is met from outside (rough glass's index ratio).
float rough_lobe(uint i, Material m, Hit h, vec3 nf, bool front, vec3 wo, vec3 l, out vec3 weight) {
    weight = vec3(0.0);
    vec3 t, b;
    frame(nf, rough_tangent(i, h), t, b);
    vec3 lo = to_local(wo, t, b, nf);
    vec3 li = to_local(l, t, b, nf);
    if (!(lo.z > 0.0)) return 0.0;
    Microfacet mf = hit_microfacet(i, m);
    if (HAS_ROUGH_PLASTICS && m.surface == SURFACE_PLASTIC) {
        // A rough coat (plastic_lobes): weight ks F(wo.h) G1(l, h) with the coat's dielectric Fresnel term,
        // density D_wo(h) / (4 l.h), as a rough conductor's.
        if (!(li.z > 0.0)) return 0.0;
        vec3 hv = normalize(lo + li);
        weight = material_term_a(i) * (coat_fresnel(dot(lo, hv), m.ior) * mf_g1(mf, li, hv));
        return mf_visible_pdf(mf, lo, hv) / (4.0 * dot(li, hv));
    }
    if (HAS_ROUGH_CONDUCTORS && m.surface == SURFACE_ROUGH_CONDUCTOR) {
        if (!(li.z > 0.0)) return 0.0;
        vec3 hv = normalize(lo + li);
        vec3 eta, k;
        material_terms(i, eta, k);
        // lobe_bounce.glsl, a rough conductor: weight ks F(wo.h) G1(l, h), density D_wo(h) / (4 l.h).
        weight = m.color * fresnel_conductor(dot(lo, hv), eta, k) * mf_g1(mf, li, hv);
        return mf_visible_pdf(mf, lo, hv) / (4.0 * dot(li, hv));
    }
    // Rough glass (lobe_bounce.glsl): the facet h by the visible normals, then reflection with
    // probability F(wo.h) or refraction; the weight G1(l, h) on either branch.
    float eta = front ? 1.0 / m.ior : m.ior; // incident (eye side) index over transmitted
    vec3 hv;
    float jacobian;
    if (li.z > 0.0) {
        hv = normalize(lo + li);
        jacobian = 1.0 / (4.0 * dot(li, hv));
    } else {
        // Refraction: l = -eta wo + (eta cos_o - cos_t) h, so h is along l + eta wo (turned to wo's side),
        // and dh/dl = |l.h| / (eta wo.h + l.h)^2 (Walter et al. 2007, eq. 16, over the transmitted index^2).
        hv = normalize(li + eta * lo);
        if (hv.z < 0.0) hv = -hv;
        float den = eta * dot(lo, hv) + dot(li, hv);
        jacobian = abs(dot(li, hv)) / (den * den);
        if (!(dot(li, hv) < 0.0)) return 0.0;
    }
    float cos_o = dot(lo, hv);
    if (!(cos_o > 0.0)) return 0.0;
    float cos_t;
    float f = fresnel_dielectric(cos_o, eta, cos_t);
    float g = mf_g1(mf, li, hv);
    weight = vec3(g);
    return mf_visible_pdf(mf, lo, hv) * (li.z > 0.0 ? f : 1.0 - f) * jacobian;
}

// The power heuristic's weight of the strategy of density p against the other's q.
float power_heuristic(float p, float q) {
    float p2 = p * p;
    float q2 = q * q;
    return p2 + q2 > 0.0 ? p2 / (p2 + q2) : 0.0;
}

// p_l' of the point y of an area light of normal ny and radiance le there, seen from x, per unit solid
// angle (above). Both strategies take it from the two points as they are, before any ray offset, so that
// they weigh a path alike.
float area_light_density(vec3 x, vec3 y, vec3 ny, vec3 le) {
    vec3 v = y - x;
    float d2 = dot(v, v);
    float cos_y = abs(dot(ny, v)) * inversesqrt(d2);
    return cos_y > 0.0 ? PI * (le.r + le.g + le.b) / params.light_power * (d2 / cos_y) : 0.0;
}

// The shadow ray's part at rough vertex h (material i, `m`), seen from wo (towards the eye): one light
// chosen by power, weighed against the lobe. nf, ng: the shading and true normals on wo's side. Draws
// three numbers, and a mask key where there is a shadow ray to trace (ray.comp's ShadowRay: prepared
// here, traced by the caller).
ShadowRay rough_light_ray(uint i, Material m, Hit h, vec3 nf, vec3 ng, bool front, vec3 wo, inout Rng rng) {
    ShadowRay ray = no_shadow();
    Emitter e = choose_emitter(rng_float(rng));
    float a = rng_float(rng);
    float b = rng_float(rng);
    if (HAS_SPHERE_LIGHTS && e.kind == LIGHT_SPHERE) return ray; // the lobe's alone
    vec3 w, li, o;
    float d;
    float pl = -1.0; // the shadow ray's p_l' for the power heuristic; below 0: weight 1 (no other strategy)
    if (is_area(e)) {
        if (params.glossy_light == GLOSSY_LIGHT_BSDF) return ray;
        vec3 point = emitter_point(e, a, b);
        // The side of the surface the light lies on (rough glass transmits), then the ray from there.
        o = offset_ray(h.pos, dot(point - h.pos, nf) >= 0.0 ? nf : -nf);
        vec3 y = offset_ray(point, e.normal); // short of the emitter, which the ray must not hit
        w = y - o;
        float d2 = dot(w, w);
        d = sqrt(d2);
        w /= d;
        float cos_y = -dot(e.normal, w);
        if (!(cos_y > 0.0) || !(d2 > 0.0)) return ray; // emitters are one-sided
        vec3 tex = emitter_radiance(e, a, b); // a radiance texture there, else 1
        vec3 le = e.value * tex;
        // Le / p_l: the flux e.flux (Le A pi / prob) times cos_y / (pi d^2).
        li = e.flux * tex * (cos_y / (PI * d2));
        if (params.glossy_light == GLOSSY_LIGHT_MIS) pl = area_light_density(h.pos, point, e.normal, le);
    } else {
        // Points, spots, the sun and the environment (light_sample: li is Le / p_l). A light below the
        // surface is sampled again from below, with the same numbers.
        float pdf;
        o = offset_ray(h.pos, nf);
        if (!light_sample(e, o, a, b, w, d, li, pdf)) return ray;
        if (dot(w, nf) < 0.0) {
            o = offset_ray(h.pos, -nf);
            if (!light_sample(e, o, a, b, w, d, li, pdf)) return ray;
        }
        if (pdf > 0.0 && params.glossy_light == GLOSSY_LIGHT_BSDF) return ray; // the environment
        if (pdf > 0.0 && params.glossy_light == GLOSSY_LIGHT_MIS) pl = pdf;
    }
    if (HAS_SHADING_NORMALS && !shading_valid(w, ng, nf)) return ray;
    vec3 fw;
    float pb = rough_lobe(i, m, h, nf, front, wo, w, fw);
    if (!(pb > 0.0)) return ray;
    float weight = pl < 0.0 ? 1.0 : power_heuristic(pl, pb);
    ray.key = mask_key(rng);
    vec3 l = fw * (pb * weight) * li; // f |cos_l| Le / p_l w_l
    if (HAS_NORMAL_MAPS) l *= bump_shadowing(w); // a bump or normal map's term (normal_map.glsl)
    return ShadowRay(o, w, d, ray.key, l, true);
}

// The lobe's part: the weight of the emission `le` met at hit h by a ray that a rough vertex at x sampled
// with density pb (pb 0: the ray did not leave a rough vertex; weight 1).
float lobe_weight(float pb, vec3 x, Hit h, vec3 le) {
    if (!(pb > 0.0) || params.glossy_light == GLOSSY_LIGHT_BSDF) return 1.0;
    if (HAS_SPHERE_LIGHTS && h.kind == HIT_SPHERE) return 1.0; // the shadow rays take no sphere
    if (params.glossy_light == GLOSSY_LIGHT_LIGHTS) return 0.0;
    return power_heuristic(pb, area_light_density(x, h.pos, h.normal, le));
}

// The same where the ray leaves the scene towards the environment.
float escape_weight(float pb, vec3 d) {
    if (!HAS_ENVIRONMENT || !(pb > 0.0) || params.glossy_light == GLOSSY_LIGHT_BSDF) return 1.0;
    if (params.glossy_light == GLOSSY_LIGHT_LIGHTS) return 0.0;
    Emitter e = first_emitter();
    return power_heuristic(pb, environment_pdf(e, d) * e.cdf);
}

// The density with which the rough bounce at h sampled d (from wo), for lobe_weight; 0 where the weights
// are not taken.
float lobe_density(uint i, Material m, Hit h, vec3 nf, bool front, vec3 wo, vec3 d) {
    if (params.glossy_light == GLOSSY_LIGHT_BSDF) return 0.0;
    vec3 unused;
    return rough_lobe(i, m, h, nf, front, wo, d, unused);
}
#endif

// Mitsuba's `roughdielectric` (Walter et al. 2007, "Microfacet Models for Refraction through Rough
// Surfaces"): an interface between two dielectrics whose surface is a microfacet distribution
// (microfacet.glsl), each facet a smooth dielectric. A bounce samples a normal m visible from wi, then
// reflection about m with the facet's Fresnel probability F(wi.m) or refraction through it otherwise; the
// weight f |cos_o| / pdf is then G1(wo, m) on either branch, at most 1. Radiance is not scaled by the
// squared index ratio where it crosses, as smooth glass leaves it (geometry.glsl's glass_branch): the
// factors of a path's entry and exit cancel, so what is seen of glass from outside is exact; with it the
// weight is the same for photons and eye paths. Its vertices are S in ray.comp's path notation, as the
// rough conductor's (rough_conductor.glsl). CPU twin: crates/materials/src/rough_dielectric.rs and
// crates/reference/src/rough_dielectric.rs (a bounce).
#ifndef ROUGH_DIELECTRIC_GLSL
#define ROUGH_DIELECTRIC_GLSL
#include "materials/rough_conductor.glsl"

#ifdef SCENE_CONSTANTS
#define HAS_ROUGH_GLASS SCENE_ROUGH_GLASS
#else
#define HAS_ROUGH_GLASS true
#endif

// One bounce off a rough dielectric of distribution mf (hit_microfacet) and index ior (inside over outside) at pos, arriving along d from the
// front (outside) or not, nf facing d, dpdu its tangent (frame): o and d become the new ray; u chooses
// the branch, u2 the normal. Returns the weight, 0 where the sampled direction leaves on the wrong side
// (the path ends there).
float rough_dielectric_bounce(Microfacet mf, float ior, vec3 pos, vec3 nf, vec3 dpdu, bool front, float u, vec2 u2,
                              inout vec3 o, inout vec3 d) {
    vec3 t, b;
    frame(nf, dpdu, t, b);
    vec3 wi = -to_local(d, t, b, nf);
    if (wi.z <= 0.0) return 0.0;
    vec3 h = mf_sample_visible(mf, wi, u2);
    float eta = front ? 1.0 / ior : ior; // incident index over transmitted
    float cos_i = dot(wi, h);
    float cos_t;
    float f = fresnel_dielectric(cos_i, eta, cos_t);
    vec3 wo;
    if (u < f) {
        wo = reflect(-wi, h);
        if (wo.z <= 0.0) return 0.0;
        o = offset_ray(pos, nf);
    } else {
        wo = normalize(-eta * wi + (eta * cos_i - cos_t) * h);
        if (wo.z >= 0.0) return 0.0;
        o = offset_ray(pos, -nf);
    }
    d = normalize(wo.x * t + wo.y * b + wo.z * nf);
    return mf_g1(mf, wo, h);
}

// The tangent an anisotropic rough material i needs at hit h (frame); 0 for an isotropic one.
vec3 rough_tangent(uint i, Hit h) {
    if (!HAS_ANISOTROPY) return vec3(0.0);
    Microfacet mf = material_microfacet(i);
    return mf.au != mf.av ? surface_tangent(h) : vec3(0.0);
}

// The bounce of an eye path off material i (`m` as apply_texture left it) at hit h, if it is rough: draws
// its numbers from rng, moves the ray (o, d) on, multiplies w by the weight (0: the path ends) and returns
// true; false for every other surface, untouched. A photon's is photon/lobe_bounce.glsl's (the same
// numbers and weights, its code shared with the plastics' coat).
bool rough_bounce(uint i, Material m, Hit h, vec3 nf, bool front, inout Rng rng, inout vec3 o,
                  inout vec3 d, inout vec3 w) {
    if (HAS_ROUGH_CONDUCTORS && m.surface == SURFACE_ROUGH_CONDUCTOR) {
        float u1 = rng_float(rng);
        float u2 = rng_float(rng);
        w *= rough_conductor_bounce(i, m, h.pos, nf, rough_tangent(i, h), vec2(u1, u2), o, d);
        return true;
    }
    if (HAS_ROUGH_GLASS && m.surface == SURFACE_ROUGH_GLASS) {
        float u = rng_float(rng);
        float u1 = rng_float(rng);
        float u2 = rng_float(rng);
        w *= rough_dielectric_bounce(hit_microfacet(i, m), m.ior, h.pos, nf, rough_tangent(i, h), front, u, vec2(u1, u2), o, d);
        return true;
    }
    return false;
}
#endif

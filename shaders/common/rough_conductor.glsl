// Mitsuba's `roughconductor`: a metal whose surface is a microfacet distribution (microfacet.glsl), each
// facet a smooth conductor (conductor.glsl). Its BSDF is F(wi.m) D(m) G1(wi, m) G1(wo, m) / (4 cos_i
// cos_o) times specular_reflectance, m the half vector. Eye paths and photons alike sample it by the
// normals visible from wi and go on along the reflection: the weight f cos_o / pdf is then F(wi.m) G1(wo,
// m) specular_reflectance, at most 1, so no photon gains flux (the fixed-point sums rely on it). The
// estimate stays consistent because such a vertex is treated as the mirror is (an S in ray.comp's path
// notation): no hit point and no photon record there, its lobe sampled by both path kinds with the exact
// weight; the BSDF is reciprocal, so the photons' weight is the eye paths'. CPU twin:
// crates/engine/src/reference/rough_conductor.rs.
#ifndef ROUGH_CONDUCTOR_GLSL
#define ROUGH_CONDUCTOR_GLSL
#include "microfacet.glsl"

#ifdef SCENE_CONSTANTS
#define HAS_ROUGH_CONDUCTORS SCENE_ROUGH_CONDUCTORS
#else
#define HAS_ROUGH_CONDUCTORS true
#endif

// A direction arriving along d at a point with normal nf facing it, in the local frame (t, b, nf) (the
// distributions the readers accept are isotropic: any tangent serves).
vec3 to_local(vec3 d, vec3 t, vec3 b, vec3 nf) {
    return vec3(dot(d, t), dot(d, b), dot(d, nf));
}

// One bounce off rough conductor i (`m` as material() read it) at pos: o and d become the reflected ray;
// returns its weight, 0 where the sampled direction goes below the surface (the path ends there).
vec3 rough_conductor_bounce(uint i, Material m, vec3 pos, vec3 nf, vec2 u, inout vec3 o, inout vec3 d) {
    vec3 t, b;
    onb(nf, t, b);
    vec3 wi = -to_local(d, t, b, nf);
    if (wi.z <= 0.0) return vec3(0.0);
    Microfacet mf = material_microfacet(i);
    vec3 h = mf_sample_visible(mf, wi, u);
    vec3 wo = reflect(-wi, h);
    if (wo.z <= 0.0) return vec3(0.0);
    vec3 eta, k;
    material_terms(i, eta, k);
    d = normalize(wo.x * t + wo.y * b + wo.z * nf);
    o = offset_ray(pos, nf);
    return m.color * fresnel_conductor(dot(wi, h), eta, k) * mf_g1(mf, wo, h);
}
#endif

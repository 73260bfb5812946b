// Mitsuba's `roughconductor`: a metal whose surface is a microfacet distribution (microfacet.glsl), each
// facet a smooth conductor (conductor.glsl). Its BSDF is F(wi.m) D(m) G1(wi, m) G1(wo, m) / (4 cos_i
// cos_o) times specular_reflectance, m the half vector. Eye paths and photons alike sample it by the
// normals visible from wi and go on along the reflection: the weight f cos_o / pdf is then F(wi.m) G1(wo,
// m) specular_reflectance, at most 1, so no photon gains flux (the fixed-point sums rely on it). The
// estimate stays consistent because such a vertex is treated as the mirror is (an S in ray.comp's path
// notation): no hit point and no photon record there, its lobe sampled by both path kinds with the exact
// weight; the BSDF is reciprocal, so the photons' weight is the eye paths'. Rough enough conductors
// (RenderParams.glossy_alpha) may instead hold hit points, below. CPU twin:
// crates/reference/src/rough_conductor.rs (density and bound: crates/materials/src/rough_conductor.rs).
#ifndef ROUGH_CONDUCTOR_GLSL
#define ROUGH_CONDUCTOR_GLSL
#include "materials/microfacet.glsl"

#ifdef SCENE_CONSTANTS
#define HAS_ROUGH_CONDUCTORS SCENE_ROUGH_CONDUCTORS
#else
#define HAS_ROUGH_CONDUCTORS true
#endif

// Glossy hit points (params.glossy_alpha): where an eye path leaves a hit point on rough conductor i
// instead of sampling through it, the photons leave records there too (photon.comp), and the gather
// weighs each photon by the BRDF for its own incoming direction. f(wi, wo) = ks F(wi.h) D(h) G1(wi, h)
// G1(wo, h) / (4 cos_i cos_o) is bounded: D(h) <= its peak (1 / (pi alpha^2) at the normal up to alpha = 1
// for GGX and 1 / sqrt(2) for Beckmann; beyond, GGX's is alpha^2 / pi at grazing and Beckmann's
// 4 alpha^2 e^(1 / alpha^2 - 2) / pi at tan^2 = 2 alpha^2 - 1), G1(wi, h) / cos_i <= gb (2 / min(alpha, 2)
// for GGX, exactly; 3.535 / alpha + 1 for Beckmann's fit, whose supremum is 3.535 / alpha below alpha = 4
// and under 1.01 above), F, G1(wo, h) and ks <= 1. The hit point's weight holds ks and
// the bound over 4 cos_o (rough_conductor_hit_weight), and a photon contributes its flux times the rest,
// rough_conductor_ratio, at most 1 per channel: the fixed-point sums' bound (RenderParams.flux_fixed)
// holds as for a diffuse hit point.
float rough_conductor_bound(Microfacet mf) {
    float a2 = mf.au * mf.av;
    float peak;
    if (mf_is_ggx(mf)) peak = max(1.0, a2 * a2);
    else peak = a2 > 0.5 ? 4.0 * a2 * a2 * exp(1.0 / a2 - 2.0) : 1.0;
    float gb = mf_is_ggx(mf) ? 2.0 / min(mf.au, 2.0) : 3.535 / mf.au + 1.0;
    return gb * peak / (PI * a2);
}

// What evaluating rough conductor i's BRDF towards wo (unit, leaving the surface of unit normal n) needs,
// read once: its distribution, complex index, the local frame, wo in it, and the bound. The gather reads
// it once per glossy hit point, not per photon.
struct RoughView {
    Microfacet mf;
    vec3 eta;
    vec3 k;
    vec3 t;
    vec3 b;
    vec3 lo;
    float bound;
};

RoughView rough_view(uint i, vec3 wo, vec3 n) {
    RoughView v;
    v.mf = material_microfacet(i);
    material_terms(i, v.eta, v.k);
    onb(n, v.t, v.b);
    v.lo = to_local(wo, v.t, v.b, n);
    v.bound = rough_conductor_bound(v.mf);
    return v;
}

// The terms of f(wi, wo) for unit wi leaving the surface of normal n (v: rough_view towards wo): returns
// D G1(wi) G1(wo) / cos_i (0 where either is below it), and F the facets' Fresnel term per channel.
float rough_conductor_terms(RoughView v, vec3 wi, vec3 n, out vec3 f) {
    f = vec3(0.0);
    vec3 li = to_local(wi, v.t, v.b, n);
    if (li.z <= 0.0 || v.lo.z <= 0.0) return 0.0;
    vec3 h = normalize(li + v.lo);
    f = fresnel_conductor(clamp(dot(li, h), 0.0, 1.0), v.eta, v.k);
    return mf_d(v.mf, h) * mf_g1(v.mf, li, h) * mf_g1(v.mf, v.lo, h) / li.z;
}

// A glossy hit point's weight on rough conductor i: the eye path's throughput times ks times the bound
// over 4 cos_o.
vec3 rough_conductor_hit_weight(uint i, vec3 color, vec3 thr, float cos_o) {
    return thr * color * (rough_conductor_bound(material_microfacet(i)) / (4.0 * cos_o));
}

// What a photon arriving along -wi gives a glossy hit point (v: rough_view of its rough conductor towards
// the eye): f(wi, wo) over the hit point's weight per unit throughput, at most 1 per channel.
vec3 rough_conductor_ratio(RoughView v, vec3 wi, vec3 n) {
    vec3 f;
    float s = rough_conductor_terms(v, wi, n, f);
    return min(f * (s / v.bound), vec3(1.0));
}

// Whether eye paths leave hit points on material i (a rough conductor) rather than sample through it: an
// isotropic one of roughness at least glossy_alpha (a hit point holds no tangent for an anisotropic lobe),
// whose alpha is not a texture (the gather evaluates the BRDF per photon without the hit's uv).
bool glossy_hit(uint i) {
    Microfacet mf = material_microfacet(i);
    return mf.au >= params.glossy_alpha && mf.au == mf.av
        && texelFetch(material_texels, int(MATERIAL_TEXELS * i + 5u)).z == 0u;
}

// A bounce off a rough conductor is common/lobe_bounce.glsl's (for the eye paths and the photons): a
// normal m visible from wi, the reflection about it, weight ks F(wi.m) G1(wo, m).
#endif

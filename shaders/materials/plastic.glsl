// Mitsuba's `plastic`: a diffuse base under a smooth dielectric coat. Its BSDF is a specular lobe,
// specular_reflectance times the coat's Fresnel term F, and a diffuse lobe D (1 - F(cos_i)) (1 - F(cos_o))
// / pi, D the base's reflectance with the light the coat sends back into it (Material.color, made on the
// host). The diffuse lobe is a product of a term of each direction, so the photon estimate needs no BSDF
// per photon: a photon's record carries its flux times (1 - F(cos_i)) (photon.comp), and a hit point on
// the plastic weighs what it gathers by D (1 - F(cos_o)) / pi (ray.comp). CPU twin:
// crates/reference/src/plastic.rs (the host's side: crates/materials/src/plastic.rs).
#ifndef PLASTIC_GLSL
#define PLASTIC_GLSL
#include "materials/microfacet.glsl"

// A kernel compiled for one scene (SCENE_CONSTANTS) knows whether it has plastics; without them this
// code is left out, as the conductors' is.
#ifdef SCENE_CONSTANTS
#define HAS_PLASTICS SCENE_PLASTICS
#define HAS_ROUGH_PLASTICS SCENE_ROUGH_PLASTICS
#else
#define HAS_PLASTICS true
#define HAS_ROUGH_PLASTICS true
#endif

float max3(vec3 v) {
    return max(v.r, max(v.g, v.b));
}

// The coat's Fresnel reflectance for light arriving from outside at incidence cos_i; ior: inside over
// outside.
float coat_fresnel(float cos_i, float ior) {
    float cos_t;
    return fresnel_dielectric(clamp(cos_i, 0.0, 1.0), 1.0 / ior, cos_t);
}

// The coat's transmittance from outside at incidence cos: 1 - F for a smooth coat (table 0), else a rough
// coat's table (Material.table: 64 values over the cosine, four a texel of texture_texels), linearly
// interpolated as Mitsuba's roughplastic reads it (crates/materials/src/rough_plastic.rs made it).
float coat_transmittance(uint table, float cos_i, float ior) {
    if (!HAS_ROUGH_PLASTICS || table == 0u) return 1.0 - coat_fresnel(cos_i, ior);
    float x = clamp(cos_i, 0.0, 1.0) * 63.0;
    uint k = min(uint(x), 62u);
    float a = x - float(k);
    uint at = table - 1u;
    float t0 = uintBitsToFloat(texelFetch(texture_texels, int(at + k / 4u))[k % 4u]);
    float t1 = uintBitsToFloat(texelFetch(texture_texels, int(at + (k + 1u) / 4u))[(k + 1u) % 4u]);
    return mix(t0, t1, a);
}

// A path arriving along d at plastic i (nf facing it): the coat's reflection, d becoming its direction and
// spec its weight, and the diffuse lobe's D t(cos_o) (diff), whose f_r is that over pi times t of the other
// direction. A smooth coat reflects d as a mirror with weight ks F(cos_o); a rough one (Mitsuba's
// roughplastic) about a normal visible from d, drawn from rng, with weight ks F(wi.h) G1(wo, h) (0 where wo
// goes below the surface), as the rough conductor's (rough_conductor.glsl). table: material_table(i).
void plastic_lobes(uint i, Material m, uint table, vec3 nf, inout Rng rng, inout vec3 d, out vec3 spec,
                   out vec3 diff) {
    float cos_o = -dot(d, nf);
    diff = m.color * coat_transmittance(table, cos_o, m.ior);
    if (!HAS_ROUGH_PLASTICS || table == 0u) {
        spec = material_term_a(i) * coat_fresnel(cos_o, m.ior);
        d = reflect(d, nf);
        return;
    }
    float u1 = rng_float(rng);
    float u2 = rng_float(rng);
    vec3 t, b;
    onb(nf, t, b);
    vec3 wi = -to_local(d, t, b, nf);
    Microfacet mf = material_microfacet(i);
    vec3 h = mf_sample_visible(mf, wi, vec2(u1, u2));
    vec3 wo = reflect(-wi, h);
    spec = wi.z > 0.0 && wo.z > 0.0 ? material_term_a(i) * (coat_fresnel(dot(wi, h), m.ior) * mf_g1(mf, wo, h))
                                    : vec3(0.0);
    d = normalize(wo.x * t + wo.y * b + wo.z * nf);
}

// A photon's scattering off a plastic is common/lobe_bounce.glsl's, which samples the coat with the rough
// conductors' and rough glass's lobes in one place.
#endif

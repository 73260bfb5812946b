// Mitsuba's `plastic`: a diffuse base under a smooth dielectric coat. Its BSDF is a specular lobe,
// specular_reflectance times the coat's Fresnel term F, and a diffuse lobe D (1 - F(cos_i)) (1 - F(cos_o))
// / pi, D the base's reflectance with the light the coat sends back into it (Material.color, made on the
// host). The diffuse lobe is a product of a term of each direction, so the photon estimate needs no BSDF
// per photon: a photon's record carries its flux times (1 - F(cos_i)) (photon.comp), and a hit point on
// the plastic weighs what it gathers by D (1 - F(cos_o)) / pi (ray.comp). CPU twin:
// crates/engine/src/reference/plastic.rs.
#ifndef PLASTIC_GLSL
#define PLASTIC_GLSL

// A kernel compiled for one scene (SCENE_CONSTANTS) knows whether it has plastics; without them this
// code is left out, as the conductors' is.
#ifdef SCENE_CONSTANTS
#define HAS_PLASTICS SCENE_PLASTICS
#else
#define HAS_PLASTICS true
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

// Seen from (or lit from) incidence cos_o, the specular lobe's weight (specular_reflectance F(cos_o))
// and the diffuse lobe's D (1 - F(cos_o)), whose f_r is that over pi times (1 - F) of the other direction.
void plastic_lobes(uint i, Material m, float cos_o, out vec3 spec, out vec3 diff) {
    float f = coat_fresnel(cos_o, m.ior);
    spec = material_term_a(i) * f;
    diff = m.color * (1.0 - f);
}

// A photon's scattering off plastic i, arriving along d at a point with normal nf facing it, where
// Fresnel reflects fi: the specular lobe with probability max(ks) fi (weight ks / max(ks)), the diffuse
// lobe with probability (1 - fi) bound (weight D (1 - F(cos_o)) / bound, at most 1 per channel: the host
// keeps bound = max(D) (1 - F(1)) <= 1), else absorbed: false. Roulette and the choice of lobe in one draw,
// and no bounce gains flux, which the fixed-point sums rely on. u: the choice; u1, u2: the direction.
bool plastic_scatter(uint i, Material m, float fi, vec3 pos, vec3 nf, float u, float u1, float u2,
                     inout vec3 o, inout vec3 d, inout vec3 flux) {
    vec3 ks, bound;
    material_terms(i, ks, bound);
    float ks_max = max3(ks);
    float ps = ks_max * fi;
    if (u < ps) {
        flux *= ks / ks_max;
        d = reflect(d, nf);
    } else if (u < ps + (1.0 - fi) * bound.x) {
        d = cosine_direction(nf, u1, u2);
        flux *= m.color * ((1.0 - coat_fresnel(dot(d, nf), m.ior)) / bound.x);
    } else {
        return false;
    }
    o = offset_ray(pos, nf);
    return true;
}
#endif

// The bounce off a surface with a Fresnel-weighted lobe choice or a microfacet lobe: plastic (smooth or
// rough coat, plastic.glsl; photons only: an eye path takes both of its lobes, ray.comp), rough conductor
// (rough_conductor.glsl) and rough glass (rough_dielectric.glsl), in one routine for the photons and the
// eye paths alike. lavapipe runs every copy of code under a mask, so a kernel with a sampler per surface
// paid for each at every bounce (an idle copy of the rough conductor's and the rough coat's cost the
// interior's photon stage 21-24%, docs/performance.md); here one frame, one draw of a visible normal, one
// dielectric Fresnel term, one reflection and one refraction about the facet serve them all. Each surface
// draws its numbers in the order its own routine drew them, and computes its weight with the same
// operations, so the paths are the CPU twin's, which keeps them apart (crates/reference/src/plastic.rs,
// rough_conductor.rs, rough_dielectric.rs, and lib.rs's rough_bounce):
//   rough conductor: the normal's two numbers; reflects about the normal, weight ks F(wi.m) G1(wo, m) (its
//     complex-index Fresnel term per channel);
//   rough glass: the branch, then the normal's two; reflects with probability F(wi.m), else refracts, weight
//     G1(wo, m); the index ratio by the side it arrives from;
//   plastic: the lobe, the base's direction (two), then a rough coat's normal (two; a smooth coat's normal
//     is nf itself, and it reflects about nf as a mirror). The coat reflects with probability max(ks) F
//     (weight ks / max(ks) G1(wo, m)), the photon enters the base with probability (1 - F) bound (weight
//     D t(cos_o) / bound times G1 of its refraction through m, whose mean over m is the table's t(cos_i):
//     so the record's flux times t(cos_i) and this bounce agree), else it is absorbed. Roulette and the
//     lobe in one draw; no bounce gains flux (the host keeps bound = max(D) max(t) <= 1), which the
//     fixed-point sums rely on.
// i: the material (`m` as apply_texture left it) at hit h, nf its normal facing d, front: d arrives from the
// outside; table: material_table(i) for a plastic (0: a smooth coat); plastics: whether the caller's
// surfaces include plastics (a constant: false leaves their code out). Moves the ray (o, d) on and
// multiplies w by the weight; where the path ends (absorbed, or sent below the surface) w becomes 0 and it
// returns false.
#ifndef LOBE_BOUNCE_GLSL
#define LOBE_BOUNCE_GLSL

// Whether lobe_bounce takes material `m`: the plastics, rough conductors and rough glass a scene has.
bool lobe_surface(Material m) {
    return (HAS_PLASTICS && m.surface == SURFACE_PLASTIC) || (HAS_ROUGH_CONDUCTORS && m.surface == SURFACE_ROUGH_CONDUCTOR)
        || (HAS_ROUGH_GLASS && m.surface == SURFACE_ROUGH_GLASS);
}

bool lobe_bounce(uint i, Material m, uint table, Hit h, vec3 nf, bool front, bool plastics, inout Rng rng,
                 inout vec3 o, inout vec3 d, inout vec3 w) {
    bool conductor = HAS_ROUGH_CONDUCTORS && m.surface == SURFACE_ROUGH_CONDUCTOR;
    bool glass = HAS_ROUGH_GLASS && m.surface == SURFACE_ROUGH_GLASS;
    bool plastic = plastics && !conductor && !glass;
    // A kernel whose caller has none of these surfaces holds none of this code.
    if (!plastics && !HAS_ROUGH_CONDUCTORS && !HAS_ROUGH_GLASS) return false;
    bool rough = conductor || glass || (HAS_ROUGH_PLASTICS && plastic && table != 0u);
    // The numbers, in each surface's order (above).
    float x0 = rng_float(rng);
    float x1 = rng_float(rng);
    float x2 = 0.0, x3 = 0.0, x4 = 0.0;
    if (!conductor) x2 = rng_float(rng);
    if (plastic && rough) {
        x3 = rng_float(rng);
        x4 = rng_float(rng);
    }
    // The local frame (an isotropic lobe's, and a plastic's, about nf alone: onb), the facet's normal.
    vec3 t, b;
    frame(nf, rough_tangent(i, h), t, b);
    vec3 wi = -to_local(d, t, b, nf);
    if (rough && wi.z <= 0.0) {
        w = vec3(0.0);
        return false;
    }
    Microfacet mf = hit_microfacet(i, m);
    vec3 mn = vec3(0.0, 0.0, 1.0);
    if (rough) mn = mf_sample_visible(mf, wi, conductor ? vec2(x0, x1) : glass ? vec2(x1, x2) : vec2(x3, x4));
    float cos_h = dot(wi, mn);
    // The dielectric's Fresnel term through the facet (glass, the coat; a smooth coat's as coat_fresnel).
    float eta = glass && !front ? m.ior : 1.0 / m.ior; // incident index over transmitted
    float cos_t;
    float f = fresnel_dielectric(rough ? cos_h : clamp(cos_h, 0.0, 1.0), eta, cos_t);
    // A conductor's complex index, or a plastic's ks and its base's bound.
    vec3 ta, tb;
    material_terms(i, ta, tb);
    float ks_max = max3(ta);
    float ps = conductor ? 1.0 : glass ? f : ks_max * f; // the probability of reflecting
    bool reflects = x0 < ps;
    if (plastic && !reflects && !(x0 < ps + (1.0 - f) * tb.x)) { // absorbed
        w = vec3(0.0);
        return false;
    }
    // Through the facet: its reflection, or its refraction (glass's way on, the base's entry into a coat).
    vec3 wf = reflects ? reflect(-wi, mn) : normalize(-eta * wi + (eta * cos_h - cos_t) * mn);
    float g = 1.0;
    if (rough) g = (reflects ? wf.z > 0.0 : wf.z < 0.0) ? mf_g1(mf, wf, mn) : 0.0;
    if (plastic && !reflects) {
        // Into the base: a cosine direction about nf (cosine_direction in the frame onb gave).
        float r = sqrt(x1);
        float phi = 2.0 * PI * x2;
        d = normalize(r * cos(phi) * t + r * sin(phi) * b + sqrt(max(0.0, 1.0 - x1)) * nf);
        w *= m.color * (coat_transmittance(table, dot(d, nf), m.ior) / tb.x * g);
    } else {
        if (conductor) w *= m.color * fresnel_conductor(cos_h, ta, tb) * g;
        else if (glass) w *= g;
        else w *= ta / ks_max * g;
        d = rough ? normalize(wf.x * t + wf.y * b + wf.z * nf) : reflect(d, nf);
    }
    o = offset_ray(h.pos, glass && !reflects ? -nf : nf);
    return plastic ? g > 0.0 : !(max3(w) <= 0.0);
}
#endif

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

// A bounce off rough glass is common/lobe_bounce.glsl's (for the eye paths and the photons): a normal m
// visible from wi, reflection with probability F(wi.m) or refraction through m, weight G1(wo, m).

// The tangent an anisotropic rough material i needs at hit h (frame); 0 for an isotropic one.
vec3 rough_tangent(uint i, Hit h) {
    if (!HAS_ANISOTROPY) return vec3(0.0);
    Microfacet mf = material_microfacet(i);
    return mf.au != mf.av ? surface_tangent(h) : vec3(0.0);
}

#endif

// Mitsuba's `conductor` BSDF (and ppm-vk's mirror): a specular reflector. The mirror reflects a constant
// fraction; the conductor its specular_reflectance times the unpolarised Fresnel reflectance of a metal of
// complex index eta + i k, per RGB channel (the exact formula Mitsuba's fresnel_conductor evaluates, after
// K. D. Moeller, "Optics", 1988). CPU twin: crates/materials/src/conductor.rs (its Fresnel term) and
// crates/reference/src/conductor.rs (a bounce).
#ifndef CONDUCTOR_GLSL
#define CONDUCTOR_GLSL

// A kernel compiled for one scene (SCENE_CONSTANTS) knows whether it has conductors; without them the
// Fresnel term's code is left out (lavapipe would run it under a mask on every mirror bounce).
#ifdef SCENE_CONSTANTS
#define HAS_CONDUCTORS SCENE_CONDUCTORS
#else
#define HAS_CONDUCTORS true
#endif

vec3 fresnel_conductor(float cos_i, vec3 eta, vec3 k) {
    float c2 = cos_i * cos_i;
    float s2 = 1.0 - c2;
    float s4 = s2 * s2;
    vec3 t1 = eta * eta - k * k - s2;
    vec3 a2b2 = sqrt(max(t1 * t1 + 4.0 * k * k * eta * eta, 0.0)); // a^2 + b^2
    vec3 a = sqrt(max(0.5 * (a2b2 + t1), 0.0));
    vec3 t2 = 2.0 * cos_i * a;
    vec3 rs = (a2b2 + c2 - t2) / (a2b2 + c2 + t2);
    vec3 t3 = a2b2 * c2 + s4;
    vec3 t4 = t2 * s2;
    vec3 rp = rs * (t3 - t4) / (t3 + t4);
    return 0.5 * (rs + rp);
}

bool is_reflector(uint surface) {
    return surface == SURFACE_MIRROR || (HAS_CONDUCTORS && surface == SURFACE_CONDUCTOR);
}

// What a specular bounce off material i (a reflector, `m` as material() read it) at incidence cos_i
// leaves of the throughput or flux. Reciprocal: the same for the photons and the eye paths.
vec3 reflector_weight(uint i, Material m, float cos_i) {
    if (!HAS_CONDUCTORS || m.surface == SURFACE_MIRROR) return m.color;
    vec3 eta, k;
    material_terms(i, eta, k);
    return m.color * fresnel_conductor(clamp(cos_i, 0.0, 1.0), eta, k);
}
#endif

// Mitsuba's `thindielectric`: a pane thin enough that light leaves it where it entered. It reflects with
// probability R' = 2 R / (1 + R), R the Fresnel reflectance at its face (R' sums the light reflected
// inside it any number of times), and lets light through without bending it otherwise; each branch is
// weighted by specular_reflectance (Material.color) or specular_transmittance (Material.lobe_a). The same
// from both sides. CPU twin: crates/materials/src/thin_dielectric.rs and
// crates/reference/src/thin_dielectric.rs (a branch).
#ifndef THIN_DIELECTRIC_GLSL
#define THIN_DIELECTRIC_GLSL

#ifdef SCENE_CONSTANTS
#define HAS_THIN SCENE_THIN
#else
#define HAS_THIN true
#endif

float thin_reflectance(float cos_i, float ior) {
    float cos_t;
    float r = fresnel_dielectric(min(abs(cos_i), 1.0), 1.0 / ior, cos_t);
    return r * 2.0 / (1.0 + r);
}

// One branch for the uniform number u: o and d become the new ray; returns the branch's weight. nf faces
// the incoming direction d.
vec3 thin_branch(uint i, Material m, vec3 pos, vec3 nf, float u, inout vec3 o, inout vec3 d) {
    if (u < thin_reflectance(-dot(d, nf), m.ior)) {
        d = reflect(d, nf);
        o = offset_ray(pos, nf);
        return m.color;
    }
    o = offset_ray(pos, -nf);
    return material_term_a(i);
}
#endif

// Smooth shading: a mesh's vertex normals interpolated across its triangles, and the adjoint BSDF that
// photons must use with them (Veach 1997, section 5.3). CPU twin: crates/reference/src/shading.rs.
//
// At a hit, ng is the geometric normal and ns the shading normal, both turned to the side the ray arrives
// from. Every BSDF is evaluated and sampled about ns. A direction w takes part only where it lies on the
// same side of both (shading_valid): elsewhere the BSDF about ns and the surface disagree on whether w is
// reflected or transmitted, and f is taken as 0 there, for eye paths and photons alike, so that the two
// stay adjoint. Eye paths (radiance) then need nothing more: their weight is f |wi . ns| / pdf. Photons
// carry flux per unit of geometric area, and the scattering equation integrates against |wi . ns|, so a
// photon's weight at a vertex takes Veach's correction
//     |wi . ns| |wo . ng| / (|wi . ng| |wo . ns|)     (wi: where it came from, wo: where it goes),
// a record (flux per geometric area, read by a hit point whose BRDF integrates against |wi . ns|) takes
// the first factor, shading_in, and a diffuse bounce sampled about ng (pdf |wo . ng| / pi) cancels the
// second. shading_in has no bound (a photon grazing the true surface, |wi . ng| -> 0); its expectation
// does, over photons whose density is |wi . ng|. A photon's flux is held at FLUX_CAP_FIXED fixed-point
// units (2^16 times the most a light gives one), counted in cut.capped: reaching it takes corrections
// whose product is 65536, e.g. |wi . ng| < 1.5e-5 |wi . ns| at one vertex (for light arriving evenly, a
// chance of about 6e-11 per vertex at a 30 degree tilt between ns and ng; docs/design.md).
#ifndef SHADING_GLSL
#define SHADING_GLSL
#include "materials/normal_map.glsl"

// The shading normal of hit h on the side of ng (h.normal turned towards the ray): interpolated from the
// triangle's vertex normals where it has them (triangle_texels' third texel), else ng (a sum of vertex
// normals that cancels keeps ng); then perturbed by its material's bump or normal map, where it has one.
vec3 shading_normal(Hit h, vec3 ng) {
    vec3 ns = ng;
    if (HAS_VERTEX_NORMALS && h.kind == HIT_TRIANGLE) {
        uvec4 t = texelFetch(triangle_texels, int(TRIANGLE_TEXELS * h.prim + 2u));
        if (t.w != 0u) {
            vec3 n = (1.0 - h.local.x - h.local.y) * normalize(oct_decode_unnormalized(t.x))
                   + h.local.x * normalize(oct_decode_unnormalized(t.y))
                   + h.local.y * normalize(oct_decode_unnormalized(t.z));
            float l = dot(n, n);
            if (l > 0.0) {
                n *= inversesqrt(l);
                ns = dot(n, ng) < 0.0 ? -n : n;
            }
        }
    }
    // A bump or normal map perturbs it further (normal_map.glsl).
    if (HAS_NORMAL_MAPS) ns = mapped_normal(h, ng, ns);
    return ns;
}

// Whether direction w (either way along it) lies on the same side of ng and ns.
bool shading_valid(vec3 w, vec3 ng, vec3 ns) {
    return dot(w, ng) * dot(w, ns) > 0.0;
}

// A record's factor, |wi . ns| / |wi . ng|, for a photon that arrived from wi (valid).
float shading_in(vec3 wi, vec3 ng, vec3 ns) {
    return abs(dot(wi, ns)) / abs(dot(wi, ng));
}

// The factor of a photon leaving along wo (valid): |wo . ng| / |wo . ns|.
float shading_out(vec3 wo, vec3 ng, vec3 ns) {
    return abs(dot(wo, ng)) / abs(dot(wo, ns));
}
#endif

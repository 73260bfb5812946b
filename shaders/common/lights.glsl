// The lights: emitting quads and triangles, chosen in proportion to their power
// (crates/engine/src/lower/lights.rs builds the table). photon.comp starts photons from them; ray.comp samples them for the
// direct light at its eye paths' first diffuse points. The including kernel declares, before this file,
//   layout(std430, binding = N) readonly buffer Lights { Light lights[]; };
// (read only where the lights are not compiled in, SCENE_INLINE_LIGHTS).
#ifndef LIGHTS_GLSL
#define LIGHTS_GLSL
#include "bvh.glsl"

// The light for the uniform number u: the first whose running cdf exceeds u.
#ifdef SCENE_INLINE_LIGHTS
// The lights are constants: a chain of selects, unrolled, reads no memory (a dynamically indexed constant
// array would be copied per invocation). A triangle's normal is computed from its edges as the buffer
// path below computes it (bvh_normal), so both start from the same bits.
Emitter choose_emitter(float u) {
    Emitter e = SCENE_EMITTERS[0];
    [[unroll]] for (uint i = 1u; i < NUM_LIGHTS; i++) {
        if (u >= SCENE_EMITTERS[i - 1u].cdf) e = SCENE_EMITTERS[i];
    }
    if (e.triangle) e.normal = triangle_normal(e.edge_u, e.edge_v);
    return e;
}
#else
// Binary search for the first light whose cdf exceeds u (the same light as a linear scan: cdfs never
// decrease), in ceil(log2 n) steps: scenes may have 100k emitting triangles.
Emitter choose_emitter(float u) {
    uint lo = 0u;
    uint hi = params.num_lights - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (u >= lights[mid].cdf) lo = mid + 1u; else hi = mid;
    }
    Light light = lights[lo];
    vec3 flux = light.power / light.prob;
    if (light.kind == LIGHT_TRIANGLE) {
        Triangle tr = bvh_triangle(light.index);
        return Emitter(tr.v0, tr.v1 - tr.v0, tr.v2 - tr.v0, bvh_normal(tr), flux, light.cdf, true);
    }
    Quad q = quads[light.index];
    return Emitter(q.origin, q.edge_u, q.edge_v, q.normal, flux, light.cdf, false);
}
#endif

// The point of emitter e at uniform numbers (a, b), uniform in its area: a triangle folds the unit square
// onto the half below its diagonal.
vec3 emitter_point(Emitter e, float a, float b) {
    if (e.triangle && a + b > 1.0) {
        a = 1.0 - a;
        b = 1.0 - b;
    }
    return e.origin + a * e.edge_u + b * e.edge_v;
}
#endif

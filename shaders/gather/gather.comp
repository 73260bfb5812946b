// Pass 4, gather: for each hit point, the photons of this batch inside its sphere of radius R that arrive
// from the side it is seen from. M counts them; tau_M sums their flux, times the cone filter's weight
// w = 1 - d / (k R) when the filter is on (eq. 10, 12-13). Sums go into PassAccum in fixed point, so the
// result does not depend on the order of photons in a bucket.
//
// Threads walk `order`, the non-empty hit-point slots sorted along a Morton curve, so the lanes of a
// subgroup read the same buckets.
#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 64) in;
#include "types.glsl"
#include "params.glsl"
layout(std430, binding = 1) readonly buffer HitPoints { HitPoint hit_points[]; };
layout(std430, binding = 2) readonly buffer Stats { HitStats stats[]; };
layout(std430, binding = 3) buffer Accum { PassAccum accum[]; };
layout(std430, binding = 4) readonly buffer Sorted { Photon sorted[]; };   // records grouped by bucket
layout(std430, binding = 5) readonly buffer CellStart { uint cell_start[]; };
layout(std430, binding = 6) readonly buffer Order { uint order[]; };
layout(push_constant) uniform GatherPush {
    uint count;      // entries of `order`
    float cone_k;    // cone filter constant k >= 1; 0: off
} pc;
#include "neighbours.glsl"
#include "invocation.glsl"

// This invocation's sums over the visited photons.
uint m = 0u;
int64_t fr = 0L, fg = 0L, fb = 0L;
float inv_kr;
float flux_fixed; // params.flux_fixed, read once: a storage-buffer read per photon costs lavapipe a gather

void visit(vec3 flux, float d2) {
    // eq. 10; the weight folds into the fixed-point scale, and without the filter no root is taken.
    float scale = inv_kr > 0.0 ? (1.0 - sqrt(d2) * inv_kr) * flux_fixed : flux_fixed;
    ivec3 f = ivec3(flux * scale + 0.5); // round to nearest: flux and weight are never negative
    m++;
    fr += int64_t(f.r);
    fg += int64_t(f.g);
    fb += int64_t(f.b);
}

void main() {
    load_params();
    uint t = invocation_index();
    if (t >= pc.count) return;
    uint i = order[t];
    HitPoint hp = hit_points[i];
    if (hp.pixel == 0xffffffffu) return; // SPPM: this pass's eye path found no diffuse surface
    float r2 = float(stats[i].r2);
    flux_fixed = params.flux_fixed;
    inv_kr = pc.cone_k > 0.0 ? 1.0 / (pc.cone_k * sqrt(r2)) : 0.0;
    for_each_photon_near(hp.pos, hp.normal, r2);
    if (m > 0u) {
        accum[i].m += m;
        accum[i].flux_r += fr;
        accum[i].flux_g += fg;
        accum[i].flux_b += fb;
    }
}

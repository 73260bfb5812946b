// Pass 4, gather: for each hit point, the photons of this batch inside its sphere of radius R that arrive
// from the side it is seen from. M counts them; tau_M sums their flux, times the cone filter's weight
// w = 1 - d / (k R) when the filter is on (eq. 10, 12-13). Sums go into PassAccum in fixed point, so the
// result does not depend on the order of photons in a bucket.
#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 64) in;
#include "types.glsl"
layout(std430, binding = 0) readonly buffer Params { RenderParams params; };
layout(std430, binding = 1) readonly buffer HitPoints { HitPoint hit_points[]; };
layout(std430, binding = 2) readonly buffer Stats { HitStats stats[]; };
layout(std430, binding = 3) buffer Accum { PassAccum accum[]; };
layout(std430, binding = 4) readonly buffer Photons { Photon photons[]; };
layout(std430, binding = 5) readonly buffer Sorted { uint sorted[]; };
layout(std430, binding = 6) readonly buffer CellStart { uint cell_start[]; };
layout(push_constant) uniform GatherPush {
    uint slots;      // hit-point slots
    float cone_k;    // cone filter constant k >= 1; 0: off
} pc;
#include "grid.glsl"
#include "sampling.glsl"
#include "invocation.glsl"

void main() {
    uint i = invocation_index();
    if (i >= pc.slots) return;
    HitPoint hp = hit_points[i];
    if (hp.pixel == 0xffffffffu) return;
    float r2 = float(stats[i].r2);
    float r = sqrt(r2);
    ivec3 lo = grid_cell(hp.pos - vec3(r));
    ivec3 hi = grid_cell(hp.pos + vec3(r));
    // cell_size >= 2 R_max, so at most 2 cells per axis; buckets already visited are skipped, since two
    // cells may share a bucket.
    uint seen[8];
    uint nseen = 0u;
    uint m = 0u;
    int64_t fr = 0L, fg = 0L, fb = 0L;
    for (int z = lo.z; z <= hi.z; z++)
    for (int y = lo.y; y <= hi.y; y++)
    for (int x = lo.x; x <= hi.x; x++) {
        uint h = grid_hash(ivec3(x, y, z));
        bool dup = false;
        for (uint s = 0u; s < nseen; s++) dup = dup || seen[s] == h;
        if (dup || nseen == 8u) continue;
        seen[nseen++] = h;
        for (uint k = cell_start[h]; k < cell_start[h + 1u]; k++) {
            Photon p = photons[sorted[k]];
            vec3 dv = p.pos - hp.pos;
            float d2 = dot(dv, dv);
            if (d2 > r2) continue;
            // The BRDF is zero for light arriving from behind the surface (ALGORITHM.md).
            if (dot(oct_decode(p.dir), hp.normal) >= 0.0) continue;
            float w = pc.cone_k > 0.0 ? 1.0 - sqrt(d2) / (pc.cone_k * r) : 1.0; // eq. 10
            m++;
            fr += int64_t(double(p.flux.r * w) * FIXED_ONE);
            fg += int64_t(double(p.flux.g * w) * FIXED_ONE);
            fb += int64_t(double(p.flux.b * w) * FIXED_ONE);
        }
    }
    if (m > 0u) {
        accum[i].m += m;
        accum[i].flux_r += fr;
        accum[i].flux_g += fg;
        accum[i].flux_b += fb;
    }
}

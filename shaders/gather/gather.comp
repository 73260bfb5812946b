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
layout(std430, binding = 0) readonly buffer Params { RenderParams params; };
layout(std430, binding = 1) readonly buffer HitPoints { HitPoint hit_points[]; };
layout(std430, binding = 2) readonly buffer Stats { HitStats stats[]; };
layout(std430, binding = 3) buffer Accum { PassAccum accum[]; };
layout(std430, binding = 4) readonly buffer Photons { Photon photons[]; };
layout(std430, binding = 5) readonly buffer Sorted { uint sorted[]; };
layout(std430, binding = 6) readonly buffer CellStart { uint cell_start[]; };
layout(std430, binding = 7) readonly buffer Order { uint order[]; };
layout(push_constant) uniform GatherPush {
    uint count;      // entries of `order`
    float cone_k;    // cone filter constant k >= 1; 0: off
} pc;
#include "grid.glsl"
#include "invocation.glsl"

void main() {
    uint t = invocation_index();
    if (t >= pc.count) return;
    uint i = order[t];
    HitPoint hp = hit_points[i];
    float r2 = float(stats[i].r2);
    float r = sqrt(r2);
    ivec3 lo = grid_cell(hp.pos - vec3(r));
    ivec3 hi = grid_cell(hp.pos + vec3(r));
    float inv_kr = pc.cone_k > 0.0 ? 1.0 / (pc.cone_k * r) : 0.0;
    uint m = 0u;
    int64_t fr = 0L, fg = 0L, fb = 0L;
    // cell_size >= 2 R_max: at most 2 cells per axis.
    for (int z = lo.z; z <= hi.z; z++)
    for (int y = lo.y; y <= hi.y; y++)
    for (int x = lo.x; x <= hi.x; x++) {
        ivec3 c = ivec3(x, y, z);
        uint h = grid_hash(c);
        for (uint k = cell_start[h]; k < cell_start[h + 1u]; k++) {
            Photon p = photons[sorted[k]];
            vec3 dv = p.pos - hp.pos;
            float d2 = dot(dv, dv);
            if (d2 > r2) continue;
            // Two cells may share a bucket: count a photon only from its own cell.
            if (grid_cell(p.pos) != c) continue;
            // The BRDF is zero for light arriving from behind the surface (ALGORITHM.md). Only the sign
            // matters, so the octahedral direction needs no normalising.
            vec2 e = unpackSnorm2x16(p.dir);
            vec3 dir = vec3(e, 1.0 - abs(e.x) - abs(e.y));
            if (dir.z < 0.0) dir.xy = (1.0 - abs(dir.yx)) * vec2(dir.x >= 0.0 ? 1.0 : -1.0, dir.y >= 0.0 ? 1.0 : -1.0);
            if (dot(dir, hp.normal) >= 0.0) continue;
            float w = 1.0 - sqrt(d2) * inv_kr; // eq. 10 (w = 1 without the filter)
            m++;
            fr += int64_t(p.flux.r * w * FIXED_ONE);
            fg += int64_t(p.flux.g * w * FIXED_ONE);
            fb += int64_t(p.flux.b * w * FIXED_ONE);
        }
    }
    if (m > 0u) {
        accum[i].m += m;
        accum[i].flux_r += fr;
        accum[i].flux_g += fg;
        accum[i].flux_b += fb;
    }
}

// Pass 4, gather: for each hit point, the photons of this batch inside its sphere of radius R that arrive
// from the side it is seen from. M counts them; tau_M sums their flux, times the cone filter's weight
// w = 1 - d / (k R) when the filter is on (eq. 10, 12-13), and on a glossy hit point (HitPoint.brdf)
// times its BRDF for the photon's direction over the bound its weight holds (rough_conductor_ratio). Sums go into PassAccum in fixed point, so the
// result does not depend on the order of photons in a bucket.
//
// Each thread takes GROUP consecutive entries of `order`, the non-empty hit-point slots sorted along a
// Morton curve, so a thread's hit points are usually neighbours and share the photons they read
// (neighbours.glsl), and the lanes of a subgroup read the same buckets.
#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 64) in;
#include "types.glsl"
#include "params.glsl"
layout(std430, binding = 1) readonly buffer HitPoints { HitPoint hit_points[]; };
layout(std430, binding = 2) readonly buffer Stats { HitStats stats[]; };
layout(std430, binding = 3) buffer Accum { PassAccum accum[]; };
// Photons grouped by bucket, as texels: (position, cell key), (flux, direction) (neighbours.glsl).
layout(binding = 4) uniform usamplerBuffer sorted_texels;
layout(std430, binding = 5) readonly buffer CellStart { uint cell_start[]; };
layout(std430, binding = 6) readonly buffer Order { uint order[]; };
layout(std430, binding = 7) writeonly buffer Status { uint lookup_status; }; // 1: a lookup was cut short
// The materials (bindings.glsl's table), for the BRDFs of glossy hit points.
layout(binding = 8) uniform usamplerBuffer material_texels;
// Whether the scene has glossy hit points: the renderer compiles the gather with 0 where it has none, since
// lavapipe would evaluate the BRDF for every photon under a mask (3x the gather's time on cornell-spheres).
#ifndef GLOSSY_HITS
#define GLOSSY_HITS 1
#endif
// Whether a photon may carry more than a light gives one (smooth shading: shading.glsl), up to
// FLUX_CAP_FIXED units, past an int32: then such a photon converts to int64 (not a vector instruction on
// AVX2, so only those photons take it). Compiled with 0 where no mesh is smooth-shaded.
#ifndef WIDE_FLUX
#define WIDE_FLUX 1
#endif
layout(push_constant) uniform GatherPush {
    uint count;      // entries of `order`
    float cone_k;    // cone filter constant k >= 1; 0: off
} pc;
#include "neighbours.glsl"
#include "invocation.glsl"
#include "materials.glsl"
#include "materials/conductor.glsl"
#include "materials/rough_conductor.glsl"

// Each member's sums over the photons it received, and the count of those within R / 2 (update.comp's
// curvature statistic).
uint m[GROUP];
uint m_half[GROUP];
int64_t fr[GROUP], fg[GROUP], fb[GROUP];
float inv_kr[GROUP];
uint q_brdf[GROUP];  // HitPoint.brdf: 0, or 1 + a rough conductor's material
#if GLOSSY_HITS
RoughView q_view[GROUP]; // its BRDF towards the eye, where q_brdf != 0
#endif
float flux_fixed; // params.flux_fixed, read once: a storage-buffer read per photon costs lavapipe a gather

void visit(uint j, vec3 flux, vec3 dir, float d2) {
#if GLOSSY_HITS
    if (q_brdf[j] != 0u) flux *= rough_conductor_ratio(q_view[j], -normalize(dir), q_normal[j]);
#endif
    // eq. 10; the weight folds into the fixed-point scale, and without the filter no root is taken.
    float scale = inv_kr[j] > 0.0 ? (1.0 - sqrt(d2) * inv_kr[j]) * flux_fixed : flux_fixed;
    vec3 v = flux * scale + 0.5; // round to nearest: flux and weight are never negative
    m[j]++;
    if (d2 <= 0.25 * q_r2[j]) m_half[j]++;
#if WIDE_FLUX
    if (max(v.r, max(v.g, v.b)) >= 2147483520.0) { // the largest f32 below 2^31
        i64vec3 w = i64vec3(min(v, vec3(FLUX_CAP_FIXED)));
        fr[j] += w.r;
        fg[j] += w.g;
        fb[j] += w.b;
        return;
    }
#endif
    ivec3 f = ivec3(v);
    fr[j] += int64_t(f.r);
    fg[j] += int64_t(f.g);
    fb[j] += int64_t(f.b);
}

void main() {
    load_params();
    uint first = invocation_index() * GROUP;
    if (first >= pc.count) return;
    flux_fixed = params.flux_fixed;
    uint slot[GROUP];
    [[unroll]] for (uint j = 0u; j < GROUP; j++) {
        m[j] = 0u;
        m_half[j] = 0u;
        fr[j] = 0L;
        fg[j] = 0L;
        fb[j] = 0L;
        q_r2[j] = -1.0;
        inv_kr[j] = 0.0;
        q_brdf[j] = 0u;
        slot[j] = first + j < pc.count ? order[first + j] : 0xffffffffu;
        if (slot[j] == 0xffffffffu) continue;
        HitPoint hp = hit_points[slot[j]];
        if (hp.pixel == 0xffffffffu) continue; // SPPM: this pass's eye path found no diffuse surface
        q_pos[j] = hp.pos;
        q_normal[j] = hp.normal;
        q_brdf[j] = hp.brdf;
#if GLOSSY_HITS
        if (hp.brdf != 0u) q_view[j] = rough_view(hp.brdf - 1u, normalize(oct_decode_unnormalized(hp.wo)), hp.normal);
#endif
        q_r2[j] = float(stats[slot[j]].r2);
        if (pc.cone_k > 0.0) inv_kr[j] = 1.0 / (pc.cone_k * sqrt(q_r2[j]));
    }
    for_each_photon_near_group();
    if (lookup_may_be_cut()) lookup_status = 1u;
    [[unroll]] for (uint j = 0u; j < GROUP; j++) {
        if (m[j] == 0u) continue;
        uint i = slot[j];
        accum[i].m += m[j];
        accum[i].m_half += m_half[j];
        accum[i].flux_r += fr[j];
        accum[i].flux_g += fg[j];
        accum[i].flux_b += fb[j];
    }
}

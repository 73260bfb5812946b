// The progressive update after a photon pass (eq. 3 and 6; with the cone filter the weighted sums of
// eq. 12-13 stand in for tau, and eq. 14 is the same ratio), then clears the pass accumulators.
// A hit point that received no photon is left as it is. tau carries the eye path's weight w f_r: for
// PPM's fixed hit points that equals weighting at the resolve, and SPPM's hit point changes every pass.
// It also leaves the largest R^2 (as the f32 the lookups read) for the renderer to size the next pass's
// grid cells by (Renderer::fit_grid): over the hit points live this pass, and over every slot.
#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_KHR_shader_subgroup_arithmetic : require
layout(local_size_x = 64) in;
#include "types.glsl"
layout(std430, binding = 0) buffer Stats { HitStats stats[]; };
layout(std430, binding = 1) buffer Accum { PassAccum accum[]; };
layout(std430, binding = 2) readonly buffer Order { uint order[]; };
layout(std430, binding = 3) readonly buffer HitPoints { HitPoint hit_points[]; };
// f32 bits of the largest R^2: [0] over the hit points live this pass, [1] over all slots. Non-negative
// floats order as their bits do, so an integer max is the float max. Zeroed before the update.
layout(std430, binding = 4) buffer RadiusMax { uint r2_max_bits[2]; };
layout(push_constant) uniform UpdatePush {
    uint count;      // entries of `order` (the non-empty hit-point slots)
    float alpha;     // the fraction of new photons kept, in (0, 1)
    float flux_fixed; // RenderParams.flux_fixed
    uint pad0;
} pc;
#include "invocation.glsl"

HitStats updated(uint i, PassAccum a, HitStats s) {
    double m = double(a.m);
    double ratio = (s.n + double(pc.alpha) * m) / (s.n + m);
    s.r2 *= ratio;                                                   // eq. 3 (squared)
    dvec3 w = dvec3(hit_points[i].weight) / double(pc.flux_fixed); // fixed-point scale: a power of two
    s.tau_r = (s.tau_r + double(a.flux_r) * w.r) * ratio; // eq. 6 / eq. 14
    s.tau_g = (s.tau_g + double(a.flux_g) * w.g) * ratio;
    s.tau_b = (s.tau_b + double(a.flux_b) * w.b) * ratio;
    s.n += double(pc.alpha) * m;
    return s;
}

// Folds this lane's R^2 into the maxima with one atomic per subgroup.
void note_radius(float r2, bool live) {
    float all_max = subgroupMax(r2);
    float live_max = subgroupMax(live ? r2 : 0.0);
    if (subgroupElect()) {
        atomicMax(r2_max_bits[0], floatBitsToUint(live_max));
        atomicMax(r2_max_bits[1], floatBitsToUint(all_max));
    }
}

void main() {
    uint t = invocation_index();
    float r2 = 0.0;
    bool live = false;
    if (t < pc.count) {
        uint i = order[t];
        PassAccum a = accum[i];
        HitStats s = stats[i];
        if (a.m != 0u) {
            s = updated(i, a, s);
            stats[i] = s;
            accum[i] = PassAccum(0L, 0L, 0L, 0u, 0u);
        }
        r2 = float(s.r2);
        live = hit_points[i].pixel != 0xffffffffu; // SPPM: this pass's eye path found a diffuse surface
    }
    note_radius(r2, live);
}

// The progressive update after a photon pass (eq. 3 and 6; with the cone filter the weighted sums of
// eq. 12-13 stand in for tau, and eq. 14 is the same ratio), then clears the pass accumulators.
// A hit point that received no photon is left as it is. tau carries the eye path's weight w f_r: for
// PPM's fixed hit points that equals weighting at the resolve, and SPPM's hit point changes every pass.
#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 64) in;
#include "types.glsl"
layout(std430, binding = 0) buffer Stats { HitStats stats[]; };
layout(std430, binding = 1) buffer Accum { PassAccum accum[]; };
layout(std430, binding = 2) readonly buffer Order { uint order[]; };
layout(std430, binding = 3) readonly buffer HitPoints { HitPoint hit_points[]; };
layout(push_constant) uniform UpdatePush {
    uint count;      // entries of `order` (the non-empty hit-point slots)
    float alpha;     // the fraction of new photons kept, in (0, 1)
    float flux_fixed; // RenderParams.flux_fixed
    uint pad0;
} pc;
#include "invocation.glsl"

void main() {
    uint t = invocation_index();
    if (t >= pc.count) return;
    uint i = order[t];
    PassAccum a = accum[i];
    if (a.m == 0u) return;
    HitStats s = stats[i];
    double m = double(a.m);
    double ratio = (s.n + double(pc.alpha) * m) / (s.n + m);
    s.r2 *= ratio;                                                   // eq. 3 (squared)
    dvec3 w = dvec3(hit_points[i].weight) / double(pc.flux_fixed); // fixed-point scale: a power of two
    s.tau_r = (s.tau_r + double(a.flux_r) * w.r) * ratio; // eq. 6 / eq. 14
    s.tau_g = (s.tau_g + double(a.flux_g) * w.g) * ratio;
    s.tau_b = (s.tau_b + double(a.flux_b) * w.b) * ratio;
    s.n += double(pc.alpha) * m;
    stats[i] = s;
    accum[i] = PassAccum(0L, 0L, 0L, 0u, 0u);
}

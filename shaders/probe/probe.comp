// Pass 2, photon probing (run once, after the ray pass): how spread out the probe photons inside each hit
// point's sphere are (eq. 7), and from that its starting radius (eq. 9). Two phases, by push constant:
//   0: per batch of probe photons, add to the hit point's accumulator the count N and the sum of d^2 / r^2
//      of the photons inside its sphere of radius r (arriving from the side it is seen from), in 2.30
//      fixed point: exact, order-independent, and in units of r^2 so it does not depend on the scene's scale;
//   1: lambda / r^2 = sum / N (eq. 7; no photon counts as sparse: lambda = r^2), then
//      paper (mode 1):      r' = r                  if lambda / r <= beta, else r (1 + lambda / r)    (eq. 9)
//      scale-free (mode 2): r' = r                  if lambda / r <= beta, else r (1 + lambda / r^2)
//      with beta = beta_frac * r, so the test is lambda / r^2 <= beta_frac in both;
//      nearest (mode 3):    r' = r min(sqrt(k / N), 2), N the probe photons within r (none: 2 r): the
//      radius that would hold k of them at the density they have within r, as classic photon mapping
//      gathers its k nearest photons. Free of units (a ratio of counts), it shrinks radii where photons
//      crowd (a caustic) and grows them where they are few, as far as the scale-free rule's most (2 r:
//      larger radii make every lookup span more grid cells, whose size the largest radius sets). SPPM's
//      update (eq. 3) shrinks every radius from there on, so the estimate stays consistent.
//      Stores r'^2 and lambda / r^2 (HitStats.probe), and clears the accumulator.
#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 64) in;
#include "types.glsl"
#include "params.glsl"
layout(std430, binding = 1) readonly buffer HitPoints { HitPoint hit_points[]; };
layout(std430, binding = 2) buffer Stats { HitStats stats[]; };
layout(std430, binding = 3) buffer Accum { PassAccum accum[]; };
// Photons grouped by bucket, as texels: (position, cell key), (flux, direction) (neighbours.glsl).
layout(binding = 4) uniform usamplerBuffer sorted_texels;
layout(std430, binding = 5) readonly buffer CellStart { uint cell_start[]; };
layout(std430, binding = 6) readonly buffer Order { uint order[]; };
layout(std430, binding = 7) writeonly buffer Status { uint lookup_status; }; // 1: a lookup was cut short
layout(push_constant) uniform ProbePush {
    uint count;      // entries of `order`
    uint phase;
    uint mode;       // 1 paper, 2 scale-free, 3 nearest
    float param;     // modes 1, 2: beta as a fraction of r (the paper's best: 1/5); mode 3: k
} pc;
#include "neighbours.glsl"
#include "invocation.glsl"

// Each member's count and fixed-point sum of d^2 / r^2.
uint m[GROUP];
int64_t sum[GROUP];
float inv_r2[GROUP];

void visit(uint j, vec3 flux, vec3 dir, float d2) {
    m[j]++;
    sum[j] += int64_t(int(d2 * inv_r2[j] * PROBE_FIXED + 0.5)); // eq. 7's |t_p - g|^2, in units of r^2
}

// Phase 1, one thread per hit point. An empty slot (in SPPM, a pixel whose first eye path saw the light or
// died in glass) has no hit point whose density could be probed: it keeps r. (The sparse rule, lambda = r^2,
// is for hit points no probe photon reached.)
void set_radius(uint i) {
    if (hit_points[i].pixel == 0xffffffffu) return;
    HitStats s = stats[i];
    PassAccum a = accum[i];
    // eq. 7, in units of r^2; a hit point no probe photon reached is sparse (../shared/paper/ALGORITHM.md)
    double ratio = a.m > 0u ? double(a.flux_r) / double(PROBE_FIXED) / double(a.m) : 1.0;
    double r = sqrt(s.r2);
    double grow = 1.0;
    if (pc.mode == 3u) {
        grow = a.m > 0u ? min(sqrt(double(pc.param) / double(a.m)), 2.0) : 2.0;
    } else if (ratio > double(pc.param)) {
        double lambda = ratio * s.r2;
        grow = pc.mode == 1u ? 1.0 + lambda / r   // eq. 9 as printed: adds an area to a length
                             : 1.0 + ratio;       // the scale-free variant
    }
    s.r2 *= grow * grow;
    s.probe = ratio;
    stats[i] = s;
    accum[i] = PassAccum(0L, 0L, 0L, 0u, 0u);
}

void main() {
    load_params();
    uint t = invocation_index();
    if (pc.phase == 1u) {
        if (t < pc.count) set_radius(order[t]);
        return;
    }
    // Phase 0, one thread per GROUP hit points (neighbours.glsl).
    uint first = t * GROUP;
    if (first >= pc.count) return;
    uint slot[GROUP];
    [[unroll]] for (uint j = 0u; j < GROUP; j++) {
        m[j] = 0u;
        sum[j] = 0L;
        q_r2[j] = -1.0;
        slot[j] = first + j < pc.count ? order[first + j] : 0xffffffffu;
        if (slot[j] == 0xffffffffu) continue;
        HitPoint hp = hit_points[slot[j]];
        if (hp.pixel == 0xffffffffu) continue;
        q_pos[j] = hp.pos;
        q_normal[j] = hp.normal;
        q_r2[j] = float(stats[slot[j]].r2);
        inv_r2[j] = 1.0 / q_r2[j];
    }
    for_each_photon_near_group();
    if (lookup_may_be_cut()) lookup_status = 1u;
    [[unroll]] for (uint j = 0u; j < GROUP; j++) {
        if (m[j] == 0u) continue;
        accum[slot[j]].m += m[j];
        accum[slot[j]].flux_r += sum[j];
    }
}

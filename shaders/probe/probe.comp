// Pass 2, photon probing (run once, after the ray pass): how spread out the probe photons inside each hit
// point's sphere are (eq. 7), and from that its starting radius (eq. 9). Two phases, by push constant:
//   0: per batch of probe photons, add to the hit point's accumulator the count N and the sum of d^2 / r^2
//      of the photons inside its sphere of radius r (arriving from the side it is seen from), in 2.30
//      fixed point: exact, order-independent, and in units of r^2 so it does not depend on the scene's scale;
//   1: lambda / r^2 = sum / N (eq. 7; no photon counts as sparse: lambda = r^2), then
//      paper (mode 1):      r' = r                  if lambda / r <= beta, else r (1 + lambda / r)    (eq. 9)
//      scale-free (mode 2): r' = r                  if lambda / r <= beta, else r (1 + lambda / r^2)
//      with beta = beta_frac * r, so the test is lambda / r^2 <= beta_frac in both. Stores r'^2 and
//      lambda / r^2 (HitStats.probe), and clears the accumulator.
#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 64) in;
#include "types.glsl"
#include "params.glsl"
layout(std430, binding = 1) readonly buffer HitPoints { HitPoint hit_points[]; };
layout(std430, binding = 2) buffer Stats { HitStats stats[]; };
layout(std430, binding = 3) buffer Accum { PassAccum accum[]; };
layout(std430, binding = 4) readonly buffer Sorted { Photon sorted[]; };
layout(std430, binding = 5) readonly buffer CellStart { uint cell_start[]; };
layout(std430, binding = 6) readonly buffer Order { uint order[]; };
layout(push_constant) uniform ProbePush {
    uint count;      // entries of `order`
    uint phase;
    uint mode;       // 1 paper, 2 scale-free
    float beta_frac; // beta as a fraction of r (the paper's best: 1/5)
} pc;
#include "neighbours.glsl"
#include "invocation.glsl"

uint m = 0u;
int64_t sum = 0L;
float inv_r2;

void visit(vec3 flux, float d2) {
    m++;
    sum += int64_t(int(d2 * inv_r2 * PROBE_FIXED + 0.5)); // eq. 7's |t_p - g|^2, in units of r^2
}

void main() {
    load_params();
    uint t = invocation_index();
    if (t >= pc.count) return;
    uint i = order[t];
    HitStats s = stats[i];
    if (pc.phase == 1u) {
        PassAccum a = accum[i];
        // eq. 7, in units of r^2; a hit point no probe photon reached is sparse (ALGORITHM.md)
        double ratio = a.m > 0u ? double(a.flux_r) / double(PROBE_FIXED) / double(a.m) : 1.0;
        double r = sqrt(s.r2);
        double grow = 1.0;
        if (ratio > double(pc.beta_frac)) {
            double lambda = ratio * s.r2;
            grow = pc.mode == 1u ? 1.0 + lambda / r   // eq. 9 as printed: adds an area to a length
                                 : 1.0 + ratio;       // the scale-free variant
        }
        s.r2 *= grow * grow;
        s.probe = ratio;
        stats[i] = s;
        accum[i] = PassAccum(0L, 0L, 0L, 0u, 0u);
        return;
    }
    HitPoint hp = hit_points[i];
    if (hp.pixel == 0xffffffffu) return;
    float r2 = float(s.r2);
    inv_r2 = 1.0 / r2;
    for_each_photon_near(hp.pos, hp.normal, r2);
    if (m > 0u) {
        accum[i].m += m;
        accum[i].flux_r += sum;
    }
}

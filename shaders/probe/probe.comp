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
//      curvature (mode 4):  the radius that minimises the density estimate's error, bias^2 + variance
//      (after Kaplanyan and Dachsbacher 2013, adaptive PPM). Over a disc of radius p a density f with
//      Laplacian L holds N(p) = pi p^2 f + pi p^4 L / 8 photons, so Na within R and Nb within R / 2 give
//      L = 32 (Na - 4 Nb) / (3 pi R^4) and f ~ Na / (pi R^2); the estimate N(p) / (pi p^2) has bias
//      p^2 L / 8 and variance f / (pi p^2), whose sum is least at p^6 = 32 f / (pi L^2), that is
//          (p / R)^6 = 9 Na / (32 D^2),  D = Na - 4 Nb       (curvature_fit),
//      a ratio of counts, so free of units. D is noisy (variance Na + 8 Nb): only the part of |D| beyond
//      CURVATURE_Z of its standard deviations counts, so a flat density (D ~ 0) reads as flat. The probe
//      looks as far as 2 r and fits at two scales, R = r (counts within r and r / 2) and R = 2 r (within
//      2 r and r), and takes the smaller radius: a radius grows (to at most 2 r) only where the density is
//      flat out to 2 r, so it never reaches over a caustic's edge it could not see from r, and shrinks (to
//      at least r / 8) where either scale finds a significant curvature (a caustic, a light's falloff).
//      pc.param (Settings::probe_grow, 1 to 2) caps the growth: 1 only ever shrinks.
//      The counts within r / 2 and 2 r go in the accumulator's flux_g and flux_b.
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
    uint mode;       // 1 paper, 2 scale-free, 3 nearest, 4 curvature
    float param;     // modes 1, 2: beta as a fraction of r (the paper's best: 1/5); mode 3: k; mode 4: the largest r' / r
} pc;
#include "neighbours.glsl"
#include "invocation.glsl"

// Mode 4: the standard deviations of noise in D that a curvature must exceed to count (2: a flat density
// reads as curved at one scale at under 2.3% of hit points), and the least r' / r it may set.
const double CURVATURE_Z = 2.0;
const double CURVATURE_MIN = 0.125;

// Each member's count within r, within r / 2 and between r and 2 r (mode 4, which looks up to 2 r), and
// fixed-point sum of d^2 / r^2 within r.
uint m[GROUP];
uint m_half[GROUP];
uint m_ring[GROUP];
int64_t sum[GROUP];
float inv_r2[GROUP];
float r2_in[GROUP];

void visit(uint j, vec3 flux, vec3 dir, float d2) {
    if (d2 > r2_in[j]) { // mode 4's ring; never in the other modes, which look up to r
        m_ring[j]++;
        return;
    }
    m[j]++;
    if (d2 * inv_r2[j] <= 0.25) m_half[j]++;
    sum[j] += int64_t(int(d2 * inv_r2[j] * PROBE_FIXED + 0.5)); // eq. 7's |t_p - g|^2, in units of r^2
}

// (p / R)^6 = 9 Na / (32 D^2) (the header), as p / R and at most 2; 2 where D is not significant.
double curvature_fit(double na, double nb) {
    double d = max(abs(na - 4.0 * nb) - CURVATURE_Z * sqrt(na + 8.0 * nb), 0.0);
    // 9 Na / (32 D^2) < 64 <=> 9 Na < 2048 D^2 (false where d = 0: flat, or no photon)
    return 9.0 * na < 2048.0 * d * d ? double(pow(float(9.0 * na / (32.0 * d * d)), 1.0 / 6.0)) : 2.0;
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
    } else if (pc.mode == 4u) {
        double n_half = double(a.flux_g), n1 = double(a.m), n_two = double(a.flux_b);
        grow = clamp(min(curvature_fit(n1, n_half), 2.0 * curvature_fit(n_two, n1)), CURVATURE_MIN, double(pc.param));
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
        m_half[j] = 0u;
        m_ring[j] = 0u;
        sum[j] = 0L;
        q_r2[j] = -1.0;
        slot[j] = first + j < pc.count ? order[first + j] : 0xffffffffu;
        if (slot[j] == 0xffffffffu) continue;
        HitPoint hp = hit_points[slot[j]];
        if (hp.pixel == 0xffffffffu) continue;
        q_pos[j] = hp.pos;
        q_normal[j] = hp.normal;
        r2_in[j] = float(stats[slot[j]].r2);
        inv_r2[j] = 1.0 / r2_in[j];
        q_r2[j] = pc.mode == 4u ? 4.0 * r2_in[j] : r2_in[j]; // the lookup's radius: 2 r in mode 4
    }
    for_each_photon_near_group();
    if (lookup_may_be_cut()) lookup_status = 1u;
    [[unroll]] for (uint j = 0u; j < GROUP; j++) {
        if (m[j] + m_ring[j] == 0u) continue;
        accum[slot[j]].m += m[j];
        accum[slot[j]].flux_r += sum[j];
        accum[slot[j]].flux_g += int64_t(m_half[j]);
        accum[slot[j]].flux_b += int64_t(m[j] + m_ring[j]);
    }
}

// The progressive update after a photon pass (eq. 3 and 6; with the cone filter the weighted sums of
// eq. 12-13 stand in for tau, and eq. 14 is the same ratio), then the adaptive shrink (shrunk()), then
// clears the pass accumulators.
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
    float shrink_z;  // the adaptive shrink's significance in standard deviations; 0: off
    float r2_floor;  // the least R^2 the adaptive shrink sets (SHRINK_FLOOR of the starting radius, squared)
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
    // The curvature statistic (shrunk()): D = M - 4 M_half ~ R^4, Var D = M + 8 M_half ~ R^2
    s.curv = (s.curv + (m - 4.0 * double(a.m_half))) * ratio * ratio;
    s.curv_var = (s.curv_var + (m + 8.0 * double(a.m_half))) * ratio;
    return s;
}

// The adaptive shrink (pc.shrink_z > 0): probe.comp's curvature fit (mode 4), (p / R)^6 = 9 N / (32 D^2),
// taken again after every pass over the photons gathered so far instead of once over the probe's, so a
// caustic the probe could not resolve (or one it shrank towards but not enough, where the density is not
// the quadratic the fit assumes) is found as photons arrive. N is the accumulated count itself; D and its
// Poisson variance are summed the same way (updated(): D scales as R^4, its variance as R^2, under the
// fit's quadratic density), so the fit weighs the estimate tau / (pi R^2) the passes have built. Only the
// part of |D| beyond shrink_z standard deviations counts (a flat density reads as flat); where the fit's p
// is below R, R^2 takes (p / R)^2, D scales as R^4, and N, tau and D's variance keep what the fit's
// density puts within p (more than the area's share at a peak, less in a dip; docs/design.md), and the
// next fit starts at p.
// Radii only ever shrink here, so eq. 3's consistency stands; a flat density reaches the threshold only by
// noise (then a mild shrink of an unbiased estimate), and the images of scenes without narrow caustics
// barely move (docs/accuracy.md).
// SHRINK_MIN: the least factor on R^2 in one pass (R halves at most), so one noisy pass cannot collapse a
// radius; a caustic that needs more takes further passes, which only delays the shrink. pc.r2_floor: the
// shrink stops at 1e-4 of the starting radius (renderer.rs's SHRINK_FLOOR), where f32 positions would
// soon stop telling photons apart; below it eq. 3 alone shrinks the radius, so a caustic narrower than
// that (a point focus) is blurred over it, never turned to a zero radius.
const double SHRINK_MIN = 0.25;

// Cube root in f64 (GLSL has no f64 pow): f32's, then two Newton steps (each squares the relative error).
double cbrt_f64(double x) {
    double y = double(pow(float(x), 1.0 / 3.0));
    y -= (y * y * y - x) / (3.0 * y * y);
    y -= (y * y * y - x) / (3.0 * y * y);
    return y;
}

HitStats shrunk(HitStats s) {
    double d = max(abs(s.curv) - double(pc.shrink_z) * sqrt(s.curv_var), 0.0);
    if (!(9.0 * s.n < 32.0 * d * d)) return s; // p >= R (or no significant curvature)
    double x = 9.0 * s.n / (32.0 * d * d); // (p / R)^6, in (0, 1)
    double t = x > SHRINK_MIN * SHRINK_MIN * SHRINK_MIN ? cbrt_f64(x) : SHRINK_MIN; // (p / R)^2
    t = max(t, double(pc.r2_floor) / s.r2);
    if (!(t < 1.0)) return s;
    // What the gathered statistics hold within p under the fit's density: N(p) = A t + (4/3) D t^2 with
    // A = N - (4/3) D (t = (p / R)^2), so N(p) / N = t (1 - k (1 - t)), k = 4 D / (3 N): at t = 1/4 the
    // count within R / 2 itself. D whole, not its significant part: the threshold decides whether to
    // shrink; what lies within p is then best told by the counts. At a peak (D < 0) that keeps more than
    // the area's share t: the photons gathered at the larger radii are not spread evenly over the disc
    // (kept = t would blur a caustic's history).
    double k = s.n > 0.0 ? 4.0 * s.curv / (3.0 * s.n) : 0.0;
    double kept = clamp(t * (1.0 - k * (1.0 - t)), 0.0, 1.0);
    s.r2 *= t;
    s.n *= kept;
    s.tau_r *= kept;
    s.tau_g *= kept;
    s.tau_b *= kept;
    s.curv *= t * t;
    s.curv_var *= kept;
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
            if (pc.shrink_z > 0.0) s = shrunk(s);
            stats[i] = s;
            accum[i] = PassAccum(0L, 0L, 0L, 0u, 0u);
        }
        r2 = float(s.r2);
        live = hit_points[i].pixel != 0xffffffffu; // SPPM: this pass's eye path found a diffuse surface
    }
    note_radius(r2, live);
}

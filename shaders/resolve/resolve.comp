// Pass 5, resolve: pixel radiance = directly seen emission (the mean of its samples, ray.comp) + sum over the
// pixel's hit points of tau / (pi R^2 N_emitted) (eq. 1-2; tau already carries w f_r), with the cone
// filter's normalisation (1 - 2/(3k)) pi R^2 (eq. 11) when it is on. Slots whose statistics never
// received a photon contribute nothing, whatever their hit point now is.
#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 64) in;
#include "types.glsl"
#include "params.glsl"
layout(std430, binding = 1) readonly buffer Stats { HitStats stats[]; };
layout(std430, binding = 2) readonly buffer Direct { dvec4 direct[]; }; // emission samples (rgb), count (w)
layout(std430, binding = 3) writeonly buffer Image { vec4 image[]; };
layout(push_constant) uniform ResolvePush {
    double emitted;  // photons emitted by all photon passes so far (exact in double up to 2^53)
    float norm;      // 1, or 1 - 2/(3k) with the cone filter (eq. 11)
    uint tile_pixels; // pixels of this dispatch's tile (the renderer's): Stats, Direct and Image are
                      // bound from its first pixel on
} pc;
#include "sampling.glsl"
#include "invocation.glsl"

void main() {
    load_params();
    uint pixel = invocation_index(); // within the tile
    if (pixel >= pc.tile_pixels) return;
    dvec3 sum = dvec3(0.0);
    if (pc.emitted > 0.0) {
        for (uint s = 0u; s < params.hit_slots; s++) {
            HitStats st = stats[pixel * params.hit_slots + s];
            double area = double(pc.norm) * double(PI) * st.r2;
            sum += dvec3(st.tau_r, st.tau_g, st.tau_b) / (area * pc.emitted);
        }
    }
    dvec4 d = direct[pixel];
    image[pixel] = vec4(vec3(sum + d.rgb / max(d.w, 1.0)), 1.0);
}

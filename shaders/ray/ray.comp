// Pass 1, the ray (eye) pass: one camera ray per pixel, followed through mirrors and glass to the first
// diffuse surface, where it leaves a hit point. Glass splits the path into both Fresnel branches while the
// pixel has hit-point slots left; beyond that one branch is chosen at random (ALGORITHM.md, "Glass in the
// ray pass"). Emission seen directly or through specular paths is added to `direct` (rgb), whose w counts
// the eye passes: PPM runs this once, at pixel centres; SPPM once per pass, at a random point of each
// pixel, with one slot (one branch at glass).
#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 64) in;

#include "types.glsl"
#include "bindings.glsl"
layout(std430, binding = 4) writeonly buffer HitPoints { HitPoint hit_points[]; };
layout(std430, binding = 5) buffer Direct { vec4 direct[]; };
layout(push_constant) uniform RayPush {
    vec2 jitter;     // sample position inside the pixel, in [0,1)^2 (0.5, 0.5: the centre); negative:
                     // a random position per pixel (box filter)
    uint salt;       // random stream family
    uint pass;       // eye pass index: pixel p of pass k draws from stream k * pixels + p
} pc;

#include "rng.glsl"
#include "geometry.glsl"
#include "sampling.glsl"
#include "invocation.glsl"

const uint MAX_SLOTS = 8u;

struct Pending { vec3 o; vec3 d; vec3 thr; uint depth; };

void main() {
    load_params();
    uint pixel = invocation_index();
    if (pixel >= params.width * params.height) return;
    uint px = pixel % params.width;
    uint py = pixel / params.width;
    uint64_t pixels = uint64_t(params.width * params.height);
    Rng rng = rng_new(uint64_t(params.seed) | (uint64_t(pc.salt) << 32), uint64_t(pc.pass) * pixels + uint64_t(pixel));
    vec2 jitter = pc.jitter;
    if (jitter.x < 0.0) {
        jitter.x = rng_float(rng);
        jitter.y = rng_float(rng);
    }
    float sx = (2.0 * (float(px) + jitter.x) / float(params.width) - 1.0) * params.aspect * params.tan_half_fov;
    float sy = (1.0 - 2.0 * (float(py) + jitter.y) / float(params.height)) * params.tan_half_fov;
    vec3 dir = normalize(params.forward + sx * params.right + sy * params.up);

    Pending stack[MAX_SLOTS];
    uint sp = 0u;
    stack[sp++] = Pending(params.eye, dir, vec3(1.0), 0u);
    uint slot = 0u;
    vec3 emitted = vec3(0.0);
    uint base = pixel * params.hit_slots;

    while (sp > 0u) {
        Pending r = stack[--sp];
        while (r.depth < params.max_eye_depth) {
            Hit h;
            if (!intersect_scene(r.o, r.d, 0.0, 1e30, h)) break;
            Material m = materials[h.material];
            bool front = dot(r.d, h.normal) < 0.0;
            vec3 nf = front ? h.normal : -h.normal;
            if (m.surface == SURFACE_DIFFUSE) {
                if (front) emitted += r.thr * m.emission; // emitters are one-sided
                if (max(m.color.r, max(m.color.g, m.color.b)) > 0.0 && slot < params.hit_slots) {
                    hit_points[base + slot] = HitPoint(h.pos, pixel, nf, 0u, r.thr * m.color / PI, 0u);
                    slot++;
                }
                break;
            }
            r.depth++;
            if (m.surface == SURFACE_MIRROR) {
                r.thr *= m.color;
                r.d = reflect(r.d, nf);
                r.o = offset_ray(h.pos, nf);
                continue;
            }
            // Glass: the exact Fresnel split.
            float eta = front ? 1.0 / m.ior : m.ior;
            float cos_i = -dot(r.d, nf);
            float cos_t;
            float f = fresnel_dielectric(cos_i, eta, cos_t);
            vec3 refl = reflect(r.d, nf);
            vec3 refr = normalize(eta * r.d + (eta * cos_i - cos_t) * nf);
            if (f >= 1.0) {
                r.d = refl;
                r.o = offset_ray(h.pos, nf);
            } else if (slot + sp + 1u < params.hit_slots) {
                stack[sp++] = Pending(offset_ray(h.pos, nf), refl, r.thr * f, r.depth);
                r.thr *= 1.0 - f;
                r.d = refr;
                r.o = offset_ray(h.pos, -nf);
            } else if (rng_float(rng) < f) {
                r.d = refl;
                r.o = offset_ray(h.pos, nf);
            } else {
                r.d = refr;
                r.o = offset_ray(h.pos, -nf);
            }
        }
    }
    for (; slot < params.hit_slots; slot++) {
        hit_points[base + slot] = HitPoint(vec3(0.0), 0xffffffffu, vec3(0.0), 0u, vec3(0.0), 0u);
    }
    direct[pixel] += vec4(emitted, 1.0);
}

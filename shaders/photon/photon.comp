// Pass 3, a photon pass: photons leave the lights in proportion to their power, bounce off mirrors and
// through glass, and leave a record at every diffuse surface they reach, continuing by Russian roulette.
// Records are appended to one buffer; the lanes of a subgroup that leave a record at the same step reserve
// their slots with a single atomic (a global counter hit once per record is slow under contention). A
// per-thread array of records, flushed once per path, measured slower on lavapipe: it lives in memory.
#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_KHR_shader_subgroup_ballot : require
layout(local_size_x = 64) in;

#include "types.glsl"
#include "bindings.glsl"
layout(std430, binding = 4) readonly buffer Lights { Light lights[]; };
layout(std430, binding = 5) writeonly buffer Photons { Photon photons[]; };
layout(std430, binding = 6) buffer Counter { uint photon_count; };
layout(push_constant) uniform PhotonPush {
    uint64_t first;  // global index of this batch's first photon: its random stream
    uint count;      // photons in this batch
    uint salt;       // random stream family (photon passes and the probe pass differ)
} pc;

#include "rng.glsl"
#include "geometry.glsl"
#include "sampling.glsl"
#include "grid.glsl"
#include "invocation.glsl"

// Records one path may leave; a path is ended at this many (ALGORITHM.md: bounded paths).
const uint MAX_RECORDS = 16u;

// Appends a record; the active lanes of a subgroup reserve their slots with one atomic.
void emit(Photon rec) {
    uvec4 ballot = subgroupBallot(true);
    uint base = 0u;
    if (subgroupElect()) base = atomicAdd(photon_count, subgroupBallotBitCount(ballot));
    uint at = subgroupBroadcastFirst(base) + subgroupBallotExclusiveBitCount(ballot);
    if (at < params.photon_capacity) photons[at] = rec;
}

// Photons per thread. A thread starts its next photon as soon as a path ends ("path regeneration"), so
// the lanes of a subgroup stay busy instead of waiting for the longest of their paths.
const uint PER_THREAD = 8u;

void main() {
    load_params();
    uint t = invocation_index();
    uint threads = (pc.count + PER_THREAD - 1u) / PER_THREAD;
    if (t >= threads) return;
    uint next = 0u;          // photons of this thread started so far
    bool alive = false;
    Rng rng;
    vec3 o, d, flux;
    uint depth = 0u;
    uint n = 0u;             // records of the current path
    for (;;) {
        if (!alive) {
            // Photon t + k * threads: consecutive threads start consecutive photons.
            uint i = t + next * threads;
            if (next == PER_THREAD || i >= pc.count) break;
            next++;
            rng = rng_new(uint64_t(params.seed) | (uint64_t(pc.salt) << 32), pc.first + uint64_t(i));
            float u = rng_float(rng);
            uint li = 0u;
            while (li + 1u < params.num_lights && u >= lights[li].cdf) li++;
            Light light = lights[li];
            Quad q = quads[light.quad];
            float a = rng_float(rng);
            float b = rng_float(rng);
            o = offset_ray(q.origin + a * q.edge_u + b * q.edge_v, q.normal);
            float u1 = rng_float(rng);
            float u2 = rng_float(rng);
            d = cosine_direction(q.normal, u1, u2);
            flux = light.power / light.prob;
            depth = 0u;
            n = 0u;
            alive = true;
        }
        Hit h;
        if (depth >= params.max_photon_depth || !intersect_scene(o, d, 0.0, 1e30, h)) {
            alive = false;
            continue;
        }
        depth++;
        Material m = materials[h.material];
        bool front = dot(d, h.normal) < 0.0;
        vec3 nf = front ? h.normal : -h.normal;
        if (m.surface == SURFACE_DIFFUSE) {
            float p = max(m.color.r, max(m.color.g, m.color.b));
            if (p <= 0.0) { alive = false; continue; } // a black emitter absorbs
            emit(Photon(h.pos, grid_key(grid_cell(h.pos)), flux, oct_encode(d)));
            n++;
            // Russian roulette: survive with the largest albedo.
            if (n == MAX_RECORDS || rng_float(rng) >= p) { alive = false; continue; }
            flux *= m.color / p;
            float v1 = rng_float(rng);
            float v2 = rng_float(rng);
            d = cosine_direction(nf, v1, v2);
            o = offset_ray(h.pos, nf);
        } else if (m.surface == SURFACE_MIRROR) {
            flux *= m.color;
            d = reflect(d, nf);
            o = offset_ray(h.pos, nf);
        } else {
            float eta = front ? 1.0 / m.ior : m.ior;
            float cos_i = -dot(d, nf);
            float cos_t;
            float f = fresnel_dielectric(cos_i, eta, cos_t);
            if (rng_float(rng) < f) {
                d = reflect(d, nf);
                o = offset_ray(h.pos, nf);
            } else {
                d = normalize(eta * d + (eta * cos_i - cos_t) * nf);
                o = offset_ray(h.pos, -nf);
            }
        }
    }
}

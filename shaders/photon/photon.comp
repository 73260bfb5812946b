// Pass 3, a photon pass: photons leave the lights in proportion to their power, bounce off mirrors and
// through glass, and leave a record at every diffuse surface they reach, continuing by Russian roulette.
// Records are appended to one buffer; the lanes of a subgroup that leave a record at the same step reserve
// their slots with a single atomic (a global counter hit once per record is slow under contention). A
// per-thread array of records, flushed once per path, measured slower on lavapipe: it lives in memory.
#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_EXT_control_flow_attributes : require
layout(local_size_x = 64) in;

#include "types.glsl"
#include "bindings.glsl"
layout(std430, binding = 6) readonly buffer Lights { Light lights[]; };
layout(std430, binding = 7) writeonly buffer Photons { u64vec4 photons[]; }; // Photon records (photon_words)
layout(std430, binding = 8) buffer Counter { uint photon_count; };
layout(std430, binding = 9) buffer Cut { PathCounters cut; };
layout(push_constant) uniform PhotonPush {
    uint64_t first;  // global index of this batch's first photon: its random stream
    uint count;      // photons in this batch
    uint salt;       // random stream family (photon passes and the probe pass differ)
    uint per_thread; // photons per thread, set with params.max_photon_depth so that no SIMD group can
                     // exceed the device's loop budget (crates/kernels/src/photon.rs, PathLimits)
    uint pad0;
} pc;

#include "rng.glsl"
#include "geometry.glsl"
#include "sampling.glsl"
#include "grid.glsl"
#include "invocation.glsl"

// Variants that `ppm-vk bench` times against this kernel to show where a step's time goes
// (Renderer::photon_breakdown); never rendered with. PHOTON_NO_STORE: the append reserves its slots but
// stores nothing. PHOTON_NO_APPEND: no append. PHOTON_TRACE_ONLY: the same photons leave the lights, but
// every hit is a diffuse bounce with no material, roulette or record, and a path ends after
// PHOTON_TRACE_ONLY hits: only the intersections, the direction draws and the loop remain, the ceiling
// of this design. PHOTON_COUNT_STEPS: counts the intersections traced in cut.pad0 (an untimed run).

// Appends a record; the active lanes of a subgroup reserve their slots with one atomic.
void emit(Photon rec) {
#ifndef PHOTON_NO_APPEND
    uvec4 ballot = subgroupBallot(true);
    uint base = 0u;
    if (subgroupElect()) base = atomicAdd(photon_count, subgroupBallotBitCount(ballot));
    uint at = subgroupBroadcastFirst(base) + subgroupBallotExclusiveBitCount(ballot);
#ifndef PHOTON_NO_STORE
    if (at < params.photon_capacity) photons[at] = photon_words(rec);
#endif
#endif
}

// The light a photon leaves, for the uniform number u (the first of its stream): the first whose running
// cdf exceeds u.
#ifdef SCENE_CONSTANTS
// The lights are constants: a chain of selects, unrolled, reads no memory (a dynamically indexed constant
// array would be copied per invocation).
Emitter choose_emitter(float u) {
    Emitter e = SCENE_EMITTERS[0];
    [[unroll]] for (uint i = 1u; i < NUM_LIGHTS; i++) {
        if (u >= SCENE_EMITTERS[i - 1u].cdf) e = SCENE_EMITTERS[i];
    }
    return e;
}
#else
// Binary search for the first light whose cdf exceeds u (the same light as a linear scan: cdfs never
// decrease), in ceil(log2 n) steps: scenes may have 100k emitting triangles.
Emitter choose_emitter(float u) {
    uint lo = 0u;
    uint hi = params.num_lights - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (u >= lights[mid].cdf) lo = mid + 1u; else hi = mid;
    }
    Light light = lights[lo];
    vec3 flux = light.power / light.prob;
    if (light.kind == LIGHT_TRIANGLE) {
        Triangle tr = bvh_triangles[light.index];
        return Emitter(tr.v0, tr.v1 - tr.v0, tr.v2 - tr.v0, bvh_normal(tr), flux, light.cdf, true);
    }
    Quad q = quads[light.index];
    return Emitter(q.origin, q.edge_u, q.edge_v, q.normal, flux, light.cdf, false);
}
#endif

// A thread traces pc.per_thread photons and starts its next one as soon as a path ends ("path
// regeneration"), so the lanes of a subgroup stay busy instead of waiting for the longest of their paths.
// Paths end by Russian roulette only; params.max_photon_depth (surface interactions) is a backstop that
// keeps every SIMD group inside lavapipe's loop budget. A path that reaches it between diffuse surfaces
// has survived roulette at each, which happens with probability at most rho_max^depth (< 1e-15 at rho 0.95
// and the depths PathLimits picks); such a path is counted in cut.photon_paths, never dropped silently.
// lavapipe runs both sides of every branch under a mask, so the loop below is written to have as little
// inside branches as it can: the cosine-weighted direction that a new photon and a diffuse bounce both
// need is drawn once per step, after either.
void main() {
    load_params();
    uint t = invocation_index();
    uint threads = (pc.count + pc.per_thread - 1u) / pc.per_thread;
    if (t >= threads) return;
    bvh_left = params.photon_bvh_budget;
    uint next = 0u;          // photons of this thread started so far
    bool alive = false;
    Rng rng;
    vec3 o, d, flux;
    vec3 lobe;               // the normal a direction is still to be drawn about (pending)
    bool pending = false;
    uint depth = 0u;
    for (;;) {
        if (!alive) {
            // Photon t + k * threads: consecutive threads start consecutive photons.
            uint i = t + next * threads;
            if (next == pc.per_thread || i >= pc.count) break;
            next++;
            rng = rng_new(uint64_t(params.seed) | (uint64_t(pc.salt) << 32), pc.first + uint64_t(i));
            Emitter e = choose_emitter(rng_float(rng));
            float a = rng_float(rng);
            float b = rng_float(rng);
            // A triangle: the unit square folded onto the half below its diagonal, uniform in area.
            if (e.triangle && a + b > 1.0) { a = 1.0 - a; b = 1.0 - b; }
            o = offset_ray(e.origin + a * e.edge_u + b * e.edge_v, e.normal);
            lobe = e.normal;
            pending = true;
            flux = e.flux;
            depth = 0u;
            alive = true;
        }
        if (pending) {
            float u1 = rng_float(rng);
            float u2 = rng_float(rng);
            d = cosine_direction(lobe, u1, u2);
            pending = false;
        }
        bvh_sync();
        if (depth >= params.max_photon_depth) {
            atomicAdd(cut.photon_paths, 1u);
            alive = false;
            continue;
        }
#ifdef PHOTON_COUNT_STEPS
        atomicAdd(cut.pad0, 1u); // per lane: a subgroup-aggregated count undercounts in this loop
#endif
        Hit h;
        if (!intersect_scene(o, d, 0.0, 1e30, h)) {
            // Out of traversal steps: an error (bvh_cut) or a long path's end (bvh_spent); either way this
            // thread's budget is gone, so it stops (BVH scenes trace one photon per thread).
            if (bvh_cut) { atomicAdd(cut.traversal_cut, 1u); break; }
            if (bvh_spent) { atomicAdd(cut.photon_paths, 1u); break; }
            alive = false;
            continue;
        }
        depth++;
        bool front = dot(d, h.normal) < 0.0;
        vec3 nf = front ? h.normal : -h.normal;
#ifdef PHOTON_TRACE_ONLY
        alive = depth < PHOTON_TRACE_ONLY;
        lobe = nf;
        pending = true;
        o = offset_ray(h.pos, nf);
        continue;
#endif
        Material m = materials[h.material];
        if (m.surface == SURFACE_DIFFUSE) {
            float p = max(m.color.r, max(m.color.g, m.color.b));
            if (p <= 0.0) { alive = false; continue; } // a black emitter absorbs
            emit(Photon(h.pos, grid_key(grid_cell(h.pos)), flux, oct_encode(d)));
            // Russian roulette: survive with the largest albedo; flux *= albedo / p keeps every channel
            // unbiased (its expectation is flux * albedo), and never grows (albedo <= p per channel).
            if (rng_float(rng) >= p) { alive = false; continue; }
            flux *= m.color / p;
            lobe = nf;
            pending = true;
            o = offset_ray(h.pos, nf);
        } else if (m.surface == SURFACE_MIRROR) {
            flux *= m.color;
            d = reflect(d, nf);
            o = offset_ray(h.pos, nf);
        } else {
            glass_branch(h.pos, nf, front, m.ior, rng_float(rng), o, d);
        }
    }
}

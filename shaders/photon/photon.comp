// Pass 3, a photon pass: photons leave the lights in proportion to their power, bounce off mirrors, rough
// metals and through (rough) glass, and leave a record at every diffuse surface (and plastic's diffuse base) they reach,
// continuing by Russian roulette. On a smooth-shaded mesh each vertex weighs the photon by Veach's
// correction for shading normals (shading.glsl): shading_in where it arrives (its records carry it), and
// shading_out where it leaves, but after a diffuse bounce, drawn about the true normal.
// Records are appended to one buffer; the lanes of a subgroup that leave a record at the same step reserve
// their slots with a single atomic (a global counter hit once per record is slow under contention). A
// per-thread array of records, flushed once per path, measured slower on lavapipe: it lives in memory.
#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_vote : require
#extension GL_EXT_control_flow_attributes : require
layout(local_size_x = 64) in;

#include "types.glsl"
#include "bindings.glsl"
layout(std430, binding = 8) readonly buffer Lights { Light lights[]; };
layout(std430, binding = 9) writeonly buffer Photons { u64vec4 photons[]; }; // Photon records (photon_words)
layout(std430, binding = 10) buffer Counter { uint photon_count; };
layout(std430, binding = 11) buffer Cut { PathCounters cut; };
layout(std430, binding = 12) buffer Work { PhotonWork work; };
layout(std430, binding = 13) buffer Suspended { PhotonState suspended[]; };
layout(push_constant) uniform PhotonPush {
    uint64_t first;  // global index of this batch's first photon: its random stream
    uint count;      // photons in this batch
    uint salt;       // random stream family (photon passes and the probe pass differ)
    uint per_thread; // photons per thread, set with params.max_photon_depth so that no SIMD group can
                     // exceed the device's loop budget (crates/kernels/src/photon.rs, PathLimits)
    uint resume;     // 1: the resume round of a BVH scene's batch (below)
    uint reserve;    // BVH scenes: the least budget a thread starts a photon with
    uint budget;     // BVH scenes: a thread's budget in the first round (the resume round's: params)
} pc;

#include "rng.glsl"
#include "geometry.glsl"
#include "sampling.glsl"
#include "materials/conductor.glsl"
#include "materials/plastic.glsl"
#include "materials/thin_dielectric.glsl"
#include "materials/rough_dielectric.glsl"
#include "lobe_bounce.glsl"
#include "texture.glsl"
#include "materials/blend.glsl"
#include "shading.glsl"
#include "grid.glsl"
#include "invocation.glsl"
#include "lights.glsl"
#include "targets.glsl"

// Variants that `ppm-vk bench` times against this kernel to show where a step's time goes
// (Renderer::photon_breakdown); never rendered with. PHOTON_NO_STORE: the append reserves its slots but
// stores nothing. PHOTON_NO_APPEND: no append. PHOTON_TRACE_ONLY: the same photons leave the lights, but
// every hit is a diffuse bounce with no material, roulette or record, and a path ends after
// PHOTON_TRACE_ONLY hits: only the intersections, the direction draws and the loop remain, the ceiling
// of this design. PHOTON_COUNT_STEPS: counts the intersections traced in cut.capped (an untimed run).

// A photon's flux after a smooth-shaded vertex's correction, held at FLUX_CAP_FIXED units and counted
// there (shading.glsl).
vec3 capped(vec3 flux) {
    float cap = FLUX_CAP_FIXED / params.flux_fixed;
    if (max3(flux) > cap) {
        atomicAdd(cut.capped, 1u);
        flux = min(flux, vec3(cap));
    }
    return flux;
}

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

// Loop iterations of one step of the path loop besides the BVH's: the step itself and the loops over the
// spheres, quads and written-out triangles in intersect_scene (counted as loops even where they are
// unrolled), and choosing a light (its binary search; counted on every step a lane starts a photon).
#define PATH_STEP_LOOPS (NUM_SPHERES + NUM_QUADS + NUM_INLINE_TRIANGLES + 3u)
// An environment map's sampling adds two binary searches (at most 2 x 23 steps: MAX_ENVMAP_PIXELS).
#define LIGHT_LOOPS (findMSB(params.num_lights) + 2u + (HAS_ENVIRONMENT ? 48u : 0u))

// A photon's path is its own: the numbers it draws come from its own stream (its global index), so which
// thread traces it, and when, changes nothing but the order of the records.
//
// A thread traces pc.per_thread photons and starts its next one as soon as a path ends ("path
// regeneration"), so the lanes of a subgroup stay busy instead of waiting for the longest of their paths.
// Paths end by Russian roulette only; params.max_photon_depth (surface interactions) is a backstop. A path
// that reaches it between diffuse surfaces has survived roulette at each, which happens with probability
// at most rho_max^depth (< 1e-15 at rho 0.95 and the depths PathLimits picks); such a path is counted in
// cut.photon_paths, never dropped silently.
//
// Without a BVH the depth backstop also keeps every SIMD group inside lavapipe's loop budget: photon
// t + k * threads is thread t's k-th. With a BVH no bound on a path's loop iterations is useful, so each
// thread counts what its subgroup has spent (bvh_left: traversal steps and path steps alike, geometry.glsl)
// and takes its photons from a counter (work.started), one at a time, while at least pc.reserve is left.
// A photon whose traversal runs out is suspended: its state (photon_state) goes to `suspended`, and the
// thread stops. The resume round (pc.resume = 1, dispatched by photon_resume.comp after this one) gives
// each suspended photon, and each photon of the batch no thread started, a thread and a whole budget of
// its own, which is what every photon of a BVH scene had when a thread traced one. There a traversal that
// runs out is what it was then: an error if it alone took BVH_TRAVERSAL_MIN steps or more (a degenerate
// BVH), else the end of a very long path, counted in cut.photon_paths.
// lavapipe runs both sides of every branch under a mask, so the loop below is written to have as little
// inside branches as it can: the cosine-weighted direction that a new photon and a diffuse bounce both
// need is drawn once per step, after either.
void main() {
    load_params();
    uint t = invocation_index();
    bool dynamic = NUM_TRIANGLES > 0u;
    uint started = pc.resume != 0u ? min(work.started, pc.count) : 0u;
    uint threads = pc.resume != 0u ? work.suspended + pc.count - started : (pc.count + pc.per_thread - 1u) / pc.per_thread;
    if (t >= threads) return;
    bvh_left = pc.resume != 0u || !dynamic ? params.photon_bvh_budget : pc.budget;
    uint next = 0u;          // photons of this thread started so far
    bool alive = false;
    Rng rng;
    vec3 o, d, flux;
    vec3 lobe;               // the normal a direction is still to be drawn about (pending)
    bool pending = false;
    bool aim = false;        // the pending direction is an emitted photon's (targets.glsl)
    // The last vertex's normals, true and shading (shading.glsl): d must lie on the same side of both, and
    // with `leave` the photon takes shading_out along d (not after a diffuse bounce, drawn about vng).
    vec3 vng, vns;
    bool leave = false;
    uint depth = 0u;
    if (pc.resume != 0u && t < work.suspended) {
        PhotonState s = suspended[t];
        rng = Rng(s.state, s.inc);
        o = s.o;
        d = s.d;
        flux = s.flux;
        depth = s.depth;
        alive = true;
        next = 1u;
        vng = d; // suspended after its last vertex's checks
        vns = d;
    }
    for (;;) {
        if (dynamic && bvh_left != 0xffffffffu) {
            // The subgroup's iterations of this loop (and of choose_emitter's), on every lane alike.
            bvh_left -= min(bvh_left, PATH_STEP_LOOPS + (subgroupAny(!alive) ? LIGHT_LOOPS : 0u));
        }
        if (!alive) {
            uint i;
            if (pc.resume != 0u) {
                // One photon no thread of the first round started.
                if (next == 1u) break;
                i = started + t - work.suspended;
            } else if (dynamic) {
                if (next == pc.per_thread || bvh_left < pc.reserve) break;
                uvec4 ballot = subgroupBallot(true);
                uint base = 0u;
                if (subgroupElect()) base = atomicAdd(work.started, subgroupBallotBitCount(ballot));
                i = subgroupBroadcastFirst(base) + subgroupBallotExclusiveBitCount(ballot);
                if (i >= pc.count) break;
            } else {
                // Photon t + k * threads: consecutive threads start consecutive photons.
                i = t + next * threads;
                if (next == pc.per_thread || i >= pc.count) break;
            }
            next++;
            rng = rng_new(uint64_t(params.seed) | (uint64_t(pc.salt) << 32), pc.first + uint64_t(i));
            Emitter e = choose_emitter(rng_float(rng));
            float a = rng_float(rng);
            float b = rng_float(rng);
            if (HAS_OTHER_LIGHTS && !is_area(e)) {
                // lights.glsl: a sphere gives its point and normal (the cosine draw below, as an area
                // light's); the other kinds a direction of their own.
                vec3 dir;
                pending = !emit_photon(e, a, b, rng, o, dir, flux);
                if (pending) lobe = dir; else d = dir;
                vng = dir;
                vns = dir;
            } else {
                o = offset_ray(emitter_point(e, a, b), e.normal);
                lobe = e.normal;
                vng = lobe;
                vns = lobe;
                pending = true;
                flux = e.flux * emitter_radiance(e, a, b);
            }
            aim = pending;
            leave = false;
            depth = 0u;
            alive = true;
        }
        if (pending) {
            float u1 = rng_float(rng);
            float u2 = rng_float(rng);
            float w = 1.0;
            if (HAS_TARGETS && aim && params.num_targets > 0u) {
                // Maybe aimed at what casts caustics, the flux weighed by the mixture's density.
                d = aimed_direction(o, lobe, u1, u2, rng_float(rng), w);
                flux *= w;
            } else {
                d = cosine_direction(lobe, u1, u2);
            }
            pending = false;
            aim = false;
            if (!(w > 0.0)) { alive = false; continue; } // below the light: it carries nothing
        }
        if (HAS_SHADING_NORMALS) {
            if (!shading_valid(d, vng, vns)) { alive = false; continue; }
            if (leave) flux = capped(flux * shading_out(d, vng, vns));
            leave = false;
        }
        bvh_sync();
        if (depth >= params.max_photon_depth) {
            atomicAdd(cut.photon_paths, 1u);
            alive = false;
            continue;
        }
#ifdef PHOTON_COUNT_STEPS
        atomicAdd(cut.capped, 1u); // per lane: a subgroup-aggregated count undercounts in this loop
#endif
        Hit h;
        // The ray's mask key; a photon suspended here keeps the stream from before it, so that the resume
        // round draws the same key for the same ray.
        Rng before = rng;
        if (!intersect_scene(o, d, 0.0, 1e30, mask_key(rng), h)) {
            // Out of traversal steps: this thread's budget is gone, so it stops. In the first round of a
            // BVH scene the photon waits for the resume round, from this intersection; in the resume round
            // it is an error (bvh_cut) or a long path's end (bvh_spent).
            if ((bvh_cut || bvh_spent) && pc.resume == 0u) {
                uint at = atomicAdd(work.suspended, 1u);
                suspended[at] = PhotonState(before.state, before.inc, o, depth, d, 0u, flux, 0u);
                break;
            }
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
        resolve_blend(h, rng); // before anything reads the hit's material (blend.glsl)
        Material m = material(h.material);
        apply_texture(m, h);
        vec3 ng = nf;
        if (HAS_SHADING_NORMALS) {
            nf = shading_normal(h, ng);
            if (!shading_valid(d, ng, nf)) { alive = false; continue; }
            flux = capped(flux * shading_in(-d, ng, nf));
            // A bump or normal map's term, for the direction the photon arrived from (normal_map.glsl).
            if (HAS_NORMAL_MAPS) flux *= bump_shadowing(-d);
            vng = ng;
            vns = nf;
            leave = true;
        }
        // The record this vertex leaves, if any (at most one per vertex), appended once after the branches
        // below: lavapipe runs every branch's code, so one append is cheaper than one in each.
        bool record = false;
        vec3 record_flux = flux;
        if (HAS_ROUGH_CONDUCTORS && m.surface == SURFACE_ROUGH_CONDUCTOR && (params.direct_light == 0u || depth > 1u)
            && glossy_hit(h.material)) {
            // A glossy hit point's surface (rough_conductor.glsl): a record, as on a diffuse surface (the first
            // landing skipped with direct light sampled), then the lobe sampled below.
            record = true;
        }
        vec3 arrived = d; // the direction the photon arrived along, which the record keeps
        if (m.surface == SURFACE_DIFFUSE) {
            float p = max(m.color.r, max(m.color.g, m.color.b));
            if (p <= 0.0) { alive = false; continue; } // a black emitter absorbs
            // With direct light sampled at the eye paths (params.direct_light), light straight from an
            // emitter to this first surface (paths L D ...) is the shadow rays' term (ray.comp): the photon
            // leaves no record here. Its later records (L D D..., L S D... : everything after a bounce)
            // are the photon estimate's, in both modes.
            record = params.direct_light == 0u || depth > 1u;
            // Russian roulette: survive with the largest albedo; flux *= albedo / p keeps every channel
            // unbiased (its expectation is flux * albedo), and never grows (albedo <= p per channel).
            if (rng_float(rng) >= p) {
                alive = false; // its record still goes below
            } else {
                flux *= m.color / p;
                lobe = ng; // about the true normal: the pdf cancels shading_out (shading.glsl)
                leave = false;
                pending = true;
                o = offset_ray(h.pos, ng);
            }
        } else if (is_reflector(m.surface)) {
            flux *= reflector_weight(h.material, m, -dot(d, nf));
            d = reflect(d, nf);
            o = offset_ray(h.pos, nf);
        } else if (lobe_surface(m)) {
            // A plastic's diffuse lobe leaves a record carrying the flux the coat lets in, times t(cos_i)
            // (1 - F(cos_i) when smooth: plastic.glsl); the first landing is skipped with direct light
            // sampled, as on a diffuse surface (its shadow rays evaluate the plastic too). Then the coat,
            // or a rough lobe sampled as the eye paths sample it (no record: an S vertex, ray.comp), in
            // one routine for all of them (lobe_bounce.glsl).
            bool plastic = HAS_PLASTICS && m.surface == SURFACE_PLASTIC;
            uint table = HAS_ROUGH_PLASTICS && plastic ? material_table(h.material) : 0u;
            if (plastic && (params.direct_light == 0u || depth > 1u) && max3(m.color) > 0.0) {
                record = true;
                record_flux = flux * coat_transmittance(table, -dot(d, nf), m.ior);
            }
            if (!lobe_bounce(h.material, m, table, h, nf, front, true, rng, o, d, flux)) alive = false;
        } else if (HAS_THIN && m.surface == SURFACE_THIN) {
            flux *= thin_branch(h.material, m, h.pos, nf, rng_float(rng), o, d);
        } else {
            glass_branch(h.pos, nf, front, m.ior, rng_float(rng), o, d);
        }
        if (record) emit(Photon(h.pos, grid_key(grid_cell(h.pos)), record_flux, oct_encode(arrived)));
    }
}

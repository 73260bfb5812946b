// Pass 1, the ray (eye) pass: one camera ray per pixel, followed through mirrors and glass to the first
// diffuse surface, where it leaves a hit point. Glass splits the path into both Fresnel branches while the
// pixel has hit-point slots left; beyond that one branch is chosen at random (../shared/paper/ALGORITHM.md, "Glass in the
// ray pass"). PPM runs the hit-point path once, at pixel centres; SPPM once per pass, at a random point of
// each pixel, one branch at glass, and where the scene has rough vertices (params.rough_split) one slot for
// each direction its first rough vertex draws from the lobe.
//
// Emission seen directly or through mirrors and glass is estimated apart from the hit points, and gets
// more samples: a pixel's value is the integral over the pixel of (a) the emission met along the specular
// chain of the eye path through each point and (b) the radiance reflected at the chain's first diffuse
// vertex. The photon estimate at the hit points covers (b). Term (a) has the sharp edges (the light and
// its images in mirrors and glass), so each eye pass also traces pc.emission_samples paths through
// points of the pixel, each uniform over it and all of them stratified (stratum_point), one Fresnel
// branch each chosen with probability f (weight f / f = 1): each is an unbiased sample of (a),
// independent of (b). `direct` sums them in double over all eye passes (rgb) with their count (w); the
// resolve divides. The hit-point path's own emission is one
// more such sample when its position is random (SPPM), or the only one when there are no others.
//
// Most pixels see no emitter through any point of them, where (a) is 0 and samples are wasted. Eye pass 0 is
// a pilot: its emission samples only mark (in `busy`) the pixels where one met the front of an emitter that
// no shadow ray takes (not straight after a rough vertex, whose shadow ray takes the same light by MIS,
// blurred by the lobe: marking that took a tenth of the interior's pixels, the floor's rough coat reflecting
// the lamps, docs/performance.md), and are not added; the renderer then marks their neighbours too
// (spread_marks), which catches the pixels an edge of the light or of its image only clips. Later passes take
// all their samples in marked pixels and one in the others. The pilot marks the pixels whose paths sampled
// through a rough lobe the same way: the light a rough vertex reflects (its shadow ray and its lobe's
// direction, glossy_light.glsl) is the noisiest term there. (Marking every pixel that sees a mirror or glass,
// as before, took the samples in the mirror and glass spheres too, mostly where they show the walls: the eye
// pass cost 80-95 ms per pass at 512^2 against 40-49 ms marking only the light, docs/performance.md.)
// The pooled mean stays unbiased because every count is fixed before the samples it counts are drawn:
// the marks depend on the pilot's samples only, which are not in the sum (pooling samples that had
// chosen their own count would bias it).
//
// Direct light (params.direct_light, `--direct sample`): each of these paths also estimates (d), the light
// that reaches the chain's first diffuse vertex straight from an emitter and is reflected towards the eye,
// by sampling one light (in proportion to its power, a point uniform on it) with a shadow ray
// (direct_light_ray below); every pixel then takes pc.light_samples such paths, marked ones
// pc.emission_samples, and those where none of the pilot's shadow rays reached a light (nor a
// neighbour's) one: the pilot marks the lit pixels too, and its samples stay out of the sums. The photons
// leave no record where they first land straight from a light (photon.comp), so the partition of the
// light reaching the eye, in path notation (E eye, S mirror or glass, D diffuse, L emitter), is:
//   E S* L           emission seen directly or through specular surfaces: term (a), these paths;
//   E S* D L         light straight from an emitter to the first diffuse vertex: term (d), these paths'
//                    shadow rays;
//   E S* D (S|D)+ L  everything that bounced before reaching it: the photon estimate at the hit points.
// With `--direct photons` (the paper's estimator) (d) stays with the photons and these paths take (a) only.
// Every kind of light keeps this partition (lights.glsl): a glowing sphere is an emitter that eye paths
// meet (a) and shadow rays sample by the solid angle of its cap (d); points, spots and the sun no eye path
// meets (no (a)), shadow rays reach them (d); the environment is (a) where an eye path leaves the scene, and
// its (d) is two strategies weighted by the power heuristic, direct_light_ray's sample of the map and
// environment_ray's cosine direction that leaves the scene: the weights sum to one in every direction,
// so together they are one unbiased estimate of (d). Photons from every kind skip their first landing alike.
// A plastic is both an S (its coat's reflection) and a D (its base, plastic.glsl): an emission-sample path
// takes the base's term (d) there and goes on along the coat, without choosing between them. Rough
// conductors and rough glass are S too: every path samples one direction of their lobes, with the exact
// weight f cos / pdf (rough_conductor.glsl, rough_dielectric.glsl), and leaves no hit point there; the
// photons do the same with the same weights, so the partition above is unchanged. The E S* L paths whose
// last S is such a rough vertex are taken both by that sampled direction and by a shadow ray from the
// vertex, weighed by multiple importance sampling (glossy_light.glsl): still term (a), and still one
// estimate of it. A rough conductor of
// roughness at least params.glossy_alpha is a D instead (a glossy hit point): the eye paths end there
// with a hit point and term (d) by its BRDF, the photons leave a record there (but the first landing) and
// go on by sampling its lobe, and the gather evaluates its BRDF per photon; the partition is again the
// one above with those vertices as D.
// On a smooth-shaded mesh every BSDF works about the shading normal nf, and a direction on different
// sides of it and of the true surface ng ends the path (shading.glsl); eye paths carry radiance, so they
// need no other correction (the photons do).
#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_control_flow_attributes : require
layout(local_size_x = 64) in;

#include "types.glsl"
#include "bindings.glsl"
layout(std430, binding = 8) writeonly buffer HitPoints { HitPoint hit_points[]; };
layout(std430, binding = 9) buffer Direct { dvec4 direct[]; };
layout(std430, binding = 10) buffer Cut { PathCounters cut; };
// Per pixel, what the pilot saw here or beside: MARK_EMISSION, the front of an emitter; MARK_LIT, a light
// through one of its shadow rays; MARK_ROUGH, a rough conductor or rough glass its paths sampled through.
layout(std430, binding = 11) buffer Busy { uint busy[]; };
const uint MARK_EMISSION = 1u;
const uint MARK_LIT = 2u;
const uint MARK_ROUGH = 4u;
const uint MARK_CHAIN = 8u;
// MARK_NEAR: one of the pilot's chains left a curved mirror or glass (a sphere, or a shading normal off its
// face: `bent`) and then passed near an area light (passes_near_light). A curve magnifies: the pixel's
// other positions may meet that light as an image too thin for the pilot's samples to find, and one such
// sample among a few is a firefly (docs/accuracy.md, "Chains that pass near a light").
const uint MARK_NEAR = 16u;
// MARK_SPLIT: set by the renderer from MARK_CURVED (and spread) where SPPM splits at glass (kernels'
// ray.rs). MARK_CURVED, the pilot's: one of its chains left a curved mirror or glass (`bent`).
const uint MARK_SPLIT = 32u;
const uint MARK_CURVED = 64u;
layout(std430, binding = 12) readonly buffer Lights { Light lights[]; };
layout(push_constant) uniform RayPush {
    vec2 jitter;     // sample position inside the pixel, in [0,1)^2 (0.5, 0.5: the centre); negative:
                     // a random position per pixel (box filter)
    uint salt;       // random stream family of the hit-point path (the emission samples use SALT_EMISSION)
    uint pass;       // eye pass index: pixel p of pass k draws from stream k * pixels + p
    uint emission_samples; // extra paths per marked pixel and eye pass (term (a), and (d) below)
    uint trace_hits; // 0: only the emission samples (PPM's passes after the first keep their hit points)
    uint chunk;      // dispatch of this eye pass: the emission samples' streams are chunk << 48 | stream
    uint pilot;      // 1: eye pass 0, whose emission samples only set `busy`
    uint light_samples; // the same paths per pixel the pilot did not mark
    uint pilot_samples; // the pilot's in every pixel; the rest of emission_samples where MARK_CHAIN
    uint rough_samples; // per pixel marked MARK_ROUGH (at least emission_samples)
    uint per_dispatch;  // paths per pixel one dispatch takes: dispatch k takes samples k * this onwards
    uint first_pixel;   // this dispatch's tile, pixels first_pixel.. (the renderer's tiles): HitPoints,
    uint tile_pixels;   // Direct and Busy are bound from its first pixel on, so index them by `local`
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
#include "invocation.glsl"
#include "lights.glsl"

const uint MAX_SLOTS = 8u;
const uint SALT_EMISSION = 4u;
const uint SALT_STRATA = 5u;

// A branch waiting for its turn: the ray, its weight, its depth, and where it left a rough vertex the
// lobe's density of d and the vertex (glossy_light.glsl; 0 after glass, a delta vertex).
struct Pending { vec3 o; vec3 d; vec3 thr; uint depth; float lobe_pdf; vec3 lobe_from; };

vec3 camera_ray(uint px, uint py, vec2 jitter) {
    float sx = (2.0 * (float(px) + jitter.x) / float(params.width) - 1.0) * params.aspect * params.tan_half_fov;
    float sy = (1.0 - 2.0 * (float(py) + jitter.y) / float(params.height)) * params.tan_half_fov;
    return normalize(params.forward + sx * params.right + sy * params.up);
}

// Whether the shadow ray o + t w, t < d, is blocked. One that runs out of traversal steps answers yes: it is
// counted here, as an eye path is, and the caller must then check bvh_spent and bvh_cut and drop the sample
// (geometry.glsl: occluded).
// `key`: the shadow ray's mask key (materials/mask.glsl).
bool shadowed(vec3 o, vec3 w, float d, uint key) {
    bool was_cut = bvh_cut;
    bool was_spent = bvh_spent;
    if (!occluded(o, w, d, key)) return false;
    if (bvh_cut && !was_cut) atomicAdd(cut.traversal_cut, 1u);
    if (bvh_spent && !was_spent) atomicAdd(cut.eye_paths, 1u);
    return true;
}

// A shadow ray prepared where a vertex samples a light (direct_light_ray, environment_ray, rough_light_ray)
// and traced apart (trace_shadow): `l` is the light it brings if nothing blocks it. A path's loop prepares
// its vertex's rays in whichever branch its kind of surface takes and traces them after the branches, so
// the kernel holds one traversal for each ray a vertex may send, not one for every kind of vertex that
// sends it: lavapipe runs every traversal a kernel holds for a SIMD group, under a mask, whether or not
// one of its lanes takes it (docs/performance.md, "One traversal per shadow ray"). Preparing draws every
// number the ray's sample needs, in the order tracing it at once did.
struct ShadowRay { vec3 o; vec3 w; float d; uint key; vec3 l; bool live; };

ShadowRay no_shadow() {
    return ShadowRay(vec3(0.0), vec3(0.0), 0.0, 0u, vec3(0.0), false);
}

// The light s brings: s.l if it is live and nothing blocks it, else 0.
vec3 trace_shadow(ShadowRay s) {
    return s.live && !shadowed(s.o, s.w, s.d, s.key) ? s.l : vec3(0.0);
}

// Term (d) at diffuse point p (nf the side its eye path arrives on, albedo its reflectance), one sample:
// a light chosen in proportion to its power, a point y uniform on it, the shadow ray towards y. Its
// estimate f_r Le G / pdf is (albedo / pi) Le (cos_p cos_y / d^2) (area / prob), and the light's flux
// (power / prob, with power = Le area pi) gives Le area / prob = flux / pi. Emitters are one-sided.
// coat_ior > 0: p is a plastic's diffuse base under a coat of that index, whose f_r also has the factor
// t(cos_p) of the light's direction (1 - F(cos_p) when smooth, coat_table 0: plastic.glsl); albedo then
// holds D t(cos_o).
// rough > 0: p is a glossy hit point on rough conductor rough - 1, seen from wo, whose f_r is its BRDF for
// the light's direction (rough_conductor.glsl); albedo then holds its specular_reflectance.
// nf is the shading normal, ng the true surface's on its side: a light on different sides of them adds
// nothing (shading.glsl).
// Prepared as a ShadowRay (traced by the caller). A shadow ray that runs out of traversal steps is counted
// (shadowed) and the caller drops the sample.
ShadowRay direct_light_ray(vec3 p, vec3 nf, vec3 ng, vec3 albedo, float coat_ior, uint coat_table, uint rough,
                           vec3 wo, inout Rng rng) {
    ShadowRay ray = no_shadow();
    Emitter e = choose_emitter(rng_float(rng));
    float a = rng_float(rng);
    float b = rng_float(rng);
    vec3 o = offset_ray(p, nf);
    // The light reaching p along w from as far as d: the estimate is f_r lflux s (with cos_p in s).
    vec3 w, lflux;
    float d, s, cos_p;
    float weight = 1.0; // an environment's multiple-importance weight against environment_ray
    if (HAS_OTHER_LIGHTS && !is_area(e)) {
        // Spheres, points, spots, the sun, the environment (lights.glsl): li / pdf per unit cos_p.
        float pdf;
        if (!light_sample(e, o, a, b, w, d, lflux, pdf)) return ray;
        cos_p = dot(nf, w);
        if (!(cos_p > 0.0)) return ray;
        s = cos_p;
        if (HAS_ENVIRONMENT && pdf > 0.0 && rough == 0u) {
            float pb = cos_p / PI; // the cosine-weighted direction's density (environment_ray)
            weight = pdf * pdf / (pdf * pdf + pb * pb); // power heuristic
        }
    } else {
        vec3 y = offset_ray(emitter_point(e, a, b), e.normal); // short of the emitter, which the ray must not hit
        w = y - o;
        float d2 = dot(w, w);
        d = sqrt(d2);
        w /= d;
        cos_p = dot(nf, w);
        float cos_y = -dot(e.normal, w);
        if (cos_p <= 0.0 || cos_y <= 0.0 || d2 <= 0.0) return ray;
        lflux = e.flux * emitter_radiance(e, a, b);
        s = cos_p * cos_y / (PI * d2);
    }
    if (HAS_SHADING_NORMALS && !shading_valid(w, ng, nf)) return ray;
    ray.key = mask_key(rng);
    vec3 fr = albedo / PI;
    if (HAS_ROUGH_CONDUCTORS && rough != 0u) {
        vec3 f;
        float sr = rough_conductor_terms(rough_view(rough - 1u, wo, nf), w, nf, f);
        fr = albedo * f * (sr / (4.0 * dot(wo, nf)));
    }
    vec3 l = fr * lflux * s;
    if (HAS_PLASTICS && coat_ior > 0.0) l *= coat_transmittance(coat_table, cos_p, coat_ior);
    if (HAS_ENVIRONMENT) l *= weight;
    if (HAS_NORMAL_MAPS) l *= bump_shadowing(w); // a bump or normal map's term (normal_map.glsl)
    return ShadowRay(o, w, d, ray.key, l, true);
}

// The environment's light at diffuse point p by the other strategy: a cosine-weighted direction (the
// diffuse BRDF's) that leaves the scene, weighted against direct_light_ray's environment samples by the
// power heuristic, so that the two together are one estimate of the environment's direct light (term
// (d)) with the lower variance of each where it is better: the map's bright spots by direct_light_ray, the
// broad sky by this. Same arguments as direct_light_ray's (a diffuse or plastic base only: a glossy hit
// point takes the environment by direct_light_ray alone, at weight 1).
ShadowRay environment_ray(vec3 p, vec3 nf, vec3 ng, vec3 albedo, float coat_ior, uint coat_table, inout Rng rng) {
    ShadowRay ray = no_shadow();
    Emitter e = first_emitter();
    if (e.kind != LIGHT_ENVIRONMENT) return ray;
    float u1 = rng_float(rng);
    float u2 = rng_float(rng);
    vec3 w = cosine_direction(nf, u1, u2);
    float cos_p = dot(nf, w);
    if (!(cos_p > 0.0)) return ray;
    if (HAS_SHADING_NORMALS && !shading_valid(w, ng, nf)) return ray;
    vec3 o = offset_ray(p, nf);
    ray.key = mask_key(rng);
    float pb = cos_p / PI;
    float pl = environment_pdf(e, w) * e.cdf;
    // f_r L cos_p / pb = albedo L.
    vec3 l = albedo * environment_radiance(e, w) * (pb * pb / (pb * pb + pl * pl));
    if (HAS_PLASTICS && coat_ior > 0.0) l *= coat_transmittance(coat_table, cos_p, coat_ior);
    if (HAS_NORMAL_MAPS) l *= bump_shadowing(w);
    return ShadowRay(o, w, infinite_reach(e, o), ray.key, l, true);
}

// Term (d) at a diffuse point or a plastic's base is direct_light_ray's ray and, with an environment,
// environment_ray's (drawn in that order); a glossy hit point's, direct_light_ray's alone. What they bring
// together: the two rays' sum.
vec3 trace_diffuse(ShadowRay light, ShadowRay sky) {
    vec3 l = trace_shadow(light);
    if (HAS_ENVIRONMENT) l += trace_shadow(sky);
    return l;
}

#include "glossy_light.glsl"

// The environment seen along d where an eye path leaves the scene (term (a)); 0 without one.
vec3 escaped(vec3 d) {
    if (!HAS_ENVIRONMENT) return vec3(0.0);
    Emitter e = first_emitter();
    return e.kind == LIGHT_ENVIRONMENT ? environment_radiance(e, d) : vec3(0.0);
}

// The uniform number that picks a smooth dielectric's branch (glass_branch, thin_branch: reflection where
// it is below the reflectance). Counted samples draw it uniformly, so each branch is taken with its
// Fresnel probability at weight 1. The pilot only marks, and takes each branch with probability 1/2: a
// light reflected in glass is met by a counted sample with probability F (about 4%) at full radiance,
// variance F L^2, as much a reason for a pixel's samples as a light seen through it; a pilot drawing by
// Fresnel finds those reflections in F of its few paths (docs/accuracy.md, "The pilot's Fresnel branches").
const float ONE_BELOW = 0.99999994; // the largest float below 1: refraction unless totally reflected
float branch_u(inout Rng rng) {
    float u = rng_float(rng);
    return pc.pilot == 0u ? u : (u < 0.5 ? 0.0 : ONE_BELOW);
}

// The cells of a pixel for `count` samples: m columns and n rows, m = floor(sqrt(count)), n = ceil(count /
// m) (count 4: 2 x 2; 16: 4 x 4; 1: the whole pixel). The square root of an integer this small, correctly
// rounded, has that floor.
uvec2 strata_grid(uint count) {
    uint m = max(uint(sqrt(float(count))), 1u);
    return uvec2(m, (count + m - 1u) / m);
}

// The position in the pixel of sample `index` of those stratified over `grid`: the samples take the cells
// in raster order from cell `shift` on (wrapping), each a uniform point `u` in its cell. With `shift`
// uniform over the cells, each sample's cell is uniform over them, so each position is uniform over the
// pixel and each sample stays an unbiased sample of the pixel's terms; together they cover the pixel
// evenly, which takes the variance over its area (texture, edges, penumbrae) down
// (docs/accuracy.md, "Stratified positions in the pixel").
vec2 stratum_point(uint index, uvec2 grid, uint shift, vec2 u) {
    uint cell = (index + shift) % (grid.x * grid.y);
    return (vec2(float(cell % grid.x), float(cell / grid.x)) + u) * (vec2(1.0) / vec2(grid));
}

// Whether the ray (o, d) passes within NEAR_REACH times the radius of the sphere around an area light
// (emitter_bounds), ahead of o. A ratio of lengths, so a scaled scene marks the same pixels. Read from the
// buffer, only the first NEAR_LIGHTS_MAX lights are looked at: the marks only move samples, so a light
// past them costs noise, never bias.
const float NEAR_REACH = 2.0;
const uint NEAR_LIGHTS_MAX = 64u;
bool near_light(Emitter e, vec3 o, vec3 d) {
    vec3 c;
    float rb;
    if (!emitter_bounds(e, c, rb)) return false;
    vec3 v = c - o;
    float t = dot(v, d);
    float reach = NEAR_REACH * rb;
    return (t > 0.0 ? dot(v, v) - t * t : dot(v, v)) < reach * reach;
}

bool passes_near_light(vec3 o, vec3 d) {
    bool near = false;
#ifdef SCENE_INLINE_LIGHTS
    [[unroll]] for (uint i = 0u; i < min(NUM_LIGHTS, NEAR_LIGHTS_MAX); i++) {
        near = near || near_light(SCENE_EMITTERS[i], o, d);
    }
#else
    uint n = min(params.num_lights, NEAR_LIGHTS_MAX);
    for (uint i = 0u; i < n && !near; i++) near = near_light(emitter_of(lights[i]), o, d);
#endif
    return near;
}

// One emission sample: the emission met along the specular chain from the eye through its position
// (sample `index` of the pixel's, stratum_point over `grid` from `shift`), and with direct light sampled,
// term (d) at the chain's diffuse end. `seen`: set if the path met the front of an
// emitter (or the environment) that no shadow ray also takes, i.e. not straight after a rough vertex;
// `lit`: set if its shadow ray reached a light; `rough`: set if it sampled through a rough conductor or
// rough glass (rough_vertex); `chain`: set past a mirror, smooth glass or a smooth coat; `near`, in the
// pilot: set where such a chain, after a curved vertex, passed near a light (MARK_NEAR); `curved`, in the
// pilot: set where such a chain followed a curved vertex (MARK_CURVED).
vec3 emission_sample(uint px, uint py, uint index, uvec2 grid, uint shift, inout Rng rng, inout bool seen,
                     inout bool lit, inout bool rough, inout bool chain, inout bool near, inout bool curved) {
    vec2 u = vec2(rng_float(rng), rng_float(rng));
    vec2 jitter = stratum_point(index, grid, shift, u);
    vec3 o = params.eye;
    vec3 d = camera_ray(px, py, jitter);
    vec3 thr = vec3(1.0);
    vec3 sum = vec3(0.0); // term (d) at the plastics passed on the way
    vec3 vng = d, vns = d; // the last vertex's normals, which d must lie on the same side of (shading.glsl)
    bump_alpha2 = 0.0;
    // Where d left a rough vertex: its lobe's density of d and the vertex (glossy_light.glsl); 0 else.
    float lobe_pdf = 0.0;
    vec3 lobe_from = vec3(0.0);
    bool bent = false; // the path met a curved vertex (MARK_NEAR)
    for (uint depth = 0u;; depth++) {
        bvh_sync();
        // Past the first vertex without a lobe's density: the path left a mirror, glass or a smooth coat.
        if (depth > 0u && !(lobe_pdf > 0.0)) {
            chain = true;
            if (pc.pilot != 0u && bent) {
                curved = true;
                if (!near) near = passes_near_light(o, d);
            }
        }
        if (HAS_SHADING_NORMALS && !shading_valid(d, vng, vns)) break;
        // The last vertex's bump or normal map term for the direction the path leaves it along.
        if (HAS_NORMAL_MAPS) { thr *= bump_shadowing(d); bump_alpha2 = 0.0; }
        if (depth >= params.max_eye_depth) { atomicAdd(cut.eye_paths, 1u); break; }
        Hit h;
        if (!intersect_scene(o, d, 0.0, 1e30, mask_key(rng), h)) {
            if (bvh_cut) atomicAdd(cut.traversal_cut, 1u);
            if (bvh_spent) atomicAdd(cut.eye_paths, 1u);
            if (HAS_ENVIRONMENT && !bvh_cut && !bvh_spent) {
                vec3 e = thr * escaped(d) * escape_weight(lobe_pdf, d);
                if (max3(e) > 0.0 && !(lobe_pdf > 0.0)) seen = true;
                sum += e;
            }
            break;
        }
        resolve_blend(h, rng); // before anything reads the hit's material (blend.glsl)
        Material m = material(h.material);
        apply_texture(m, h);
        bool front = dot(d, h.normal) < 0.0;
        vec3 ng = front ? h.normal : -h.normal;
        vec3 nf = shading_normal(h, ng);
        if (HAS_SHADING_NORMALS && !shading_valid(d, ng, nf)) break;
        // Curved: a sphere, or a shading normal more than 0.8 degrees off the face (a flat face's own
        // interpolated normals are not, but for rounding).
        bent = bent || h.kind == HIT_SPHERE || dot(nf, ng) < 0.9999;
        vng = ng;
        vns = nf;
        float lobe_in = lobe_pdf;
        lobe_pdf = 0.0;
        // This vertex's shadow rays, prepared by its kind of surface and traced after the branches
        // (ShadowRay): `light` (and with an environment `sky`) for term (d) at a diffuse point, a glossy
        // hit point or a plastic's base, or for the light a rough vertex reflects; `lobe` for a rough
        // coat's, the one vertex that sends two (a scene without rough plastics has no such traversal).
        ShadowRay light = no_shadow(), sky = no_shadow(), lobe = no_shadow();
        vec3 vthr = thr;     // the path's weight at this vertex (thr goes on with the path)
        vec3 e = vec3(0.0);  // the emission here, where the path ends here
        bool diffuse = m.surface == SURFACE_DIFFUSE;
        bool glossy = HAS_ROUGH_CONDUCTORS && m.surface == SURFACE_ROUGH_CONDUCTOR && glossy_hit(h.material);
        bool plastic = HAS_PLASTICS && m.surface == SURFACE_PLASTIC;
        bool ends = diffuse || glossy; // the path ends here (at a glossy hit point the photons have the rest)
        bool stops = false;  // a rough vertex's lobe left the path no weight
        // One preparation of each kind of ray serves every kind of vertex, as one traversal does
        // (lavapipe runs every copy under a mask); each vertex still draws its numbers in the order it
        // did when its branch prepared its own.
        vec3 albedo = m.color; // the reflectance term (d) takes here
        float coat_ior = 0.0;
        uint table = 0u;
        vec3 spec = vec3(0.0), coat_d = d;
        vec3 wo = -d;
        if (diffuse) {
            // Emitters are one-sided; after a rough vertex the emission is weighed against its shadow ray,
            // and marks nothing: `seen` is for the emission no shadow ray takes (lobe_in 0).
            e = front ? thr * m.emission * lobe_weight(lobe_in, lobe_from, h, m.emission) : vec3(0.0);
            if (max(e.r, max(e.g, e.b)) > 0.0 && !(lobe_in > 0.0)) seen = true;
        } else if (plastic) {
            // Both lobes, without a choice between them: the base's term (d) by its shadow ray here, and
            // the path goes on along the coat's reflection (term (a) and (d) further along its chain).
            // Plastic does not emit.
            table = HAS_ROUGH_PLASTICS ? material_table(h.material) : 0u;
            plastic_lobes(h.material, m, table, nf, rng, coat_d, spec, albedo);
            coat_ior = m.ior;
        }
        // Term (d): at a diffuse point, a glossy hit point (by its BRDF) and a plastic's base.
        if (params.direct_light != 0u && (ends || plastic)) {
            light = direct_light_ray(h.pos, nf, ng, albedo, coat_ior, table, glossy ? h.material + 1u : 0u, wo, rng);
            if (HAS_ENVIRONMENT && !glossy) sky = environment_ray(h.pos, nf, ng, albedo, coat_ior, table, rng);
        }
        // A rough vertex, or a plastic's rough coat (glossy_light.glsl): the light it reflects straight from
        // an emitter by a shadow ray, then the lobe's direction, whose emission met next is weighed
        // against it.
        bool coat_rough = plastic && rough_coat(m, table);
        bool rough_here = coat_rough || rough_vertex(m, h.material);
        if (rough_here) {
            ShadowRay r = rough_light_ray(h.material, m, h, nf, ng, front, wo, rng);
            if (coat_rough) lobe = r; else light = r;
        }
        if (plastic) {
            thr *= spec;
            d = coat_d;
            o = offset_ray(h.pos, nf);
        } else if (rough_here) {
            rough = true;
            lobe_bounce(h.material, m, 0u, h, nf, front, false, rng, o, d, thr);
            stops = max3(thr) <= 0.0;
        } else if (!ends) {
            if (is_reflector(m.surface)) {
                thr *= reflector_weight(h.material, m, -dot(d, nf));
                d = reflect(d, nf);
                o = offset_ray(h.pos, nf);
            } else if (HAS_THIN && m.surface == SURFACE_THIN) {
                thr *= thin_branch(h.material, m, h.pos, nf, branch_u(rng), o, d);
            } else {
                glass_branch(h.pos, nf, front, m.ior, branch_u(rng), o, d);
            }
        }
        if (rough_here && !stops) {
            lobe_pdf = lobe_density(h.material, m, h, nf, front, wo, d);
            lobe_from = h.pos;
        }
        // The shadow rays, added to the sums in the order the branches added them when they traced their
        // own.
        if (light.live || sky.live) {
            vec3 l = trace_diffuse(light, sky);
            if (max3(l) > 0.0) lit = true;
            if (ends) e += vthr * l; else sum += vthr * l;
        }
        if (HAS_ROUGH_PLASTICS && lobe.live) {
            vec3 l = trace_shadow(lobe);
            if (max3(l) > 0.0) lit = true;
            sum += vthr * l;
        }
        if (bvh_spent || bvh_cut) break; // counted by shadowed; the sample is dropped
        if (ends) return sum + e;
        if (stops) break;
    }
    return sum;
}

void main() {
    load_params();
    uint local = invocation_index();
    if (local >= pc.tile_pixels) return;
    uint pixel = pc.first_pixel + local;
    uint px = pixel % params.width;
    uint py = pixel / params.width;
    uint64_t pixels = uint64_t(params.width * params.height);
    uint64_t stream = uint64_t(pc.pass) * pixels + uint64_t(pixel);
    dvec3 emitted = dvec3(0.0);
    uint samples = 0u;
    bvh_left = params.eye_bvh_budget;

    if (pc.trace_hits != 0u) {
        Rng rng = rng_new(uint64_t(params.seed) | (uint64_t(pc.salt) << 32), stream);
        vec2 jitter = pc.jitter;
        if (jitter.x < 0.0) {
            jitter.x = rng_float(rng);
            jitter.y = rng_float(rng);
        }
        Pending stack[MAX_SLOTS];
        uint sp = 0u;
        stack[sp++] = Pending(params.eye, camera_ray(px, py, jitter), vec3(1.0), 0u, 0.0, vec3(0.0));
        uint slot = 0u;
        vec3 hit_emitted = vec3(0.0);
        // A sample at a fixed point of the pixel (PPM's centre) would bias the box-filtered terms (a) and
        // (d): it counts only when no random sample does.
        bool hit_is_sample = pc.jitter.x < 0.0 || pc.emission_samples == 0u;
        uint base_slot = local * params.hit_slots;
        // SPPM's split happens once, at the camera path's first rough vertex: a branch that ends without
        // a hit point (escaping, or at the depth backstop in a closed rough-metal furnace) must not let the
        // next one split again, or the branches would multiply along the path.
        bool may_split = params.rough_split != 0u;
        // The slots glass, panes and plastics may split into both branches: all of them in PPM, none where
        // they are the rough vertex's (one branch each there).
        uint branch_slots = params.rough_split != 0u ? 1u : params.hit_slots;
        // SPPM (hit points at random points of the pixel) splits at glass only in the pixels the renderer
        // marked MARK_SPLIT, whose split slots alone the gather and the update visit: a slot the rest would
        // leave empty still costs lavapipe a thread of each. The marks are fixed before any counted path.
        if (pc.jitter.x < 0.0 && (busy[local] & MARK_SPLIT) == 0u) branch_slots = 1u;

        while (sp > 0u) {
            Pending r = stack[--sp];
            // The last vertex's normals, which r.d must lie on the same side of (shading.glsl); a branch
            // is stacked only where it does.
            vec3 vng = r.d, vns = r.d;
            bump_alpha2 = 0.0; // a stacked branch took its vertex's term when stacked
            // Where r.d left a rough vertex: its lobe's density of r.d and the vertex (glossy_light.glsl).
            float lobe_pdf = r.lobe_pdf;
            vec3 lobe_from = r.lobe_from;
            for (;;) {
                bvh_sync();
                if (HAS_SHADING_NORMALS && !shading_valid(r.d, vng, vns)) break;
                // The last vertex's bump or normal map term for the direction the path leaves it along.
                if (HAS_NORMAL_MAPS) { r.thr *= bump_shadowing(r.d); bump_alpha2 = 0.0; }
                if (r.depth >= params.max_eye_depth) { atomicAdd(cut.eye_paths, 1u); break; }
                Hit h;
                if (!intersect_scene(r.o, r.d, 0.0, 1e30, mask_key(rng), h)) {
                    if (bvh_cut) atomicAdd(cut.traversal_cut, 1u);
                    if (bvh_spent) { atomicAdd(cut.eye_paths, 1u); sp = 0u; } // no budget for the rest
                    if (HAS_ENVIRONMENT) hit_emitted += r.thr * escaped(r.d) * escape_weight(lobe_pdf, r.d); // term (a) (dropped if cut)
                    break;
                }
                resolve_blend(h, rng); // before anything reads the hit's material (blend.glsl)
                Material m = material(h.material);
                apply_texture(m, h);
                bool front = dot(r.d, h.normal) < 0.0;
                vec3 ng = front ? h.normal : -h.normal;
                vec3 nf = shading_normal(h, ng);
                if (HAS_SHADING_NORMALS && !shading_valid(r.d, ng, nf)) break;
                vng = ng;
                vns = nf;
                float lobe_in = lobe_pdf;
                lobe_pdf = 0.0;
                bool diffuse = m.surface == SURFACE_DIFFUSE;
                bool glossy = HAS_ROUGH_CONDUCTORS && m.surface == SURFACE_ROUGH_CONDUCTOR && glossy_hit(h.material);
                bool plastic = HAS_PLASTICS && m.surface == SURFACE_PLASTIC;
                // This vertex's shadow rays where this path is one of the samples, traced after the branches
                // (ShadowRay, as emission_sample): `light` and `sky` for term (d) or a rough vertex's light,
                // weighted r.thr as the vertex found it (vthr); `lobe` for a rough coat's, weighted vthr
                // times coat_scale.
                ShadowRay light = no_shadow(), sky = no_shadow(), lobe = no_shadow();
                vec3 vthr = r.thr;
                bool ends = false; // the path ends at this vertex, once its shadow rays are traced
                // A diffuse surface, or a plastic's base under its coat: the hit point and term (d). A
                // plastic keeps both lobes while the pixel has slots for the reflection's path and those
                // pending (the base's hit point, weighted D (1 - F(cos_o)) / pi, and the coat's reflection,
                // weighted ks F(cos_o)), else one, chosen in proportion to its largest weight. A glossy hit
                // point (rough_conductor.glsl): term (d) by its BRDF, the hit point whose gather evaluates
                // the BRDF per photon; the path ends there.
                vec3 diff = m.color, spec = vec3(0.0);
                bool base = diffuse || plastic, coat = false;
                uint table = 0u;
                vec3 coat_d = r.d;
                float coat_scale = 1.0; // 1 / the probability of the coat where one lobe is chosen
                vec3 wo = -r.d;
                float cos_o = dot(wo, nf);
                if (diffuse) {
                    // Emitters are one-sided; after a rough vertex weighed against its shadow ray.
                    if (front) hit_emitted += r.thr * m.emission * lobe_weight(lobe_in, lobe_from, h, m.emission);
                } else if (plastic) {
                    table = HAS_ROUGH_PLASTICS ? material_table(h.material) : 0u;
                    plastic_lobes(h.material, m, table, nf, rng, coat_d, spec, diff);
                    coat = true;
                    if (slot + sp + 1u >= branch_slots) {
                        if (!(max3(spec) + max3(diff) > 0.0)) break;
                        float ps = max3(spec) / (max3(spec) + max3(diff));
                        coat = rng_float(rng) < ps;
                        base = !coat;
                        if (coat) spec /= ps; else diff /= 1.0 - ps;
                        if (coat) coat_scale = 1.0 / ps;
                    }
                } else if (glossy && !(cos_o > 0.0)) {
                    break;
                }
                // Term (d) for this path, where it is one of the samples (below); one preparation for every
                // kind of vertex that takes it, each drawing its numbers where its own branch did.
                if ((base || glossy) && params.direct_light != 0u && hit_is_sample) {
                    float coat_ior = plastic ? m.ior : 0.0;
                    light = direct_light_ray(h.pos, nf, ng, diff, coat_ior, table, glossy ? h.material + 1u : 0u, wo, rng);
                    if (HAS_ENVIRONMENT && !glossy) sky = environment_ray(h.pos, nf, ng, diff, coat_ior, table, rng);
                }
                if (base) {
                    if (max3(diff) > 0.0 && slot < params.hit_slots) {
                        hit_points[base_slot + slot] = HitPoint(h.pos, pixel, nf, 0u, r.thr * diff / PI, 0u);
                        slot++;
                    }
                    ends = !coat;
                }
                if (glossy) {
                    if (slot < params.hit_slots) {
                        vec3 w = rough_conductor_hit_weight(h.material, m.color, r.thr, cos_o);
                        hit_points[base_slot + slot] = HitPoint(h.pos, pixel, nf, h.material + 1u, w, oct_encode(wo));
                        slot++;
                    }
                    ends = true;
                }
                // A rough coat followed, or a rough vertex (glossy_light.glsl): its shadow ray where this path
                // is a sample, weighed as the lobe is, then the lobe's direction.
                bool coat_rough = plastic && !ends && rough_coat(m, table);
                bool lobe_vertex = !ends && rough_vertex(m, h.material); // a rough conductor or rough glass
                bool rough_here = coat_rough || lobe_vertex;
                if (rough_here && hit_is_sample) {
                    ShadowRay sr = rough_light_ray(h.material, m, h, nf, ng, front, wo, rng);
                    if (coat_rough) lobe = sr; else light = sr;
                }
                if (ends) {
                    // A diffuse point or a glossy hit point: nothing follows.
                } else if (plastic || rough_here) {
                    // The coat's reflection, or a rough vertex's lobe. SPPM's split (params.rough_split): the
                    // first rough vertex draws a direction of its lobe for every slot (glass and plastics take
                    // one branch there, so the stack is empty and no slot is taken yet), each branch weighted
                    // 1 / k, so the light seen through the lobe gets k hit points a pass; their sum is one
                    // sample of it (each branch's terms (a) and (d) too). The k - 1 stacked first, in order;
                    // this path takes the last. One loop for all of them, so that the kernel holds one copy
                    // of the lobe's sampling and density (lavapipe runs every copy).
                    r.depth++;
                    uint k = lobe_vertex && may_split ? params.hit_slots : 1u;
                    if (lobe_vertex) may_split = false;
                    r.thr /= float(k);
                    Pending own = Pending(r.o, r.d, r.thr, r.depth, 0.0, h.pos);
                    for (uint j = 1u; j <= k; j++) {
                        Pending b = Pending(r.o, r.d, r.thr, r.depth, 0.0, h.pos);
                        if (plastic) {
                            b.thr *= spec;
                            b.d = coat_d;
                            b.o = offset_ray(h.pos, nf);
                        } else {
                            lobe_bounce(h.material, m, 0u, h, nf, front, false, rng, b.o, b.d, b.thr);
                        }
                        bool mine = j == k;
                        if (!mine && !(max3(b.thr) > 0.0)) continue;
                        if (!mine && HAS_SHADING_NORMALS && !shading_valid(b.d, ng, nf)) continue;
                        if (!mine && HAS_NORMAL_MAPS) b.thr *= bump_shadowing(b.d);
                        bool weighed = rough_here && hit_is_sample && (!mine || plastic || !(max3(b.thr) <= 0.0));
                        if (weighed) b.lobe_pdf = lobe_density(h.material, m, h, nf, front, wo, b.d);
                        if (mine) own = b; else stack[sp++] = b;
                    }
                    r.o = own.o;
                    r.d = own.d;
                    r.thr = own.thr;
                    ends = lobe_vertex && max3(r.thr) <= 0.0;
                    if (rough_here && !ends) {
                        lobe_pdf = own.lobe_pdf;
                        lobe_from = h.pos;
                    }
                } else if (HAS_THIN && m.surface == SURFACE_THIN) {
                    r.depth++;
                    // As glass: both branches while the pixel has slots, else one.
                    float rr = thin_reflectance(-dot(r.d, nf), m.ior);
                    if (rr < 1.0 && slot + sp + 1u < branch_slots) {
                        vec3 refl = reflect(r.d, nf);
                        if (!HAS_SHADING_NORMALS || shading_valid(refl, ng, nf))
                            stack[sp++] = Pending(offset_ray(h.pos, nf), refl, r.thr * (rr * m.color) * bump_shadowing(refl), r.depth, 0.0, vec3(0.0));
                        r.thr *= (1.0 - rr) * material_term_a(h.material);
                        r.o = offset_ray(h.pos, -nf);
                    } else {
                        r.thr *= thin_branch(h.material, m, h.pos, nf, rng_float(rng), r.o, r.d);
                    }
                } else if (is_reflector(m.surface)) {
                    r.depth++;
                    r.thr *= reflector_weight(h.material, m, -dot(r.d, nf));
                    r.d = reflect(r.d, nf);
                    r.o = offset_ray(h.pos, nf);
                } else {
                    r.depth++;
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
                    } else if (slot + sp + 1u < branch_slots) {
                        if (!HAS_SHADING_NORMALS || shading_valid(refl, ng, nf))
                            stack[sp++] = Pending(offset_ray(h.pos, nf), refl, r.thr * f * bump_shadowing(refl), r.depth, 0.0, vec3(0.0));
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
                // The shadow rays, added to the sums in the order the branches added them when they traced
                // their own. One that runs out of the budget ends this path and the pixel's others (counted
                // by shadowed).
                if (light.live || sky.live) {
                    hit_emitted += vthr * trace_diffuse(light, sky);
                    if (bvh_spent) { sp = 0u; ends = true; }
                }
                if (HAS_ROUGH_PLASTICS && lobe.live && !bvh_spent) {
                    hit_emitted += vthr * coat_scale * trace_shadow(lobe);
                    if (bvh_spent) { sp = 0u; ends = true; }
                }
                if (ends) break;
            }
        }
        for (; slot < params.hit_slots; slot++) {
            hit_points[base_slot + slot] = HitPoint(vec3(0.0), 0xffffffffu, vec3(0.0), 0u, vec3(0.0), 0u);
        }
        if (hit_is_sample && !bvh_spent && !bvh_cut) {
            emitted += dvec3(hit_emitted);
            samples++;
        }
    }

    Rng erng = rng_new(uint64_t(params.seed) | (uint64_t(SALT_EMISSION) << 32), (uint64_t(pc.chunk) << 48) | stream);
    // Only whole samples count: once long paths have spent the thread's BVH budget (bvh_spent, counted),
    // the remaining samples are not taken rather than taken as black.
    // How many (reference::samples_for_mark, the CPU twin's rule): pc.rough_samples where the pilot
    // sampled through a rough lobe (whose light, by shadow rays and the lobe, is the noisiest term there,
    // docs/accuracy.md, "Eye paths through rough lobes"); all of emission_samples where it saw emission or
    // a curved chain passed near a light (MARK_NEAR); with direct light sampled, light_samples where one of
    // its shadow rays reached a light and one where none did (in the umbra, or where no light is in direct
    // view: the shadow rays there would add nothing); else light_samples.
    uint mark = busy[local];
    uint total = pc.light_samples;
    if (pc.pilot != 0u) total = pc.emission_samples;
    else if ((mark & MARK_ROUGH) != 0u) total = pc.rough_samples;
    else if ((mark & (MARK_EMISSION | MARK_NEAR)) != 0u) total = pc.emission_samples;
    else if (params.direct_light != 0u && pc.emission_samples > 0u && (mark & MARK_LIT) == 0u) total = min(total, 1u);
    uint first = pc.chunk * pc.per_dispatch;
    uint want = total > first ? min(total - first, pc.per_dispatch) : 0u;
    bool seen = false;
    bool lit = false;
    bool rough = false;
    bool near = false;
    bool curved = false;
    // The pilot takes pc.pilot_samples in every pixel, and the rest of its count only where one of them (or
    // an earlier dispatch's) left a mirror, glass or a smooth coat: what such a chain shows of a light can
    // be an image a pixel wide, which a few samples miss, while a light seen straight or through a rough
    // lobe is found by few and spread to the neighbours (docs/performance.md, "The pilot's samples").
    bool chain = pc.pilot != 0u && (mark & MARK_CHAIN) != 0u;
    // The positions of this pass's `total` samples, stratified (stratum_point); the pilot's, which only
    // mark, are uniform. The first cell comes from a stream of its own, the same in every dispatch of the
    // pass.
    uvec2 grid = strata_grid(pc.pilot != 0u ? 1u : max(total, 1u));
    uint cells = grid.x * grid.y;
    Rng srng = rng_new(uint64_t(params.seed) | (uint64_t(SALT_STRATA) << 32), stream);
    uint shift = min(uint(rng_float(srng) * float(cells)), cells - 1u);
    for (uint s = 0u; s < want; s++) {
        if (bvh_spent || bvh_cut) break;
        if (pc.pilot != 0u && first + s >= pc.pilot_samples && !chain) break;
        vec3 e = emission_sample(px, py, first + s, grid, shift, erng, seen, lit, rough, chain, near, curved);
        if (bvh_spent || bvh_cut) break;
        if (pc.pilot != 0u) continue;
        emitted += dvec3(e);
        samples++;
    }
    if (pc.pilot != 0u) {
        busy[local] |= (seen ? MARK_EMISSION : 0u) | (lit ? MARK_LIT : 0u) | (rough ? MARK_ROUGH : 0u)
            | (chain ? MARK_CHAIN : 0u) | (near ? MARK_NEAR : 0u) | (curved ? MARK_CURVED : 0u);
    }
    if (samples > 0u) direct[local] += dvec4(emitted, double(samples));
}

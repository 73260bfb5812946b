// Ray intersection with the scene (analytic spheres and parallelograms, and triangles through the BVH),
// through the accessors of bindings.glsl.
#ifndef GEOMETRY_GLSL
#define GEOMETRY_GLSL
// The traversal asks bvh_filter (below) about each triangle hit: a masked surface may let the ray pass.
#define BVH_FILTER
#include "bvh.glsl"
#include "sampling.glsl"

// BVH traversal steps this thread's subgroup may still take (lavapipe's loop budget, less what the
// kernel's other loops may take: PathLimits). Kernels set bvh_left at the start and call bvh_sync() at the
// top of every loop iteration that may intersect, so all active lanes agree on what the subgroup has used.
// A traversal that runs out of steps ends its path, in one of two ways:
//   bvh_cut:   it had at least BVH_TRAVERSAL_MIN steps and needed more: the BVH is degenerate, an error;
//   bvh_spent: long paths (glass that traps light by internal reflection) had used up the budget: the
//              path ends there, counted as a path cut at a backstop, like the depth limits.
uint bvh_left = 0xffffffffu;
bool bvh_cut = false;
bool bvh_spent = false;
const uint BVH_TRAVERSAL_MIN = 8192u;

void bvh_sync() {
    if (NUM_TRIANGLES > 0u) bvh_left = subgroupMin(bvh_left);
}

// A point moved off a surface along n, far enough that the next ray does not hit the surface it left: a
// multiple of the f32 spacing at the point's coordinates (which grows with its distance from the origin)
// plus a small floor relative to the scene. Both follow a uniform scale of the scene. (A fixed fraction of
// the scene's size was wrong for a scene with one huge primitive: a 1000 m floor made it 10 cm.)
vec3 offset_ray(vec3 p, vec3 n) {
    return p + (params.eps_rel * max(max(abs(p.x), abs(p.y)), abs(p.z)) + params.eps) * n;
}

// One branch at a smooth dielectric, reflection with probability f (Fresnel) else refraction: the
// branch's weight f / f = 1 leaves the path's throughput as it is. `u` uniform in [0, 1); nf faces the
// incoming ray; o and d become the new ray.
void glass_branch(vec3 pos, vec3 nf, bool front, float ior, float u, inout vec3 o, inout vec3 d) {
    float eta = front ? 1.0 / ior : ior;
    float cos_i = -dot(d, nf);
    float cos_t;
    float f = fresnel_dielectric(cos_i, eta, cos_t);
    if (u < f) {
        d = reflect(d, nf);
        o = offset_ray(pos, nf);
    } else {
        d = normalize(eta * d + (eta * cos_i - cos_t) * nf);
        o = offset_ray(pos, -nf);
    }
}

// Mitsuba's dp/du and dp/dv of a sphere of radius r at unit normal n (src/shapes/sphere.cpp: u the
// longitude about z over 2 pi, v the colatitude over pi; at a pole dp/dv's direction is x).
void sphere_derivatives(vec3 n, float r, out vec3 dpdu, out vec3 dpdv) {
    float rd = sqrt(n.x * n.x + n.y * n.y);
    dpdu = (2.0 * PI * r) * vec3(-n.y, n.x, 0.0);
    dpdv = rd > 0.0 ? (PI * r) * vec3(n.z * n.x / rd, n.z * n.y / rd, -rd) : (PI * r) * vec3(1.0, 0.0, 0.0);
}

struct Hit {
    float t;
    vec3 pos;
    vec3 normal;     // geometric normal: outward for spheres, the front normal for quads and triangles
    uint material;
    uint kind;       // HIT_*
    uint prim;       // a triangle's index in the BVH's leaf order
    vec2 local;      // a quad's planar coordinates (its texture coordinates), a triangle's barycentric
                     // weights of v1 and v2 (texture.glsl's surface_uv reads them)
    vec3 dpdu;       // a quad's edge_u, a triangle's v1 - v0, where a scene has anisotropic surfaces
                     // (surface_tangent) or normal maps; a sphere's dp/du where it has normal maps
    vec3 dpdv;       // where a scene has normal maps (normal_map.glsl): a quad's edge_v, a triangle's
                     // v2 - v0, a sphere's dp/dv
};

const uint HIT_QUAD = 0u;     // hit.normal set in the loop
const uint HIT_SPHERE = 1u;
const uint HIT_TRIANGLE = 2u; // hit.normal from the triangle's vertices, after the loops

// materials/mask.glsl, included at the end of this file (it reads texture.glsl, which reads Hit).
// `prim` keys the hash: a triangle's index in the BVH's leaf order as it is, a quad's and a sphere's side
// (0 near, 1 far) above the triangles' (ppm_vk_materials::mask::PRIM_*).
const uint MASK_PRIM_QUAD = 0x80000000u;
const uint MASK_PRIM_SPHERE = 0x40000000u;
bool mask_keeps(uint m, uint key, uint prim, Hit h);

// The mask key (materials/mask.glsl) of the ray trace_scene is tracing, for bvh_filter.
uint trace_key = 0u;

// Whether the ray stops at triangle `tri` (leaf order) of material m at barycentric weights `bary`, or
// passes a masked surface there.
bool triangle_stops(uint tri, uint m, vec2 bary) {
    if (!HAS_MASKS) return true;
    Hit h;
    h.kind = HIT_TRIANGLE;
    h.prim = tri;
    h.local = bary;
    return mask_keeps(m, trace_key, tri, h);
}

// bvh.glsl's any-hit filter.
bool bvh_filter(BvhRay r, uint tri, uint m, vec2 bary) {
    return triangle_stops(tri, m, bary);
}

// Where o + t d meets the plane through `origin` spanned by e1 and e2, for t in (tmin, tmax): t and the
// point's coordinates (a, b) = ab, point = origin + a e1 + b e2 (a quad's test, Shirley's trick). A
// degenerate plane (e1 x e2 = 0) or a ray along it gives no finite t: false.
bool plane_hit(vec3 o, vec3 d, vec3 origin, vec3 e1, vec3 e2, float tmin, float tmax, out float t, out vec2 ab) {
    vec3 n = cross(e1, e2);
    t = dot(n, origin - o) / dot(n, d);
    ab = vec2(0.0);
    if (!(t > tmin && t < tmax)) return false;
    vec3 rel = o + t * d - origin;
    vec3 w = n / dot(n, n);
    ab = vec2(dot(w, cross(rel, e2)), dot(w, cross(e1, rel)));
    return true;
}

// A triangle written into the kernel (specialize.rs, a small mesh) by its plane, as a quad is tested: t
// where the ray meets the plane, then the point's weights of v1 and v2 (bary) from the edges. Its edges,
// normal and 1 / |n|^2 are constants there, so the compiler folds them into the test (an axis-aligned
// wall's to a few operations), which the BVH's watertight test, permuted by the ray's own axes, does not
// allow: cornell-mesh's eye pass took 2.2-2.4x cornell-spheres' with it, 1.1-1.4x by planes and pairs
// (inline_pair_test below; docs/performance.md, "Small meshes by their planes"). Not watertight: a ray
// within an ulp or so of an edge two triangles share can miss both, as at the edge of two quads.
// Two-sided; a degenerate triangle (n = 0) or a ray in its plane gives no finite t and no hit.
// CPU twin: reference::trace::inline_triangle_test.
bool inline_triangle_test(vec3 o, vec3 d, Triangle tr, float tmin, float tmax, out float t, out vec2 bary) {
    // rel = bary.x e1 + bary.y e2
    if (!plane_hit(o, d, tr.v0, tr.v1 - tr.v0, tr.v2 - tr.v0, tmin, tmax, t, bary)) return false;
    return bary.x >= 0.0 && bary.y >= 0.0 && bary.x + bary.y <= 1.0;
}

// The weights of a pair's corners A, B, C, D (inline_pairs.rs) at its planar coordinates (a, b), in its
// first triangle (A B C, where a + b <= 1) or its second (A C D, D = A + C - B).
vec4 pair_weights(bool first, float a, float b) {
    return first ? vec4(a, 1.0 - a - b, b, 0.0) : vec4(1.0 - b, 0.0, 1.0 - a, a + b - 1.0);
}

// Two written-out triangles that make a parallelogram, tested as one (inline_pairs.rs) by its plane, as a
// quad is: which of the two the ray met (`first`), where (t) and at what weights of that triangle's v1
// and v2 (bary). Its corners are constants, as a single triangle's are. CPU twin:
// reference::trace::inline_pair_test.
bool inline_pair_test(vec3 o, vec3 d, InlinePair p, float tmin, float tmax, out float t, out bool first,
                      out vec2 bary) {
    first = true;
    bary = vec2(0.0);
    vec2 ab;
    if (!plane_hit(o, d, p.origin, p.edge_u, p.edge_v, tmin, tmax, t, ab)) return false;
    float a = ab.x, b = ab.y;
    if (!(a >= 0.0 && a <= 1.0 && b >= 0.0 && b <= 1.0)) return false;
    first = a + b <= 1.0;
    vec4 w1 = pair_weights(true, a, b);
    vec4 w2 = pair_weights(false, a, b);
    uint c = p.corners;
    bary = first ? vec2(w1[c & 3u], w1[(c >> 2u) & 3u]) : vec2(w2[(c >> 4u) & 3u], w2[(c >> 6u) & 3u]);
    return true;
}

// Whether the ray stops at distance t on sphere s (index i), its near root or, with `far`, its far one.
bool sphere_stops(Sphere s, uint i, bool far, vec3 o, vec3 d, float t) {
    if (!HAS_MASKS) return true;
    Hit h;
    h.kind = HIT_SPHERE;
    h.prim = i;
    h.normal = (o + t * d - s.center) * (1.0 / s.radius);
    return mask_keeps(s.material, trace_key, MASK_PRIM_SPHERE | (2u * i + uint(far)), h);
}

// Nearest hit with t in (tmin, tmax); false if none. What the hit needs is taken inside the loops, where
// the primitive's index is the loop's own. The tests run in a fixed order (spheres, quads, the triangles
// written out, the BVH), each only accepting a hit nearer than the best so far: the CPU reference
// (reference::trace::intersect_scene) keeps the same order, so equal distances resolve the same way.
// With `any_hit` (shadow rays, `occluded`) the BVH's traversal ends at the first hit it finds. `key` is
// the ray's mask key (materials/mask.glsl's mask_key: a masked surface lets a ray pass by it).
bool trace_scene(vec3 o, vec3 d, float tmin, float tmax, bool any_hit, uint key, out Hit hit) {
    trace_key = key;
    hit.t = tmax;
    bool found = false;
    uint kind = HIT_QUAD;
    hit.local = vec2(0.0);
    hit.prim = 0u;
    hit.dpdu = vec3(0.0);
    hit.dpdv = vec3(0.0);
    vec3 center = vec3(0.0);
    float inv_radius = 0.0;
    Triangle tri = Triangle(vec3(0.0), 0u, vec3(0.0), 0u, vec3(0.0), 0u);
    for (uint i = 0u; i < NUM_SPHERES; i++) {
        Sphere s = SPHERE(i);
        // Ray Tracing Gems, ch. 7: the discriminant as r^2 - |f|^2 (f from the centre to the ray's closest
        // point) rather than b^2 - c, which cancels to nothing for a small sphere seen from afar (a 1 cm
        // sphere 3 m away lost 12% of its shadow rays to its own fuzzy silhouette); the near root as c / q.
        vec3 oc = o - s.center;
        float b = dot(oc, d);
        vec3 f = oc - b * d;
        float r2 = s.radius * s.radius;
        float disc = r2 - dot(f, f);
        if (disc < 0.0) continue;
        float q = -(b + (b >= 0.0 ? sqrt(disc) : -sqrt(disc)));
        if (q == 0.0) continue;
        float t0 = (dot(oc, oc) - r2) / q;
        float t = min(t0, q);
        bool far = t <= tmin;
        // A masked sphere the ray passes at its near side may stop it at its far side.
        if (!far && t < hit.t && !sphere_stops(s, i, false, o, d, t)) far = true;
        if (far) t = max(t0, q);
        if (t > tmin && t < hit.t && (!far || sphere_stops(s, i, true, o, d, t))) {
            hit.t = t; found = true; kind = HIT_SPHERE;
            center = s.center; inv_radius = 1.0 / s.radius; hit.material = s.material;
        }
    }
    for (uint i = 0u; i < NUM_QUADS; i++) {
        Quad q = QUAD(i);
        float denom = dot(q.normal, d);
        if (abs(denom) < 1e-12) continue;
        float t = (q.plane_d - dot(q.normal, o)) / denom;
        if (t <= tmin || t >= hit.t) continue;
        vec3 rel = o + t * d - q.origin;
        float a = dot(q.w, cross(rel, q.edge_v));
        float b = dot(q.w, cross(q.edge_u, rel));
        if (a < 0.0 || a > 1.0 || b < 0.0 || b > 1.0) continue;
        if (q.shape == QUAD_DISK && (2.0 * a - 1.0) * (2.0 * a - 1.0) + (2.0 * b - 1.0) * (2.0 * b - 1.0) > 1.0) continue;
        if (HAS_MASKS) {
            Hit h;
            h.kind = HIT_QUAD;
            h.local = vec2(a, b);
            if (!mask_keeps(q.material, trace_key, MASK_PRIM_QUAD | i, h)) continue;
        }
        hit.t = t; found = true; kind = HIT_QUAD;
        hit.normal = q.normal; hit.material = q.material;
        hit.local = vec2(a, b);
        if (HAS_ANISOTROPY || HAS_NORMAL_MAPS) hit.dpdu = q.edge_u;
        if (HAS_NORMAL_MAPS) hit.dpdv = q.edge_v;
    }
    // A small mesh's triangles, written out (specialize.rs): those that make parallelograms two at a time
    // (inline_pair_test), then the rest one by one (inline_triangle_test), each by its plane.
    if (NUM_INLINE_TRIANGLES > 0u) {
        [[unroll]] for (uint k = 0u; k < NUM_INLINE_PAIRS; k++) {
            InlinePair p = INLINE_PAIR(k);
            float t;
            bool first;
            vec2 bary;
            if (!inline_pair_test(o, d, p, tmin, hit.t, t, first, bary)) continue;
            uint i = first ? p.first : p.second;
            // A select of two constants: INLINE_TRIANGLE(i) would index the constant array dynamically.
            Triangle tr = first ? INLINE_TRIANGLE(p.first) : INLINE_TRIANGLE(p.second);
            if (triangle_stops(i, tr.material, bary)) {
                hit.t = t; found = true; kind = HIT_TRIANGLE;
                tri = tr; hit.material = tr.material;
                hit.prim = i; hit.local = bary;
            }
        }
        [[unroll]] for (uint k = 0u; k < NUM_INLINE_SINGLES; k++) {
            uint i = INLINE_SINGLE(k);
            Triangle tr = INLINE_TRIANGLE(i);
            float t;
            vec2 bary;
            if (inline_triangle_test(o, d, tr, tmin, hit.t, t, bary) && triangle_stops(i, tr.material, bary)) {
                hit.t = t; found = true; kind = HIT_TRIANGLE;
                tri = tr; hit.material = tr.material;
                hit.prim = i; hit.local = bary;
            }
        }
    }
    // A shadow ray already stopped by an analytic primitive needs no traversal.
    if (NUM_TRIANGLES > 0u && !(any_hit && found)) {
        BvhHit bh;
        uint had = bvh_left;
        if (bvh_intersect(o, d, tmin, hit.t, bvh_left, any_hit, bh)) {
            tri = bvh_triangle(bh.triangle);
            hit.t = bh.t; found = true; kind = HIT_TRIANGLE;
            hit.material = tri.material;
            hit.prim = bh.triangle; hit.local = bh.bary;
        }
        // bvh_left is a budget, not a count of loop iterations: unlimited devices pass 0xffffffff.
        if (bvh_left != 0xffffffffu) bvh_left -= min(bvh_left, bvh_subgroup_cost(bh));
        if (bh.cut) {
            if (had >= BVH_TRAVERSAL_MIN) bvh_cut = true; else bvh_spent = true;
            return false;
        }
    }
    hit.kind = kind;
    if (found) {
        hit.pos = o + hit.t * d;
        if (kind == HIT_SPHERE) hit.normal = (hit.pos - center) * inv_radius;
        if (kind == HIT_TRIANGLE) hit.normal = bvh_normal(tri);
        if ((HAS_ANISOTROPY || HAS_NORMAL_MAPS) && kind == HIT_TRIANGLE) hit.dpdu = tri.v1 - tri.v0;
        if (HAS_NORMAL_MAPS && kind == HIT_TRIANGLE) hit.dpdv = tri.v2 - tri.v0;
        if (HAS_NORMAL_MAPS && kind == HIT_SPHERE) sphere_derivatives(hit.normal, 1.0 / inv_radius, hit.dpdu, hit.dpdv);
    }
    return found;
}

// The direction of increasing u at hit h, Mitsuba's dp/du, which an anisotropic lobe's alpha_u lies along
// (microfacet.glsl's frame): a sphere's longitude about the world's z axis, a quad's first edge (the Mitsuba
// reader keeps a rectangle's x axis there), a triangle's from its texture coordinates where its mesh has
// them, else its first edge v1 - v0 (Mitsuba then parameterises it by its barycentric coordinates). Not
// unit. Checked against Mitsuba's shading frames on each kind of shape (reference::trace's tests).
vec3 surface_tangent(Hit h) {
    if (h.kind == HIT_SPHERE) return vec3(-h.normal.y, h.normal.x, 0.0);
    if (h.kind == HIT_TRIANGLE) {
        uvec4 t = texelFetch(triangle_texels, int(TRIANGLE_TEXELS * h.prim + 1u));
        if (t.w != 0u) return oct_decode_unnormalized(t.z);
    }
    return h.dpdu;
}

bool intersect_scene(vec3 o, vec3 d, float tmin, float tmax, uint key, out Hit hit) {
    return trace_scene(o, d, tmin, tmax, false, key, hit);
}

// Whether anything lies on o + t d for t in (0, tmax): a shadow ray. Like intersect_scene it may run out of
// traversal steps (bvh_cut, bvh_spent): then it answers true and the caller must not use the answer.
bool occluded(vec3 o, vec3 d, float tmax, uint key) {
    Hit h;
    return trace_scene(o, d, 0.0, tmax, true, key, h) || bvh_cut || bvh_spent;
}
#include "texture.glsl"
#include "materials/mask.glsl"
#endif

// Ray traversal of the triangle BVH built by crates/engine/src/bvh.rs, with the watertight ray/triangle test
// of Woop, Benthin and Wald 2013 ("Watertight Ray/Triangle Intersection", JCGT 2(1)).
// crates/engine/src/reference/bvh.rs is the same code in Rust, operation for operation: the tests compare
// hits and step counts.
//
// The including kernel declares, before including this file (at bindings of its choosing):
//   layout(std430, binding = N) readonly buffer BvhNodes { BvhNode bvh_nodes[]; };
//   layout(std430, binding = M) readonly buffer BvhTriangles { Triangle bvh_triangles[]; };
// and calls bvh_intersect(o, d, tmin, tmax, budget, hit); see there for the budget.
//
// Every product and sum that decides a hit is `precise` (no fused multiply-add): the watertight test
// relies on the two triangles of a shared edge computing exactly opposite edge functions, and on the
// GPU and the CPU reference computing the same bits.
#ifndef BVH_GLSL
#define BVH_GLSL
#extension GL_KHR_shader_subgroup_arithmetic : require

// The deepest leaf of a built BVH is at most this far below the root (bvh::MAX_DEPTH: the builder falls
// back to median splits to keep to it), so the traversal stack never holds more.
const uint BVH_MAX_DEPTH = 64u;
const uint BVH_NONE = 0xffffffffu;
const uint BVH_LEAF = 3u; // BvhNode.count_axis & 3 of a leaf
// lavapipe ends every loop of a SIMD group (8 lanes) once its loops have run this many iterations in all
// (LP_MAX_TGSI_LOOP_ITERATIONS), silently.
const uint BVH_LOOP_LIMIT = 65535u;
// 1 + 2 gamma(3), gamma(n) = n u / (1 - n u), u = 2^-24: the slab test's far distance widened by its
// rounding error bound (pbrt-v4, after Ize 2013), so rounding never loses a box the ray meets, such as one
// whose triangle the ray meets exactly at an edge on the box's face.
const float BVH_ROBUST = 1.0000003576;
// A direction component below this in magnitude makes the ray parallel to that axis's slab: inside it (its
// faces included) for every t or for none. Its reciprocal would be infinite, and infinity times the 0 of
// an origin on a face is NaN.
const float BVH_TINY = 1e-30;
// Stands for an infinite distance in the slab test (finite: no infinity arithmetic needed).
const float BVH_HUGE = 3e38;

// A ray prepared for the box and triangle tests.
struct BvhRay {
    vec3 o;
    vec3 d;
    vec3 inv_d;     // 1 / d, 0 on the parallel axes
    bvec3 parallel; // |d| < BVH_TINY
    bool any_parallel;
    uvec3 k;   // kx, ky, kz: kz the axis of the largest |d|; kx, ky swapped when d[kz] < 0 (keeps the winding)
    vec3 s;    // d[kx] / d[kz], d[ky] / d[kz], 1 / d[kz]: the shear to ray space
};

struct BvhHit {
    float t;        // distance along d, in units of |d|
    uint triangle;  // index into bvh_triangles (leaf order); BVH_NONE: no hit
    vec2 bary;      // barycentric weights of v1 and v2 at the hit (v0's is 1 - x - y)
    uint steps;     // loop steps this lane took: node visits plus triangle tests
    bool cut;       // stopped after `budget` steps with work left: the result is not final
};

BvhRay bvh_ray(vec3 o, vec3 d) {
    BvhRay r;
    r.o = o;
    r.d = d;
    vec3 ad = abs(d);
    r.parallel = lessThan(ad, vec3(BVH_TINY));
    r.any_parallel = any(r.parallel);
    r.inv_d = vec3(r.parallel.x ? 0.0 : 1.0 / d.x, r.parallel.y ? 0.0 : 1.0 / d.y, r.parallel.z ? 0.0 : 1.0 / d.z);
    uint kz = 0u;
    if (ad.y > ad[kz]) kz = 1u;
    if (ad.z > ad[kz]) kz = 2u;
    uint kx = kz == 2u ? 0u : kz + 1u;
    uint ky = kx == 2u ? 0u : kx + 1u;
    if (d[kz] < 0.0) {
        uint tmp = kx;
        kx = ky;
        ky = tmp;
    }
    r.k = uvec3(kx, ky, kz);
    // Reciprocal then products (not three divisions): lavapipe lowers a division to that, and the CPU
    // reference does the same, so both get the same bits.
    float sz = 1.0 / d[kz];
    r.s = vec3(d[kx] * sz, d[ky] * sz, sz);
    return r;
}

// Whether the ray meets the box [lo, hi] within (tmin, tmax], conservatively.
bool bvh_box_test(BvhRay r, vec3 lo, vec3 hi, float tmin, float tmax) {
    precise vec3 t0 = (lo - r.o) * r.inv_d;
    precise vec3 t1 = (hi - r.o) * r.inv_d;
    vec3 tn = min(t0, t1);
    vec3 tf = max(t0, t1);
    if (r.any_parallel) {
        bvec3 inside = bvec3(uvec3(greaterThanEqual(r.o, lo)) & uvec3(lessThanEqual(r.o, hi)));
        vec3 entry = mix(vec3(BVH_HUGE), vec3(-BVH_HUGE), inside); // inside: from -inf to +inf; else never
        tn = mix(tn, entry, r.parallel);
        tf = mix(tf, -entry, r.parallel);
    }
    float near = max(max(tn.x, tn.y), max(tn.z, tmin));
    precise float far = min(min(tf.x, tf.y), tf.z) * BVH_ROBUST;
    return near <= min(far, tmax);
}

// The watertight test: the vertices relative to the origin, permuted so the ray runs along +z, sheared so
// it is the z axis; then the 2D edge functions of the origin against each edge. Two-sided. An edge
// function that comes out exactly 0 is recomputed in double (the products of two floats are exact there,
// so its sign is exact), as the paper does. Hits with t in (tmin, tmax) only.
bool bvh_triangle_test(BvhRay r, vec3 v0, vec3 v1, vec3 v2, float tmin, float tmax, out float t, out vec2 bary) {
    precise vec3 a0 = v0 - r.o;
    precise vec3 b0 = v1 - r.o;
    precise vec3 c0 = v2 - r.o;
    vec3 a = vec3(a0[r.k.x], a0[r.k.y], a0[r.k.z]);
    vec3 b = vec3(b0[r.k.x], b0[r.k.y], b0[r.k.z]);
    vec3 c = vec3(c0[r.k.x], c0[r.k.y], c0[r.k.z]);
    precise float ax = a.x - r.s.x * a.z;
    precise float ay = a.y - r.s.y * a.z;
    precise float bx = b.x - r.s.x * b.z;
    precise float by = b.y - r.s.y * b.z;
    precise float cx = c.x - r.s.x * c.z;
    precise float cy = c.y - r.s.y * c.z;
    precise float u = cx * by - cy * bx;
    precise float v = ax * cy - ay * cx;
    precise float w = bx * ay - by * ax;
    if (u == 0.0 || v == 0.0 || w == 0.0) {
        u = float(double(cx) * double(by) - double(cy) * double(bx));
        v = float(double(ax) * double(cy) - double(ay) * double(cx));
        w = float(double(bx) * double(ay) - double(by) * double(ax));
    }
    t = 0.0;
    bary = vec2(0.0);
    if ((u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)) return false;
    precise float det = u + v + w;
    if (det == 0.0) return false; // the ray lies in the triangle's plane
    precise float az = r.s.z * a.z;
    precise float bz = r.s.z * b.z;
    precise float cz = r.s.z * c.z;
    precise float tt = u * az + v * bz + w * cz;
    float rcp = 1.0 / det;
    precise float th = tt * rcp;
    if (!(th > tmin && th < tmax)) return false;
    t = th;
    precise vec2 bv = vec2(v, w) * rcp;
    bary = bv;
    return true;
}

// The nearest triangle hit by o + t d with t in (tmin, tmax); true if there is one. d need not be unit.
// Nodes are visited depth first, the child on the side the ray comes from first (by the sign of d on the
// node's split axis). One loop step is one node visit or one triangle test, and each lane stops after
// `budget` steps with hit.cut set: its result is then not final and the caller must fail.
//
// The budget: the loop runs, for the SIMD group, as many steps as its longest lane plus one (the exit), so
// one call costs the subgroup at most budget + 1 of lavapipe's BVH_LOOP_LIMIT iterations, which all loops
// of an invocation share. A kernel with no other loops can pass BVH_LOOP_LIMIT - 1; one that calls this in
// a loop passes what its subgroup has left, e.g. `left -= bvh_subgroup_cost(hit)` after each call made by
// the whole subgroup together.
bool bvh_intersect(vec3 o, vec3 d, float tmin, float tmax, uint budget, out BvhHit hit) {
    BvhRay r = bvh_ray(o, d);
    hit.t = tmax;
    hit.triangle = BVH_NONE;
    hit.bary = vec2(0.0);
    hit.steps = 0u;
    hit.cut = false;
    uint stack[BVH_MAX_DEPTH];
    uint sp = 0u;
    uint node = 0u;               // the node to visit next; BVH_NONE: take one from the stack
    uint tri = 0u, tri_end = 0u;  // the current leaf's triangles still to test
    while (true) {
        if (tri == tri_end && node == BVH_NONE) {
            if (sp == 0u) break;
            node = stack[--sp];
        }
        if (hit.steps == budget) {
            hit.cut = true;
            break;
        }
        hit.steps++;
        if (tri != tri_end) {
            Triangle tr = bvh_triangles[tri];
            float t;
            vec2 bary;
            if (bvh_triangle_test(r, tr.v0, tr.v1, tr.v2, tmin, hit.t, t, bary)) {
                hit.t = t;
                hit.triangle = tri;
                hit.bary = bary;
            }
            tri++;
            continue;
        }
        BvhNode n = bvh_nodes[node];
        uint here = node;
        node = BVH_NONE;
        if (!bvh_box_test(r, n.lo, n.hi, tmin, hit.t)) continue;
        uint axis = n.count_axis & 3u;
        if (axis == BVH_LEAF) {
            tri = n.offset;
            tri_end = n.offset + (n.count_axis >> 2);
        } else if (r.d[axis] < 0.0) {
            stack[sp++] = here + 1u;
            node = n.offset;
        } else {
            stack[sp++] = n.offset;
            node = here + 1u;
        }
    }
    return hit.triangle != BVH_NONE;
}

// What a call of bvh_intersect cost this subgroup of lavapipe's loop budget (call it where the lanes
// that called bvh_intersect together are the active ones).
uint bvh_subgroup_cost(BvhHit hit) {
    return subgroupMax(hit.steps) + 1u;
}

// The geometric normal of a triangle from its edges v1 - v0 and v2 - v0: its front side is the one its
// vertices wind counter-clockwise on.
vec3 triangle_normal(vec3 e1, vec3 e2) {
    return normalize(cross(e1, e2));
}

vec3 bvh_normal(Triangle tr) {
    return triangle_normal(tr.v1 - tr.v0, tr.v2 - tr.v0);
}
#endif

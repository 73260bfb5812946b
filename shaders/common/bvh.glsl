// Ray traversal of the triangle BVH built by crates/engine/src/bvh/, with the watertight ray/triangle test
// of Woop, Benthin and Wald 2013 ("Watertight Ray/Triangle Intersection", JCGT 2(1)).
// crates/reference/src/bvh.rs is the same code in Rust, operation for operation: the tests compare
// hits and step counts.
//
// The including kernel declares, before including this file (at bindings of its choosing), the BVH's
// nodes (BvhNode) and triangles (Triangle) as uniform texel buffers of 16-byte texels:
//   layout(binding = N) uniform usamplerBuffer bvh_node_texels;
//   layout(binding = M) uniform usamplerBuffer bvh_triangle_texels;
// and calls bvh_intersect(o, d, tmin, tmax, budget, hit); see there for the budget.
//
// Every product and sum that decides a hit is `precise` (no fused multiply-add): the watertight test
// relies on the two triangles of a shared edge computing exactly opposite edge functions, and on the
// GPU and the CPU reference computing the same bits.
#ifndef BVH_GLSL
#define BVH_GLSL
#extension GL_KHR_shader_subgroup_arithmetic : require

// The deepest leaf of the binary tree the builder makes is at most this far below the root (bvh::MAX_DEPTH:
// it falls back to median splits to keep to it). The 4-wide tree collapsed from it is no deeper, and its
// traversal keeps at most three children of each node on its path on the stack, so BVH_STACK entries
// always hold them.
const uint BVH_MAX_DEPTH = 64u;
const uint BVH_STACK = 3u * BVH_MAX_DEPTH;
const uint BVH_NONE = 0xffffffffu;
// BvhNode.child: a slot without a child (also: no reference to visit); a leaf, its triangle count less one
// above BVH_COUNT_SHIFT and its first triangle below; anything else, an interior node's index.
const uint BVH_EMPTY = 0xffffffffu;
const uint BVH_LEAF = 0x80000000u;
const uint BVH_COUNT_SHIFT = 29u;
const uint BVH_FIRST_MASK = 0x1fffffffu;
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

// The watertight test: the vertices relative to the origin, permuted so the ray runs along +z, sheared so
// it is the z axis; then the 2D edge functions of the origin against each edge. Two-sided, and an edge
// function of exactly 0 counts as inside. Two triangles sharing an edge see its two vertices transformed
// to the same bits and compute its edge function from the same two products, in the other order: exactly
// opposite values, so a ray through the edge is inside one of them at least (Woop et al.'s argument; their
// recomputation of zeros in double, which only ever turns an accepted hit into a rejected one, is left out:
// it cost every step on lavapipe, which runs both sides of a branch). Hits with t in (tmin, tmax) only.
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

// The records read as texels. lavapipe runs a load from a storage buffer as a loop over the SIMD group's
// lanes, each with its bounds checks, and loads were most of a traversal step's cost; a texel fetch is one
// vector gather per 32-bit channel. Measured on the bounce rays of glass-on-table (examples/bvh_trace.rs,
// 500k rays, best of three): nodes of float boxes read as 28 32-bit fields, 1019 ms; as 7 pairs of 64-bit
// words, 631; quantized as 2 loads of four words, 411 (with the exit moved to the loop's bottom); as
// texels, 231.

// Triangle i (v0, material | v1, source | v2, pad0): three texels.
Triangle bvh_triangle(uint i) {
    int at = int(3u * i);
    uvec4 a = texelFetch(bvh_triangle_texels, at);
    uvec4 b = texelFetch(bvh_triangle_texels, at + 1);
    uvec4 c = texelFetch(bvh_triangle_texels, at + 2);
    return Triangle(uintBitsToFloat(a.xyz), a.w, uintBitsToFloat(b.xyz), b.w, uintBitsToFloat(c.xyz), c.w);
}

// Node i's children: their references, and their boxes decoded axis by axis (BvhNode).
struct BvhChildren {
    vec4 lo_x, hi_x, lo_y, hi_y, lo_z, hi_z;
    uvec4 child;
};

void bvh_axis(float origin, uint exponent, uvec2 q, out vec4 lo, out vec4 hi) {
    float step = uintBitsToFloat((exponent & 0xffu) << 23u);
    uvec4 shift = uvec4(0u, 8u, 16u, 24u);
    precise vec4 l = origin + vec4((uvec4(q.x) >> shift) & 0xffu) * step;
    precise vec4 h = origin + vec4((uvec4(q.y) >> shift) & 0xffu) * step;
    lo = l;
    hi = h;
}

BvhChildren bvh_node(uint i) {
    // Texels: origin x, y, z, exponents | qx, qy | qz, children 0, 1 | children 2, 3, padding.
    int at = int(4u * i);
    uvec4 a = texelFetch(bvh_node_texels, at);
    uvec4 b = texelFetch(bvh_node_texels, at + 1);
    uvec4 c = texelFetch(bvh_node_texels, at + 2);
    uvec4 d = texelFetch(bvh_node_texels, at + 3);
    BvhChildren n;
    bvh_axis(uintBitsToFloat(a.x), a.w, b.xy, n.lo_x, n.hi_x);
    bvh_axis(uintBitsToFloat(a.y), a.w >> 8u, b.zw, n.lo_y, n.hi_y);
    bvh_axis(uintBitsToFloat(a.z), a.w >> 16u, c.xy, n.lo_z, n.hi_z);
    n.child = uvec4(c.zw, d.xy);
    return n;
}

// One slab of the four boxes of a node: entry and exit distances along axis `k` (conservative: see
// bvh_intersect). A ray parallel to the slab is inside it for every t (its origin within the slab, faces
// included) or for none.
void bvh_slab(BvhRay r, uint k, vec4 lo, vec4 hi, out vec4 near, out vec4 far) {
    precise vec4 t0 = (lo - r.o[k]) * r.inv_d[k];
    precise vec4 t1 = (hi - r.o[k]) * r.inv_d[k];
    near = min(t0, t1);
    far = max(t0, t1);
    if (r.parallel[k]) {
        bvec4 inside = bvec4(uvec4(greaterThanEqual(vec4(r.o[k]), lo)) & uvec4(lessThanEqual(vec4(r.o[k]), hi)));
        near = mix(vec4(BVH_HUGE), vec4(-BVH_HUGE), inside);
        far = -near;
    }
}

// Orders two children of a node by entry distance, the nearer first (ties keep their order).
void bvh_order(inout vec4 key, inout uvec4 ref, uint i, uint j) {
    if (key[j] < key[i]) {
        float kt = key[i];
        key[i] = key[j];
        key[j] = kt;
        uint rt = ref[i];
        ref[i] = ref[j];
        ref[j] = rt;
    }
}

// The nearest triangle hit by o + t d with t in (tmin, tmax); true if there is one. d need not be unit.
// With `any_hit` (a shadow ray), the first hit found ends the traversal: whether there is one, not which.
//
// The 4-wide BVH, depth first, nearest child first: a node's four boxes are tested at once (the slab test
// with its far distance widened by BVH_ROBUST, so rounding never loses a box the ray meets), the children
// the ray enters sorted by entry distance; the nearest is visited next and the others pushed with their
// distances, and a popped one is skipped if the ray enters it beyond the nearest hit found since.
//
// Each loop step does whatever this lane has to do: take the next reference from the stack if it has
// none, visit it if it is a node, take its triangles if it is a leaf and the last leaf's are done, and test
// one triangle if any is left. lavapipe runs a SIMD group's lanes in step and both sides of every branch,
// so a step that does a node visit and a triangle test for the lanes that need either costs about what one
// of them costs, and a lane need not wait for a leaf's triangles to go on down the tree.
//
// The budget: each lane stops after `budget` steps with hit.cut set (its result is then not final and the
// caller must fail). The loop runs, for the SIMD group, as many steps as its longest lane plus one (the
// exit), so one call costs the subgroup at most budget + 1 of lavapipe's BVH_LOOP_LIMIT iterations, which
// all loops of an invocation share. A kernel with no other loops can pass BVH_LOOP_LIMIT - 1; one that
// calls this in a loop passes what its subgroup has left, e.g. `left -= bvh_subgroup_cost(hit)` after each
// call made by the whole subgroup together.
//
// An including file that defines BVH_FILTER defines bvh_filter(ray, triangle, material, bary) too: a hit
// it answers false for is passed as if the triangle were not there (geometry.glsl: Mitsuba's mask). The
// answer must depend on nothing but its arguments, so the traversal's order does not change the result.
#ifdef BVH_FILTER
bool bvh_filter(BvhRay r, uint tri, uint material, vec2 bary);
#endif
bool bvh_intersect(vec3 o, vec3 d, float tmin, float tmax, uint budget, bool any_hit, out BvhHit hit) {
    BvhRay r = bvh_ray(o, d);
    hit.t = tmax;
    hit.triangle = BVH_NONE;
    hit.bary = vec2(0.0);
    hit.steps = 0u;
    hit.cut = false;
    uint stack[BVH_STACK];
    float stack_t[BVH_STACK];
    uint sp = 0u;
    uint next = 0u;               // the reference to visit (the root node first); BVH_EMPTY: none
    uint tri = 0u, tri_end = 0u;  // the current leaf's triangles still to test
    while (true) {
        if (hit.steps == budget) {
            hit.cut = true;
            break;
        }
        hit.steps++;
        if (next == BVH_EMPTY && sp > 0u) {
            sp--;
            if (stack_t[sp] <= hit.t) next = stack[sp];
        }
        if ((next & BVH_LEAF) == 0u) {
            BvhChildren n = bvh_node(next);
            vec4 nx, fx, ny, fy, nz, fz;
            bvh_slab(r, 0u, n.lo_x, n.hi_x, nx, fx);
            bvh_slab(r, 1u, n.lo_y, n.hi_y, ny, fy);
            bvh_slab(r, 2u, n.lo_z, n.hi_z, nz, fz);
            vec4 near = max(max(nx, ny), max(nz, vec4(tmin)));
            precise vec4 far = min(min(fx, fy), fz) * BVH_ROBUST;
            bvec4 enter = bvec4(uvec4(lessThanEqual(near, min(far, vec4(hit.t)))) &
                                uvec4(notEqual(n.child, uvec4(BVH_EMPTY))));
            vec4 key = mix(vec4(BVH_HUGE), near, enter);
            uvec4 ref = n.child;
            // A sorting network of four: entered children first, nearest first.
            bvh_order(key, ref, 0u, 1u);
            bvh_order(key, ref, 2u, 3u);
            bvh_order(key, ref, 0u, 2u);
            bvh_order(key, ref, 1u, 3u);
            bvh_order(key, ref, 1u, 2u);
            uint entered = uint(enter.x) + uint(enter.y) + uint(enter.z) + uint(enter.w);
            if (entered > 3u) { stack[sp] = ref.w; stack_t[sp] = key.w; sp++; }
            if (entered > 2u) { stack[sp] = ref.z; stack_t[sp] = key.z; sp++; }
            if (entered > 1u) { stack[sp] = ref.y; stack_t[sp] = key.y; sp++; }
            next = entered > 0u ? ref.x : BVH_EMPTY;
        }
        if (next != BVH_EMPTY && (next & BVH_LEAF) != 0u && tri == tri_end) {
            tri = next & BVH_FIRST_MASK;
            tri_end = tri + ((next >> BVH_COUNT_SHIFT) & 3u) + 1u;
            next = BVH_EMPTY;
        }
        if (tri != tri_end) {
            Triangle tr = bvh_triangle(tri);
            float t;
            vec2 bary;
            if (bvh_triangle_test(r, tr.v0, tr.v1, tr.v2, tmin, hit.t, t, bary)
#ifdef BVH_FILTER
                && bvh_filter(r, tri, tr.material, bary)
#endif
            ) {
                hit.t = t;
                hit.triangle = tri;
                hit.bary = bary;
                if (any_hit) {
                    next = BVH_EMPTY;
                    sp = 0u;
                    tri_end = tri + 1u;
                }
            }
            tri++;
        }
        // The exit at the bottom: the last iteration does work (at the top, it would run the body once
        // more under an empty mask, lavapipe executing both sides of every branch).
        if (next == BVH_EMPTY && tri == tri_end && sp == 0u) break;
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

// Test kernel: the nearest triangle hit of each ray of a buffer, through shaders/common/bvh.glsl. It is how
// the GLSL traversal is checked against the CPU reference (crates/reference/src/bvh.rs). It also
// binds the nodes and triangles a second time as storage buffers of typed records (bindings 4 and 5), so
// that build.rs reflects the BvhNode and Triangle layouts the traversal's texel reads assume, and the
// hit's normal and the root's first child, read that way, check those reads.
#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 64) in;
#include "types.glsl"
#include "invocation.glsl"

struct TraceRay {
    vec3 origin;
    float tmin;
    vec3 dir;        // need not be unit: t is in units of |dir|
    float tmax;
};

struct TraceHit {
    vec3 normal;     // geometric, front side counter-clockwise; 0 on a miss
    float t;         // the ray's tmax on a miss
    vec2 bary;       // weights of v1 and v2
    uint triangle;   // index into the leaf-ordered triangles; 0xffffffff: no hit
    uint steps;      // loop steps the traversal took (node visits + triangle tests)
    uint cut;        // 1: stopped at the step budget, the hit is not final
    uint subgroup_cost; // bvh_subgroup_cost: the loop iterations this lane's subgroup spent
    uint subgroup_size;
    uint root_child; // the root's first child, read through the typed alias
};

layout(binding = 0) uniform usamplerBuffer bvh_node_texels;
layout(binding = 1) uniform usamplerBuffer bvh_triangle_texels;
layout(std430, binding = 2) readonly buffer Rays { TraceRay rays[]; };
layout(std430, binding = 3) writeonly buffer Hits { TraceHit hits[]; };
layout(std430, binding = 4) readonly buffer BvhNodes { BvhNode bvh_nodes[]; };
layout(std430, binding = 5) readonly buffer BvhTriangles { Triangle bvh_triangles[]; };
layout(push_constant) uniform TracePush {
    uint count;      // rays
    uint budget;     // steps each traversal may take (at most BVH_LOOP_LIMIT - 1: this kernel has no other loop)
    uint any_hit;    // 1: shadow rays, ended by the first hit found
} pc;
#include "bvh.glsl"

void main() {
    uint i = invocation_index();
    if (i >= pc.count) return;
    TraceRay ray = rays[i];
    BvhHit h;
    bool found = bvh_intersect(ray.origin, ray.dir, ray.tmin, ray.tmax, pc.budget, pc.any_hit != 0u, h);
    TraceHit out_hit;
    out_hit.normal = found ? bvh_normal(bvh_triangles[h.triangle]) : vec3(0.0);
    out_hit.t = h.t;
    out_hit.bary = h.bary;
    out_hit.triangle = h.triangle;
    out_hit.steps = h.steps;
    out_hit.cut = h.cut ? 1u : 0u;
    out_hit.subgroup_cost = bvh_subgroup_cost(h);
    out_hit.subgroup_size = gl_SubgroupSize;
    out_hit.root_child = bvh_nodes[0].child[0];
    hits[i] = out_hit;
}

// Photon grid, step 0 of 5: the build's dispatches from the batch's record count, so the count, the split
// and the placing run workgroups for the records the photons left, not for the buffer's capacity. An idle
// thread is not free on lavapipe: sized by the capacity (4 records a photon), cornell-spheres' build took
// 180 ms a pass against 105 for half the capacity (docs/performance.md, "The grid build's idle threads").
#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 1) in;
#include "types.glsl"
#include "params.glsl"
#include "invocation.glsl"
layout(std430, binding = 1) readonly buffer Counter { uint photon_count; };
layout(std430, binding = 2) writeonly buffer Dispatch { GridDispatch dispatch; };
layout(push_constant) uniform GridDispatchPush {
    uint chunk;      // records per workgroup of the count and the split (CHUNK, partition.glsl)
    uint local_size; // grid_scatter.comp's workgroup size
} pc;

void main() {
    load_params();
    uint n = min(photon_count, params.photon_capacity); // as partition.glsl's batch_records()
    dispatch.chunks = uvec3((n + pc.chunk - 1u) / pc.chunk, 1u, 1u);
    dispatch.records = spread_groups((n + pc.local_size - 1u) / pc.local_size);
}

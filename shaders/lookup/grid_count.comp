// Photon grid, step 1 of 3: count the photon records in each hash bucket, and keep each record's rank
// among its bucket's records (the count before it), so the scatter needs no atomic of its own.
#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 256) in;
#include "types.glsl"
#include "params.glsl"
layout(std430, binding = 1) readonly buffer Photons { Photon photons[]; };
layout(std430, binding = 2) readonly buffer Counter { uint photon_count; };
layout(std430, binding = 3) buffer CellCount { uint cell_count[]; };
layout(std430, binding = 4) writeonly buffer Rank { uint rank[]; };
#include "grid.glsl"
#include "invocation.glsl"

void main() {
    load_params();
    uint i = invocation_index();
    if (i >= min(photon_count, params.photon_capacity)) return;
    rank[i] = atomicAdd(cell_count[grid_bucket(photons[i].cell)], 1u);
}

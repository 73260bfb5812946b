// Photon grid, step 3 of 3: copy each record into its bucket's range of `sorted`, so the gather reads a
// bucket's photons contiguously. Counting the bucket back down returns `cell_count` to zero, ready for the
// next batch.
#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 256) in;
#include "types.glsl"
#include "params.glsl"
layout(std430, binding = 1) readonly buffer Photons { Photon photons[]; };
layout(std430, binding = 2) readonly buffer Counter { uint photon_count; };
layout(std430, binding = 3) buffer CellCount { uint cell_count[]; };
layout(std430, binding = 4) readonly buffer CellStart { uint cell_start[]; };
layout(std430, binding = 5) writeonly buffer Sorted { Photon sorted[]; };
#include "grid.glsl"
#include "invocation.glsl"

void main() {
    load_params();
    uint i = invocation_index();
    if (i >= min(photon_count, params.photon_capacity)) return;
    Photon p = photons[i];
    uint h = grid_bucket(p.cell);
    uint k = atomicAdd(cell_count[h], 0xffffffffu) - 1u;
    sorted[cell_start[h] + k] = p;
}

// Photon grid, step 3 of 3: copy each record into its bucket's range of `sorted`, so the gather reads a
// bucket's photons contiguously. Counting the bucket back down returns `cell_count` to zero, ready for the
// next batch.
#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 256) in;
#include "types.glsl"
#include "params.glsl"
// The records as 64-bit words (a Photon is 4 of them; pos.z and cell share the second): lavapipe stores a
// vector one component per lane, so half as many components is half the scattered stores.
layout(std430, binding = 1) readonly buffer Photons { u64vec4 photons[]; };
layout(std430, binding = 2) readonly buffer Counter { uint photon_count; };
layout(std430, binding = 3) buffer CellCount { uint cell_count[]; };
layout(std430, binding = 4) readonly buffer CellStart { uint cell_start[]; };
layout(std430, binding = 5) writeonly buffer Sorted { u64vec4 sorted[]; };
#include "grid.glsl"
#include "invocation.glsl"

void main() {
    load_params();
    uint i = invocation_index();
    if (i >= min(photon_count, params.photon_capacity)) return;
    u64vec4 p = photons[i];
    uint h = grid_bucket(uint(p.y >> 32)); // Photon.cell: the high half of the second word
    uint k = atomicAdd(cell_count[h], 0xffffffffu) - 1u;
    sorted[cell_start[h] + k] = p;
}

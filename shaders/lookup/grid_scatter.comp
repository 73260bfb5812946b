// Photon grid, step 3 of 3: copy each record into its bucket's range of `sorted`, at the rank the count
// gave it, so the gather reads a bucket's photons contiguously. No atomic: on lavapipe each is a locked
// instruction per lane on a table that outgrows the cache as the cells shrink.
#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 256) in;
#include "types.glsl"
#include "params.glsl"
// The records as 64-bit words (photon_words in types.glsl): lavapipe stores a vector one component per
// lane, so half as many components is half the scattered stores.
layout(std430, binding = 1) readonly buffer Photons { u64vec4 photons[]; };
layout(std430, binding = 2) readonly buffer Counter { uint photon_count; };
layout(std430, binding = 3) readonly buffer Rank { uint rank[]; };
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
    sorted[cell_start[h] + rank[i]] = p;
}

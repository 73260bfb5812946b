// Photon grid, step 1 of 5: count the photon records in each hash bucket, and, per chunk of CHUNK records
// (one workgroup), how many fall in each partition (partition.glsl) for the split.
#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 256) in;
#include "types.glsl"
#include "params.glsl"
// The records as texels (position, cell key | flux, direction): a texel fetch is a vector gather on
// lavapipe, where a storage-buffer load is a loop over the lanes (bvh.glsl).
layout(binding = 1) uniform usamplerBuffer photon_texels;
layout(std430, binding = 2) readonly buffer Counter { uint photon_count; };
layout(std430, binding = 3) buffer CellCount { uint cell_count[]; };
layout(std430, binding = 4) writeonly buffer PartCount { uint part_count[]; }; // [chunk][partition]
#include "grid.glsl"
#include "partition.glsl"

shared uint hist[MAX_PARTS];

void main() {
    load_params();
    uint t = gl_LocalInvocationIndex;
    uint first, end;
    if (!chunk_range(first, end)) return;
    for (uint p = t; p < pc.parts; p += 256u) hist[p] = 0u;
    barrier();
    for (uint i = first + t; i < end; i += 256u) {
        uint h = grid_bucket(texelFetch(photon_texels, int(2u * i)).w); // Photon.cell
        atomicAdd(cell_count[h], 1u);
        atomicAdd(hist[h >> pc.shift], 1u);
    }
    barrier();
    uint row = chunk_index() * pc.parts;
    for (uint p = t; p < pc.parts; p += 256u) part_count[row + p] = hist[p];
}

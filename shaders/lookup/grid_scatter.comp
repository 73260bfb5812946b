// Photon grid, step 5 of 5: place each record of `staging` in its bucket's range of the record buffer, so
// the lookups read a bucket's photons contiguously. `staging` holds the records partition by partition,
// so the threads working at one time write within one partition's range, which stays in cache. A
// bucket's count, left by grid_count, counts down to the record's place and ends at zero, ready for the
// next batch. The order within a bucket varies from run to run; the lookups' sums do not depend on it.
#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 256) in;
#include "types.glsl"
#include "params.glsl"
// The staged records as texels (position, cell key | flux, direction), as grid_count reads them.
layout(binding = 1) uniform usamplerBuffer staging_texels;
layout(std430, binding = 2) readonly buffer Counter { uint photon_count; };
layout(std430, binding = 3) buffer CellCount { uint cell_count[]; };
layout(std430, binding = 4) readonly buffer CellStart { uint cell_start[]; };
layout(std430, binding = 5) writeonly buffer Photons { u64vec4 photons[]; }; // grouped by bucket
#include "grid.glsl"
#include "invocation.glsl"

void main() {
    load_params();
    uint i = invocation_index();
    if (i >= min(photon_count, params.photon_capacity)) return;
    uvec4 a = texelFetch(staging_texels, int(2u * i));
    uvec4 b = texelFetch(staging_texels, int(2u * i + 1u));
    uint h = grid_bucket(a.w); // Photon.cell
    uint left = atomicAdd(cell_count[h], 0xffffffffu); // records of the bucket not yet placed, this one included
    photons[cell_start[h] + left - 1u] = texels_words(a, b);
}

// Photon grid, step 4 of 5: split the records by partition into `staging`. Each workgroup takes the chunk
// the count took and writes its records of a partition one after another from that chunk's offset, so
// the writes stream through one open run per partition instead of landing at random.
#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 256) in;
#include "types.glsl"
#include "params.glsl"
// The records as texels (position, cell key | flux, direction), read as grid_count reads them.
layout(binding = 1) uniform usamplerBuffer photon_texels;
layout(std430, binding = 2) readonly buffer Counter { uint photon_count; };
layout(std430, binding = 3) readonly buffer PartStart { uint part_start[]; }; // [chunk][partition]
layout(std430, binding = 4) writeonly buffer Staging { u64vec4 staging[]; };
#include "grid.glsl"
#include "partition.glsl"

shared uint cursor[MAX_PARTS];

void main() {
    load_params();
    uint t = gl_LocalInvocationIndex;
    uint first, end;
    if (!chunk_range(first, end)) return;
    uint row = chunk_index() * pc.parts;
    for (uint p = t; p < pc.parts; p += 256u) cursor[p] = part_start[row + p];
    barrier();
    for (uint i = first + t; i < end; i += 256u) {
        uvec4 a = texelFetch(photon_texels, int(2u * i));
        uvec4 b = texelFetch(photon_texels, int(2u * i + 1u));
        uint h = grid_bucket(a.w); // Photon.cell
        staging[atomicAdd(cursor[h >> pc.shift], 1u)] = texels_words(a, b);
    }
}

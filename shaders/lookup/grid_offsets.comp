// Photon grid, step 3 of 5 (after the scan): where each chunk's records of each partition go in `staging`.
// A partition's records start where its first bucket does (cell_start); within it, chunk by chunk. One
// thread per partition runs over the chunks (at most MAX_CHUNKS, lookup.rs, far inside the loop budget).
#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 64) in;
#include "types.glsl"
#include "params.glsl"
layout(std430, binding = 1) readonly buffer Counter { uint photon_count; };
layout(std430, binding = 2) readonly buffer CellStart { uint cell_start[]; };
layout(std430, binding = 3) buffer PartCount { uint part_count[]; }; // counts in, offsets out
#include "partition.glsl"

void main() {
    load_params();
    uint p = gl_GlobalInvocationID.x;
    if (p >= pc.parts) return;
    uint chunks = batch_chunks();
    uint run = cell_start[p << pc.shift];
    for (uint c = 0u; c < chunks; c++) {
        uint k = c * pc.parts + p;
        uint v = part_count[k];
        part_count[k] = run;
        run += v;
    }
}

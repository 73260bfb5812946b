// Photon grid, step 2 of 5: exclusive prefix sum of the bucket counts into bucket starts, in three phases
// chosen by push constant (one kernel, so the three share their declarations):
//   0: each workgroup scans its block of BLOCK counts into `cell_start` and writes the block's total (the
//      counts stay: grid_scatter counts them down to zero);
//   1: one workgroup scans the block totals (at most 65536 of them) and writes the grand total last;
//   2: each block adds its scanned total to its entries.
#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer CellCount { uint cell_count[]; };
layout(std430, binding = 1) buffer CellStart { uint cell_start[]; };   // cells + 1 entries
layout(std430, binding = 2) buffer BlockSums { uint block_sums[]; };
layout(push_constant) uniform ScanPush {
    uint cells;      // a multiple of BLOCK
    uint phase;
} pc;

const uint PER_THREAD = 4u;
const uint BLOCK = 256u * PER_THREAD;
shared uint partial[256];

// Exclusive scan of one value per thread across the workgroup (Hillis-Steele in shared memory).
uint workgroup_exclusive_scan(uint v, out uint total) {
    uint t = gl_LocalInvocationIndex;
    partial[t] = v;
    barrier();
    for (uint off = 1u; off < 256u; off <<= 1u) {
        uint add = t >= off ? partial[t - off] : 0u;
        barrier();
        partial[t] += add;
        barrier();
    }
    total = partial[255];
    uint inclusive = partial[t];
    barrier();
    return inclusive - v;
}

void main() {
    uint t = gl_LocalInvocationIndex;
    uint block = gl_WorkGroupID.x;
    if (pc.phase == 0u) {
        uint base = block * BLOCK + t * PER_THREAD;
        uint v[PER_THREAD];
        uint sum = 0u;
        for (uint k = 0u; k < PER_THREAD; k++) { v[k] = cell_count[base + k]; sum += v[k]; }
        uint total;
        uint run = workgroup_exclusive_scan(sum, total);
        for (uint k = 0u; k < PER_THREAD; k++) { cell_start[base + k] = run; run += v[k]; }
        if (t == 0u) block_sums[block] = total;
    } else if (pc.phase == 1u) {
        uint blocks = pc.cells / BLOCK;
        uint per = (blocks + 255u) / 256u;
        uint sum = 0u;
        for (uint k = 0u; k < per; k++) { uint j = t * per + k; if (j < blocks) sum += block_sums[j]; }
        uint total;
        uint run = workgroup_exclusive_scan(sum, total);
        for (uint k = 0u; k < per; k++) {
            uint j = t * per + k;
            if (j < blocks) { uint s = block_sums[j]; block_sums[j] = run; run += s; }
        }
        if (t == 0u) cell_start[pc.cells] = total;
    } else {
        uint base = block * BLOCK + t * PER_THREAD;
        uint add = block_sums[block];
        for (uint k = 0u; k < PER_THREAD; k++) cell_start[base + k] += add;
    }
}

// Photon grid, step 2 of 5: exclusive prefix sum of the bucket counts into bucket starts, in three phases
// chosen by push constant (one kernel, so the three share their declarations):
//   0: each workgroup scans its block of BLOCK counts into `cell_start` and writes the block's total (the
//      counts stay: grid_scatter counts them down to zero);
//   1: one workgroup scans the block totals (at most 65536 of them) and writes the grand total last;
//   2: each block adds its scanned total to its entries.
#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_KHR_shader_subgroup_arithmetic : require
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
shared uint partial[256]; // per subgroup: its total, then its offset in the workgroup
shared uint group_total;

// Exclusive scan of one value per thread across the workgroup: within each subgroup by subgroup
// arithmetic, then over the subgroups' totals by the first subgroup. Two barriers, where a Hillis-Steele
// scan in shared memory took sixteen, each of which lavapipe pays once per SIMD batch of every workgroup
// (docs/performance.md, "The grid build's scan"). Subgroups are full here: 256 is a multiple of every
// subgroup size.
uint workgroup_exclusive_scan(uint v, out uint total) {
    uint before = subgroupExclusiveAdd(v);
    uint sum = subgroupAdd(v);
    if (subgroupElect()) partial[gl_SubgroupID] = sum;
    barrier();
    if (gl_SubgroupID == 0u) {
        uint carry = 0u;
        for (uint base = 0u; base < gl_NumSubgroups; base += gl_SubgroupSize) {
            uint i = base + gl_SubgroupInvocationID;
            uint s = i < gl_NumSubgroups ? partial[i] : 0u;
            uint offset = carry + subgroupExclusiveAdd(s);
            if (i < gl_NumSubgroups) partial[i] = offset;
            carry += subgroupAdd(s);
        }
        if (subgroupElect()) group_total = carry;
    }
    barrier();
    total = group_total;
    uint result = partial[gl_SubgroupID] + before;
    barrier(); // `partial` is free for the caller's next scan
    return result;
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

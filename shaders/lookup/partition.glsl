// The grid build's partitions (grid_count, grid_offsets, grid_partition): a partition is a run of 2^shift
// consecutive hash buckets, and the records are first split by partition, then placed within it. A
// record's bucket is random in the order photons leave records, so writing each straight to its place
// misses the cache once per record (the records outgrow it many times over); split first, each
// partition's records land in a range small enough to stay in cache while they are placed
// (grid_scatter.comp). Measured in docs/performance.md.
#ifndef PARTITION_GLSL
#define PARTITION_GLSL
// Records per workgroup of the count and the split (256 threads x 32); the split writes each chunk's
// records of a partition contiguously, from an offset grid_offsets.comp computes per chunk and partition.
const uint CHUNK = 8192u;
// Most partitions (crates/kernels/src/lookup.rs: MAX_PARTS): a workgroup keeps one counter per partition
// in shared memory.
const uint MAX_PARTS = 512u;

layout(push_constant) uniform GridPush {
    uint parts;      // partitions in use (a power of two, at most MAX_PARTS)
    uint shift;      // a bucket's partition is bucket >> shift
} pc;

// This workgroup's chunk of the records (the count's and the split's dispatches are one-dimensional).
uint chunk_index() {
    return gl_WorkGroupID.x;
}

// The records of this batch: the counter, capped at the buffer (an overflowed batch is run again).
// Needs `photon_count` and `params` declared before this file.
uint batch_records() {
    return min(photon_count, params.photon_capacity);
}

uint batch_chunks() {
    return (batch_records() + CHUNK - 1u) / CHUNK;
}

// Records first .. end - 1 are this workgroup's chunk, the same in the count and the split. False for a
// chunk past the batch's records: the whole workgroup has nothing to do, and grid_offsets reads only the
// chunks that hold records.
bool chunk_range(out uint first, out uint end) {
    uint n = batch_records();
    first = chunk_index() * CHUNK;
    end = min(first + CHUNK, n);
    return first < n;
}
#endif

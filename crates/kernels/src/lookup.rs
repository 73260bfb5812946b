//! Stage 3b, `shaders/lookup/`: the photon grid, a hashed uniform grid rebuilt per batch by a counting
//! sort in two levels: count (per bucket, and per chunk of records per partition of the buckets), scan,
//! partition offsets, split by partition, then place within the partition; the count, the split and the
//! placing run indirectly, sized from the batch's records (grid_dispatch.comp). Hit points then read the
//! buckets their sphere overlaps.

use anyhow::{bail, Result};
use bytemuck::{Pod, Zeroable};
use ppm_vk_device::{barrier, vk, Buffer, BufferKind, ComputePipeline, Context, Profiler};

use crate::layout::GridDispatch;
use crate::push_struct;

/// Loop steps of a subgroup that the gather and probe kernels keep for their loops other than the
/// lookups (their per-thread setup loops are unrolled; this is a margin, not a count).
pub const LOOKUP_MARGIN: u32 = 5535;

/// `RenderParams::lookup_limit` for a device's loop budget (`DeviceInfo::loop_budget`): a subgroup
/// whose lookups take this many steps may have been cut short, and says so (neighbours.glsl), which
/// stops the render with an error. A device without a budget (`None`) never stops one.
pub fn lookup_limit(budget: Option<u32>) -> u32 {
    budget.map_or(u32::MAX, |b| b.saturating_sub(LOOKUP_MARGIN))
}

/// Buckets scanned per workgroup in `grid_scan.comp` (256 threads x 4).
pub const SCAN_BLOCK: u32 = 1024;
/// Records per workgroup of the count and the split (`CHUNK` in shaders/lookup/partition.glsl).
pub const CHUNK: u32 = crate::reflected::constants::CHUNK;
/// Most partitions of the buckets (`MAX_PARTS` in partition.glsl).
pub const MAX_PARTS: u32 = crate::reflected::constants::MAX_PARTS;
/// Most chunks a batch may have: `grid_offsets.comp` runs one loop step per chunk, and this keeps it far
/// inside lavapipe's 65535 steps per SIMD group (and the dispatch within 65535 workgroups). 60000 chunks
/// are 491M records, beyond the largest buffer a device binds (the renderer checks that first).
pub const MAX_CHUNKS: u32 = 60000;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ScanPush {
    pub cells: u32,
    pub phase: u32,
}
push_struct!(ScanPush, GRID_SCAN);

/// The partitions of the count, the offsets and the split (partition.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GridPush {
    /// Partitions in use, a power of two.
    pub parts: u32,
    /// A bucket's partition is `bucket >> shift`.
    pub shift: u32,
}
push_struct!(GridPush, GRID_COUNT);
push_struct!(GridPush, GRID_OFFSETS);
push_struct!(GridPush, GRID_PARTITION);

/// grid_dispatch.comp's push constants: what its dispatches are sized by.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GridDispatchPush {
    /// Records per workgroup of the count and the split ([`CHUNK`]).
    pub chunk: u32,
    /// grid_scatter.comp's workgroup size.
    pub local_size: u32,
}
push_struct!(GridDispatchPush, GRID_DISPATCH);

impl GridPush {
    /// One partition per scan block of `cells` buckets, at most [`MAX_PARTS`]: a partition's records
    /// (the batch over the partitions) stay in cache while they are placed.
    pub fn for_cells(cells: u32) -> GridPush {
        let parts = (cells / SCAN_BLOCK).clamp(1, MAX_PARTS);
        GridPush {
            parts,
            shift: (cells / parts).trailing_zeros(),
        }
    }
}

/// The photon records and the grid's buffers for a table of up to `allocated` buckets, `cells` of them in
/// use.
pub struct Grid {
    /// Buckets in use (the hash's mask + 1).
    pub cells: u32,
    pub allocated: u32,
    /// The records: the photon kernel appends them, the build groups them by bucket in place.
    pub records: Buffer,
    /// The records split by partition, between the build's split and its placing.
    pub staging: Buffer,
    /// Per bucket: records in it while building; zero between batches (the placing counts them down).
    pub cell_count: Buffer,
    /// Per chunk and partition: the chunk's records in the partition, then where they go in `staging`.
    pub part_count: Buffer,
    /// Per bucket: index of its first record in `records`; `cells + 1` entries.
    pub cell_start: Buffer,
    pub block_sums: Buffer,
    /// The count's, the split's and the placing's dispatches for the batch (`GridDispatch`).
    pub dispatch: Buffer,
    /// One word the kernels that read the grid set to 1 when a lookup loop stopped early (lavapipe's
    /// limit on loop iterations); zero otherwise.
    pub status: Buffer,
}

impl Grid {
    /// Bytes of the grid's buffers that grow with the record capacity, for the renderer's memory check:
    /// the records, their staging copy and the per-chunk partition counts (rounded up).
    pub fn bytes_per_record() -> u64 {
        2 * std::mem::size_of::<crate::layout::Photon>() as u64 + (MAX_PARTS as u64 * 4).div_ceil(CHUNK as u64)
    }

    /// `cells` must be a power of two, at least [`SCAN_BLOCK`] and at most 65536 blocks; `capacity` (records)
    /// at most [`MAX_CHUNKS`] chunks.
    pub fn new(ctx: &Context, cells: u32, capacity: u32) -> Result<Grid> {
        if !cells.is_power_of_two() || cells < SCAN_BLOCK || cells / SCAN_BLOCK > 65536 {
            bail!(
                "photon grid: {cells} buckets is not a power of two in [{SCAN_BLOCK}, {}]",
                SCAN_BLOCK as u64 * 65536
            );
        }
        let chunks = chunks_for(capacity)?;
        let record = std::mem::size_of::<crate::layout::Photon>() as u64;
        let cell_count = Buffer::new(ctx, "grid cell_count", cells as u64 * 4, BufferKind::Storage)?;
        let status = Buffer::new(ctx, "grid lookup status", 4, BufferKind::Storage)?;
        ctx.run(|cmd| {
            cell_count.cmd_fill(cmd, 0);
            status.cmd_fill(cmd, 0);
            Ok(())
        })?;
        Ok(Grid {
            cells,
            allocated: cells,
            records: Buffer::new(ctx, "photon records", capacity as u64 * record, BufferKind::Storage)?,
            staging: Buffer::new(
                ctx,
                "grid staging records",
                capacity as u64 * record,
                BufferKind::Storage,
            )?,
            cell_count,
            part_count: Buffer::new(
                ctx,
                "grid part_count",
                chunks.max(1) as u64 * MAX_PARTS as u64 * 4,
                BufferKind::Storage,
            )?,
            cell_start: Buffer::new(ctx, "grid cell_start", (cells as u64 + 1) * 4, BufferKind::Storage)?,
            block_sums: Buffer::new(
                ctx,
                "grid block_sums",
                (cells / SCAN_BLOCK) as u64 * 4,
                BufferKind::Storage,
            )?,
            dispatch: Buffer::new(
                ctx,
                "grid dispatch",
                std::mem::size_of::<GridDispatch>() as u64,
                BufferKind::Storage,
            )?,
            status,
        })
    }
}

impl Grid {
    /// Uses the first `cells` buckets (the kernels' hash mask must agree).
    pub fn set_cells(&mut self, cells: u32) -> Result<()> {
        if !cells.is_power_of_two() || cells < SCAN_BLOCK || cells > self.allocated {
            bail!(
                "photon grid: {cells} buckets in use is not a power of two in [{SCAN_BLOCK}, {}]",
                self.allocated
            );
        }
        self.cells = cells;
        Ok(())
    }
}

/// The chunks of the count and the split for `capacity` records; an error past [`MAX_CHUNKS`].
pub fn chunks_for(capacity: u32) -> Result<u32> {
    let chunks = capacity.div_ceil(CHUNK);
    if chunks > MAX_CHUNKS {
        bail!(
            "photon grid: {capacity} records are more than the build takes ({} at most)",
            MAX_CHUNKS as u64 * CHUNK as u64
        );
    }
    Ok(chunks)
}

/// The grid kernels: the five steps of the build and the sizing of their dispatches.
pub struct Lookup {
    pub dispatch: ComputePipeline,
    pub count: ComputePipeline,
    pub scan: ComputePipeline,
    pub offsets: ComputePipeline,
    pub partition: ComputePipeline,
    pub scatter: ComputePipeline,
}

impl Lookup {
    pub fn new(ctx: &Context) -> Result<Lookup> {
        use crate::reflected::*;
        Ok(Lookup {
            dispatch: crate::pipeline(ctx, &GRID_DISPATCH)?,
            count: crate::pipeline(ctx, &GRID_COUNT)?,
            scan: crate::pipeline(ctx, &GRID_SCAN)?,
            offsets: crate::pipeline(ctx, &GRID_OFFSETS)?,
            partition: crate::pipeline(ctx, &GRID_PARTITION)?,
            scatter: crate::pipeline(ctx, &GRID_SCATTER)?,
        })
    }

    /// Records the grid build over the records in `grid.records` (their number is in `counter`, capped at
    /// the buffer's capacity), which it leaves grouped by bucket; the count, the split and the placing are
    /// dispatched for that number of records (grid_dispatch.comp sizes them on the device).
    /// Profiler scopes: `lookup/count` (with the sizing), `lookup/scan` (with the partition offsets), `lookup/split` and
    /// `lookup/scatter`. Placing each record straight at its bucket's place, the way this build did before
    /// the split, took 130-260 ms for 2.8M records, and 41-48 ms with the same writes in order: the
    /// writes' cache misses were the cost (docs/performance.md).
    // One argument per buffer the pass binds, in binding order (the reflected layout checks it).
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        profiler: &Profiler,
        params: &Buffer,
        counter: &Buffer,
        grid: &Grid,
    ) -> Result<()> {
        let parts = GridPush::for_cells(grid.cells);
        let push = bytemuck::bytes_of(&parts);
        profiler.scope(cmd, "lookup/count", || {
            let sizes = GridDispatchPush {
                chunk: CHUNK,
                local_size: self.scatter.local_size(),
            };
            let buffers = [params, counter, &grid.dispatch];
            self.dispatch
                .dispatch_groups(cmd, &buffers, bytemuck::bytes_of(&sizes), [1, 1, 1])?;
            barrier(ctx, cmd);
            let buffers = [params, &grid.records, counter, &grid.cell_count, &grid.part_count];
            self.count
                .dispatch_indirect(cmd, &buffers, push, &grid.dispatch, GridDispatch::CHUNKS_OFFSET)
        })?;
        barrier(ctx, cmd);
        let blocks = grid.cells / SCAN_BLOCK;
        let scan_buffers = [&grid.cell_count, &grid.cell_start, &grid.block_sums];
        profiler.scope(cmd, "lookup/scan", || {
            for (phase, groups) in [(0u32, blocks), (1, 1), (2, blocks)] {
                let push = ScanPush {
                    cells: grid.cells,
                    phase,
                };
                self.scan
                    .dispatch_groups(cmd, &scan_buffers, bytemuck::bytes_of(&push), [groups, 1, 1])?;
                barrier(ctx, cmd);
            }
            self.offsets.dispatch(
                cmd,
                &[params, counter, &grid.cell_start, &grid.part_count],
                push,
                parts.parts as u64,
            )
        })?;
        barrier(ctx, cmd);
        profiler.scope(cmd, "lookup/split", || {
            let buffers = [params, &grid.records, counter, &grid.part_count, &grid.staging];
            self.partition
                .dispatch_indirect(cmd, &buffers, push, &grid.dispatch, GridDispatch::CHUNKS_OFFSET)
        })?;
        barrier(ctx, cmd);
        profiler.scope(cmd, "lookup/scatter", || {
            let buffers = [
                params,
                &grid.staging,
                counter,
                &grid.cell_count,
                &grid.cell_start,
                &grid.records,
            ];
            self.scatter
                .dispatch_indirect(cmd, &buffers, &[], &grid.dispatch, GridDispatch::RECORDS_OFFSET)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lookups_are_limited_only_on_a_device_with_a_loop_budget() {
        // lavapipe's 65535 steps per SIMD group: the lookups stop the render at 60000 (neighbours.glsl).
        assert_eq!(lookup_limit(Some(65535)), 60000);
        // No budget: no subgroup's step count (a u32) ever reaches the limit.
        assert_eq!(lookup_limit(None), u32::MAX);
        assert_eq!(lookup_limit(Some(100)), 0);
    }

    #[test]
    fn the_build_takes_records_up_to_its_chunk_bound() {
        assert_eq!(chunks_for(0).unwrap(), 0);
        assert_eq!(chunks_for(CHUNK + 1).unwrap(), 2);
        assert_eq!(chunks_for(MAX_CHUNKS * CHUNK).unwrap(), MAX_CHUNKS);
        let e = chunks_for(MAX_CHUNKS * CHUNK + 1).unwrap_err().to_string();
        assert!(e.contains("more than the build takes (491520000 at most)"), "{e}");
    }

    /// The chunk and partition bounds stated here are the ones the kernels use.
    #[test]
    fn constants_match_the_glsl() {
        let glsl = crate::reflected::SOURCES
            .iter()
            .find(|(p, _)| *p == "lookup/partition.glsl")
            .unwrap()
            .1;
        for line in [
            format!("const uint CHUNK = {CHUNK}u;"),
            format!("const uint MAX_PARTS = {MAX_PARTS}u;"),
        ] {
            assert!(
                glsl.lines().any(|l| l.starts_with(&line)),
                "partition.glsl lacks `{line}`"
            );
        }
        let scan = crate::reflected::SOURCES
            .iter()
            .find(|(p, _)| *p == "lookup/grid_scan.comp")
            .unwrap()
            .1;
        assert!(scan.contains("const uint BLOCK = 256u * PER_THREAD;") && scan.contains("const uint PER_THREAD = 4u;"));
        assert_eq!(SCAN_BLOCK, 256 * 4);
    }

    #[test]
    fn partitions_cover_the_table_in_whole_scan_blocks() {
        for cells in (SCAN_BLOCK.trailing_zeros()..=SCAN_BLOCK.trailing_zeros() + 16).map(|b| 1u32 << b) {
            let p = GridPush::for_cells(cells);
            assert!(p.parts.is_power_of_two() && p.parts <= MAX_PARTS, "{cells}: {p:?}");
            // Every bucket falls in a partition, and every partition starts on a scan block.
            assert_eq!((cells - 1) >> p.shift, p.parts - 1, "{cells}: {p:?}");
            assert!(1u32 << p.shift >= SCAN_BLOCK, "{cells}: {p:?}");
        }
    }
}

//! Stage 3b, `shaders/lookup/`: the photon grid, a hashed uniform grid rebuilt per batch by a counting
//! sort (count, exclusive scan, scatter). Hit points then read the buckets their sphere overlaps.

use anyhow::{bail, Result};
use bytemuck::{Pod, Zeroable};
use ppm_vk_device::{barrier, vk, Buffer, BufferKind, ComputePipeline, Context, Profiler};

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

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ScanPush {
    pub cells: u32,
    pub phase: u32,
}
push_struct!(ScanPush, GRID_SCAN);

/// The grid's buffers for a table of up to `allocated` buckets, `cells` of them in use.
pub struct Grid {
    /// Buckets in use (the hash's mask + 1).
    pub cells: u32,
    pub allocated: u32,
    /// Per bucket: records in it while building; zero between batches (the scan zeroes what it reads).
    pub cell_count: Buffer,
    /// Per record: its rank among its bucket's records, from the count, for the scatter.
    pub rank: Buffer,
    /// Per bucket: index of its first record in `sorted`; `cells + 1` entries.
    pub cell_start: Buffer,
    pub block_sums: Buffer,
    /// The records, grouped by bucket.
    pub sorted: Buffer,
    /// One word the kernels that read the grid set to 1 when a lookup loop stopped early (lavapipe's
    /// limit on loop iterations); zero otherwise.
    pub status: Buffer,
}

impl Grid {
    /// `cells` must be a power of two, at least [`SCAN_BLOCK`] and at most 65536 blocks.
    pub fn new(ctx: &Context, cells: u32, capacity: u32) -> Result<Grid> {
        if !cells.is_power_of_two() || cells < SCAN_BLOCK || cells / SCAN_BLOCK > 65536 {
            bail!("photon grid: {cells} buckets is not a power of two in [{SCAN_BLOCK}, {}]", SCAN_BLOCK as u64 * 65536);
        }
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
            cell_count,
            cell_start: Buffer::new(ctx, "grid cell_start", (cells as u64 + 1) * 4, BufferKind::Storage)?,
            rank: Buffer::new(ctx, "grid record ranks", capacity as u64 * 4, BufferKind::Storage)?,
            block_sums: Buffer::new(ctx, "grid block_sums", (cells / SCAN_BLOCK) as u64 * 4, BufferKind::Storage)?,
            sorted: Buffer::new(
                ctx,
                "grid sorted records",
                capacity as u64 * std::mem::size_of::<crate::layout::Photon>() as u64,
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
            bail!("photon grid: {cells} buckets in use is not a power of two in [{SCAN_BLOCK}, {}]", self.allocated);
        }
        self.cells = cells;
        Ok(())
    }
}

/// The three grid kernels.
pub struct Lookup {
    pub count: ComputePipeline,
    pub scan: ComputePipeline,
    pub scatter: ComputePipeline,
}

impl Lookup {
    pub fn new(ctx: &Context) -> Result<Lookup> {
        use crate::reflected::*;
        Ok(Lookup {
            count: crate::pipeline(ctx, &GRID_COUNT)?,
            scan: crate::pipeline(ctx, &GRID_SCAN)?,
            scatter: crate::pipeline(ctx, &GRID_SCATTER)?,
        })
    }

    /// Records the grid build over the records in `photons` (their number is in `counter`); dispatches
    /// cover `capacity` records and the kernels stop at the count. Each step is a `profiler` scope named
    /// `lookup/count`, `lookup/scan` and `lookup/scatter` (which copies whole records: scattering 4-byte
    /// indices and then permuting the records measured no faster on lavapipe, 180 ms against 183 ms for
    /// 2.8M records).
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        profiler: &Profiler,
        params: &Buffer,
        photons: &Buffer,
        counter: &Buffer,
        grid: &Grid,
        capacity: u32,
    ) -> Result<()> {
        profiler.scope(cmd, "lookup/count", || {
            self.count.dispatch(cmd, &[params, photons, counter, &grid.cell_count, &grid.rank], &[], capacity as u64)
        })?;
        barrier(ctx, cmd);
        let blocks = grid.cells / SCAN_BLOCK;
        let scan_buffers = [&grid.cell_count, &grid.cell_start, &grid.block_sums];
        profiler.scope(cmd, "lookup/scan", || {
            for (phase, groups) in [(0u32, blocks), (1, 1), (2, blocks)] {
                let push = ScanPush { cells: grid.cells, phase };
                self.scan.dispatch_groups(cmd, &scan_buffers, bytemuck::bytes_of(&push), [groups, 1, 1])?;
                barrier(ctx, cmd);
            }
            Ok(())
        })?;
        profiler.scope(cmd, "lookup/scatter", || {
            self.scatter.dispatch(
                cmd,
                &[params, photons, counter, &grid.rank, &grid.cell_start, &grid.sorted],
                &[],
                capacity as u64,
            )
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
}

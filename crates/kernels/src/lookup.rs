//! Stage 3b, `shaders/lookup/`: the photon grid, a hashed uniform grid rebuilt per batch by a counting
//! sort (count, exclusive scan, scatter). Hit points then read the buckets their sphere overlaps.

use anyhow::{bail, Result};
use bytemuck::{Pod, Zeroable};
use ppm_vk_device::{barrier, vk, Buffer, BufferKind, ComputePipeline, Context, Profiler};

use crate::push_struct;

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
    /// Per bucket: records in it while building; zero between batches.
    pub cell_count: Buffer,
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
    /// A grid of `cells` buckets (see [`Grid::set_cells`]) over a record buffer of `capacity` records.
    pub fn new(ctx: &Context, cells: u32, capacity: u32) -> Result<Grid> {
        check_cells(cells)?;
        let record_size = std::mem::size_of::<crate::layout::Photon>() as u64;
        let table = Table::new(ctx, cells)?;
        let status = Buffer::new(ctx, "grid lookup status", 4, BufferKind::Storage)?;
        ctx.run(|cmd| {
            status.cmd_fill(cmd, 0);
            Ok(())
        })?;
        Ok(Grid {
            cells,
            allocated: cells,
            cell_count: table.cell_count,
            cell_start: table.cell_start,
            block_sums: table.block_sums,
            sorted: Buffer::new(ctx, "grid sorted records", capacity as u64 * record_size, BufferKind::Storage)?,
            status,
        })
    }

    /// Uses `cells` buckets from now on (the kernels' hash mask must agree): a power of two, at least
    /// [`SCAN_BLOCK`] and at most 65536 blocks. The table grows when they are more than it holds (the
    /// renderer shrinks the cells as the radii shrink, and smaller cells want more buckets); it never
    /// shrinks, so the memory is the largest table the render needed.
    pub fn set_cells(&mut self, ctx: &Context, cells: u32) -> Result<()> {
        check_cells(cells)?;
        if cells > self.allocated {
            let table = Table::new(ctx, cells)?;
            (self.cell_count, self.cell_start, self.block_sums) = (table.cell_count, table.cell_start, table.block_sums);
            self.allocated = cells;
        }
        self.cells = cells;
        Ok(())
    }
}

fn check_cells(cells: u32) -> Result<()> {
    if !cells.is_power_of_two() || cells < SCAN_BLOCK || cells / SCAN_BLOCK > 65536 {
        bail!("photon grid: {cells} buckets is not a power of two in [{SCAN_BLOCK}, {}]", SCAN_BLOCK as u64 * 65536);
    }
    Ok(())
}

/// The hash table's buffers; `cell_count` starts zeroed (the count kernel adds, the scatter clears).
struct Table {
    cell_count: Buffer,
    cell_start: Buffer,
    block_sums: Buffer,
}

impl Table {
    fn new(ctx: &Context, cells: u32) -> Result<Table> {
        let cell_count = Buffer::new(ctx, "grid cell_count", cells as u64 * 4, BufferKind::Storage)?;
        ctx.run(|cmd| {
            cell_count.cmd_fill(cmd, 0);
            Ok(())
        })?;
        Ok(Table {
            cell_count,
            cell_start: Buffer::new(ctx, "grid cell_start", (cells as u64 + 1) * 4, BufferKind::Storage)?,
            block_sums: Buffer::new(ctx, "grid block_sums", (cells / SCAN_BLOCK) as u64 * 4, BufferKind::Storage)?,
        })
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
            self.count.dispatch(cmd, &[params, photons, counter, &grid.cell_count], &[], capacity as u64)
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
                &[params, photons, counter, &grid.cell_count, &grid.cell_start, &grid.sorted],
                &[],
                capacity as u64,
            )
        })
    }
}

//! Stage 4, `shaders/gather/`: per hit point, this batch's photons within R (gather.comp), then the
//! progressive radius and flux update (update.comp, eq. 3, 6, 14).

use anyhow::Result;
use bytemuck::{Pod, Zeroable};
use ppm_vk_device::{vk, Buffer, ComputePipeline};

use crate::lookup::Grid;
use crate::push_struct;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GatherPush {
    /// Entries of the hit-point order (the non-empty slots).
    pub count: u32,
    /// Cone filter constant k >= 1, or 0 for none (eq. 10).
    pub cone_k: f32,
}
push_struct!(GatherPush, GATHER);

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct UpdatePush {
    pub count: u32,
    pub alpha: f32,
    /// `RenderParams::flux_fixed`.
    pub flux_fixed: f32,
    pub pad0: u32,
}
push_struct!(UpdatePush, UPDATE);

/// Per-hit-point state the gather and update read and write.
pub struct HitBuffers<'a> {
    pub hit_points: &'a Buffer,
    pub stats: &'a Buffer,
    pub accum: &'a Buffer,
    /// Indices of the non-empty slots, in the order threads take them (spatially coherent).
    pub order: &'a Buffer,
}

/// The bindings of the kernels that read the photon grid per hit point (gather.comp and probe.comp).
pub fn grid_reader_bindings<'a>(params: &'a Buffer, hits: &HitBuffers<'a>, grid: &'a Grid) -> [&'a Buffer; 8] {
    [params, hits.hit_points, hits.stats, hits.accum, &grid.sorted, &grid.cell_start, hits.order, &grid.status]
}

/// Hit points one gather or probe thread takes together in the kernels as built (`GROUP` in
/// shaders/common/neighbours.glsl); [`with_group`] compiles a variant with another count.
pub const GROUP: u32 = 4;

/// A kernel that reads the photon grid (gather or probe) compiled to take `group` hit points per thread.
pub fn with_group(ctx: &ppm_vk_device::Context, k: &crate::reflected::KernelInfo, group: u32) -> Result<GridReader> {
    let pipeline = match group {
        GROUP => crate::pipeline(ctx, k)?,
        _ => crate::pipeline_from(ctx, k, &crate::specialize::compile_with(k, &[("GROUP_SIZE", &group.to_string())], "")?)?,
    };
    Ok(GridReader { pipeline, group })
}

/// A gather or probe pipeline and the hit points each of its threads takes.
pub struct GridReader {
    pub pipeline: ComputePipeline,
    pub group: u32,
}

pub fn record_gather(
    k: &GridReader,
    cmd: vk::CommandBuffer,
    params: &Buffer,
    hits: &HitBuffers,
    grid: &Grid,
    push: &GatherPush,
) -> Result<()> {
    let threads = push.count.div_ceil(k.group) as u64;
    k.pipeline.dispatch(cmd, &grid_reader_bindings(params, hits, grid), bytemuck::bytes_of(push), threads)
}

/// The update (eq. 3, 6, 14). `r2_max` (two words, zeroed before) receives the f32 bits of the largest
/// R^2 after it: over the hit points live this pass, and over all slots (`RadiusMax`).
pub fn record_update(
    k: &ComputePipeline,
    cmd: vk::CommandBuffer,
    hits: &HitBuffers,
    r2_max: &Buffer,
    push: &UpdatePush,
) -> Result<()> {
    let buffers = [hits.stats, hits.accum, hits.order, hits.hit_points, r2_max];
    k.dispatch(cmd, &buffers, bytemuck::bytes_of(push), push.count as u64)
}

/// The largest R^2 the update saw, from the two words it wrote.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RadiusMax {
    /// Over the hit points live in the pass (SPPM: whose eye path found a diffuse surface).
    pub live: f32,
    /// Over every slot in the order.
    pub all: f32,
}

impl RadiusMax {
    pub fn from_bits(bits: [u32; 2]) -> RadiusMax {
        RadiusMax { live: f32::from_bits(bits[0]), all: f32::from_bits(bits[1]) }
    }
}

//! Stage 4, `shaders/gather/`: per hit point, this batch's photons within R (gather.comp); the progressive
//! update that follows is stage 4b, [`crate::update`].

use anyhow::Result;
use bytemuck::{Pod, Zeroable};
use ppm_vk_device::{vk, Buffer, BufferSlice, ComputePipeline};

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

/// Per-hit-point state the gather and update read and write: one tile's slots (the renderer binds the
/// per-slot buffers in slices of consecutive slots, each within the device's largest storage binding).
pub struct HitBuffers<'a> {
    pub hit_points: BufferSlice<'a>,
    pub stats: BufferSlice<'a>,
    pub accum: BufferSlice<'a>,
    /// Indices of the non-empty slots, in the order threads take them (spatially coherent); relative to
    /// the first slot of the slices above.
    pub order: BufferSlice<'a>,
}

/// The bindings of the kernels that read the photon grid per hit point (gather.comp and probe.comp).
pub fn grid_reader_bindings<'a>(params: &'a Buffer, hits: &HitBuffers<'a>, grid: &'a Grid) -> [BufferSlice<'a>; 8] {
    [
        params.whole(),
        hits.hit_points,
        hits.stats,
        hits.accum,
        grid.records.whole(),
        grid.cell_start.whole(),
        hits.order,
        grid.status.whole(),
    ]
}

/// Hit points one gather or probe thread takes together in the kernels as built (`GROUP` in
/// shaders/common/neighbours.glsl); [`with_group`] compiles a variant with another count.
pub const GROUP: u32 = 2;

/// A kernel that reads the photon grid (gather or probe) compiled to take `group` hit points per thread,
/// and what making it cost.
pub fn with_group(
    ctx: &ppm_vk_device::Context,
    k: &crate::reflected::KernelInfo,
    group: u32,
) -> Result<(GridReader, crate::specialize::KernelTiming)> {
    with_variant(ctx, k, group, true, true)
}

/// The same, and for the gather whether it evaluates the BRDFs of glossy hit points (`GLOSSY_HITS` in
/// gather.comp) and whether a photon may carry more than a light gives one (`WIDE_FLUX`: smooth shading,
/// shading.glsl); the kernel as built does both, and a scene that needs neither gets a gather without them.
pub fn with_variant(
    ctx: &ppm_vk_device::Context,
    k: &crate::reflected::KernelInfo,
    group: u32,
    glossy: bool,
    wide: bool,
) -> Result<(GridReader, crate::specialize::KernelTiming)> {
    let flag = |on: bool| if on { "1" } else { "0" };
    let group_text = group.to_string();
    let defines = match (group, glossy, wide) {
        (GROUP, true, true) => vec![],
        _ => vec![
            ("GROUP_SIZE", group_text.as_str()),
            ("GLOSSY_HITS", flag(glossy)),
            ("WIDE_FLUX", flag(wide)),
        ],
    };
    let (pipeline, timing) = crate::specialize::build(ctx, k, &defines, "")?;
    Ok((GridReader { pipeline, group }, timing))
}

/// A gather or probe pipeline and the hit points each of its threads takes.
pub struct GridReader {
    pub pipeline: ComputePipeline,
    pub group: u32,
}

/// `materials`: the material table (binding 8), whose rough conductors' BRDFs glossy hit points evaluate.
pub fn record_gather(
    k: &GridReader,
    cmd: vk::CommandBuffer,
    params: &Buffer,
    hits: &HitBuffers,
    grid: &Grid,
    materials: &Buffer,
    push: &GatherPush,
) -> Result<()> {
    let threads = push.count.div_ceil(k.group) as u64;
    let [a, b, c, d, e, f, g, h] = grid_reader_bindings(params, hits, grid);
    k.pipeline.dispatch_slices(
        cmd,
        &[a, b, c, d, e, f, g, h, materials.whole()],
        bytemuck::bytes_of(push),
        threads,
    )
}

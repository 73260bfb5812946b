//! Stage 5, `shaders/resolve/resolve.comp`: the image from the hit points' statistics (eq. 1-2, 11).

use anyhow::Result;
use bytemuck::{Pod, Zeroable};
use ppm_vk_device::{vk, Buffer, BufferSlice, ComputePipeline};

use crate::push_struct;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ResolvePush {
    /// Photons emitted by all photon passes so far.
    pub emitted: f64,
    /// 1, or the cone filter's 1 - 2/(3k) (eq. 11).
    pub norm: f32,
    /// Pixels of the dispatch's tile (the renderer's): the bound slices start at its first pixel.
    pub tile_pixels: u32,
}
push_struct!(ResolvePush, RESOLVE);

// One argument per buffer the kernel binds, in binding order (the reflected layout checks it).
#[allow(clippy::too_many_arguments)]
pub fn record(
    k: &ComputePipeline,
    cmd: vk::CommandBuffer,
    params: &Buffer,
    stats: BufferSlice,
    direct: BufferSlice,
    image: BufferSlice,
    push: &ResolvePush,
) -> Result<()> {
    k.dispatch_slices(
        cmd,
        &[params.whole(), stats, direct, image],
        bytemuck::bytes_of(push),
        push.tile_pixels as u64,
    )
}

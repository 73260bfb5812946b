//! Stage 5, `shaders/resolve/resolve.comp`: the image from the hit points' statistics (eq. 1-2, 11).

use anyhow::Result;
use bytemuck::{Pod, Zeroable};
use ppm_vk_device::{vk, Buffer, ComputePipeline};

use crate::push_struct;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ResolvePush {
    /// Photons emitted by all photon passes so far.
    pub emitted: f64,
    /// 1, or the cone filter's 1 - 2/(3k) (eq. 11).
    pub norm: f32,
    pub pad0: f32,
}
push_struct!(ResolvePush, RESOLVE);

// One argument per buffer the kernel binds, in binding order (the reflected layout checks it).
#[allow(clippy::too_many_arguments)]
pub fn record(
    k: &ComputePipeline,
    cmd: vk::CommandBuffer,
    params: &Buffer,
    stats: &Buffer,
    direct: &Buffer,
    image: &Buffer,
    pixels: u32,
    push: &ResolvePush,
) -> Result<()> {
    k.dispatch(
        cmd,
        &[params, stats, direct, image],
        bytemuck::bytes_of(push),
        pixels as u64,
    )
}

//! Stage 4b, `shaders/update/`: the progressive radius and flux update after a photon pass (update.comp,
//! eq. 3, 6, 14), which also clears the pass accumulators the gather filled.

use anyhow::Result;
use bytemuck::{Pod, Zeroable};
use ppm_vk_device::{vk, ComputePipeline};

use crate::gather::HitBuffers;
use crate::push_struct;

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

pub fn record_update(k: &ComputePipeline, cmd: vk::CommandBuffer, hits: &HitBuffers, push: &UpdatePush) -> Result<()> {
    k.dispatch(cmd, &[hits.stats, hits.accum, hits.order, hits.hit_points], bytemuck::bytes_of(push), push.count as u64)
}

//! Stage 4b, `shaders/update/`: the progressive radius and flux update after a photon pass (update.comp,
//! eq. 3, 6, 14), which also clears the pass accumulators the gather filled.

use anyhow::Result;
use bytemuck::{Pod, Zeroable};
use ppm_vk_device::{vk, Buffer, ComputePipeline};

use crate::gather::HitBuffers;
use crate::push_struct;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct UpdatePush {
    pub count: u32,
    pub alpha: f32,
    /// `RenderParams::flux_fixed`.
    pub flux_fixed: f32,
    /// The adaptive shrink's significance in standard deviations (`Settings::shrink_z`); 0: off.
    pub shrink_z: f32,
    /// The least R^2 the adaptive shrink sets.
    pub r2_floor: f32,
}
push_struct!(UpdatePush, UPDATE);

/// The update (eq. 3, 6, 14). `r2_max` (two words, zeroed before) receives the f32 bits of the largest
/// R^2 after it: over the hit points live this pass, and over all slots (`RadiusMax`).
pub fn record_update(
    k: &ComputePipeline,
    cmd: vk::CommandBuffer,
    hits: &HitBuffers,
    r2_max: &Buffer,
    push: &UpdatePush,
) -> Result<()> {
    let buffers = [hits.stats, hits.accum, hits.order, hits.hit_points, r2_max.whole()];
    k.dispatch_slices(cmd, &buffers, bytemuck::bytes_of(push), push.count as u64)
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
        RadiusMax {
            live: f32::from_bits(bits[0]),
            all: f32::from_bits(bits[1]),
        }
    }
}

//! Stage 3, `shaders/photon/photon.comp`: photons from the lights to diffuse surfaces.

use anyhow::Result;
use bytemuck::{Pod, Zeroable};
use ppm_vk_device::{vk, Buffer, ComputePipeline};

use crate::push_struct;
use crate::ray::SceneBuffers;

/// Most records one photon path may leave (`MAX_RECORDS` in photon.comp).
pub const MAX_RECORDS: u32 = 16;
/// Photons each thread traces one after another (`PER_THREAD` in photon.comp).
pub const PER_THREAD: u32 = 8;
/// Random-stream families, so photon passes, the probe pass and the eye pass never share numbers.
pub const SALT_PHOTON: u32 = 1;
pub const SALT_PROBE: u32 = 2;
pub const SALT_EYE: u32 = 3;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PhotonPush {
    /// Global index of the batch's first photon (its random stream).
    pub first: u64,
    pub count: u32,
    pub salt: u32,
}
push_struct!(PhotonPush, PHOTON);

/// Traces `push.count` photons, appending their records to `photons` and counting them in `counter`
/// (which must be zero before; records past the capacity are counted but not written).
pub fn record(
    k: &ComputePipeline,
    cmd: vk::CommandBuffer,
    scene: &SceneBuffers,
    lights: &Buffer,
    photons: &Buffer,
    counter: &Buffer,
    push: &PhotonPush,
) -> Result<()> {
    k.dispatch(
        cmd,
        &[scene.params, scene.spheres, scene.quads, scene.materials, lights, photons, counter],
        bytemuck::bytes_of(push),
        push.count.div_ceil(PER_THREAD) as u64,
    )
}

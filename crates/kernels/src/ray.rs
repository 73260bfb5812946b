//! Stage 1, `shaders/ray/ray.comp`: camera rays to diffuse hit points.

use anyhow::Result;
use bytemuck::{Pod, Zeroable};
use ppm_vk_device::{vk, Buffer, ComputePipeline};

use crate::push_struct;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct RayPush {
    /// Sample position inside the pixel, [0,1)^2; (0.5, 0.5) is the centre; negative: a random position
    /// per pixel ([`JITTER_RANDOM`]).
    pub jitter: [f32; 2],
    pub salt: u32,
    /// Eye pass index: pixel p of pass k draws from random stream k * pixels + p.
    pub pass: u32,
}

/// `RayPush::jitter` for a random position in every pixel (SPPM's box filter).
pub const JITTER_RANDOM: [f32; 2] = [-1.0, -1.0];
push_struct!(RayPush, RAY);

/// The scene as the tracing kernels see it (bindings 0-3 of `ray` and `photon`).
pub struct SceneBuffers<'a> {
    pub params: &'a Buffer,
    pub spheres: &'a Buffer,
    pub quads: &'a Buffer,
    pub materials: &'a Buffer,
}

/// Writes `hit_slots` hit points per pixel into `hit_points` and adds the directly seen emission to
/// `direct` (rgb) and 1 to its w.
pub fn record(
    k: &ComputePipeline,
    cmd: vk::CommandBuffer,
    scene: &SceneBuffers,
    hit_points: &Buffer,
    direct: &Buffer,
    pixels: u32,
    push: &RayPush,
) -> Result<()> {
    k.dispatch(
        cmd,
        &[scene.params, scene.spheres, scene.quads, scene.materials, hit_points, direct],
        bytemuck::bytes_of(push),
        pixels as u64,
    )
}

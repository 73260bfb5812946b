//! Stage 2, `shaders/probe/probe.comp`: photon probing (eq. 7-9), run once after the ray pass.

use anyhow::Result;
use bytemuck::{Pod, Zeroable};
use ppm_vk_device::{vk, Buffer};

use crate::gather::HitBuffers;
use crate::lookup::Grid;
use crate::push_struct;

/// Eq. 9 as printed (its result depends on the scene's units).
pub const MODE_PAPER: u32 = 1;
/// r' = r (1 + lambda / r^2).
pub const MODE_SCALE_FREE: u32 = 2;
/// r' = r sqrt(k / N): the radius that holds k probe photons where they are N within r.
pub const MODE_NEAREST: u32 = 3;
/// r' from the count within r and within r / 2: the radius of least bias^2 + variance (probe.comp).
pub const MODE_CURVATURE: u32 = 4;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ProbePush {
    /// Entries of the hit-point order.
    pub count: u32,
    /// 0: accumulate a batch of probe photons; 1: set the radii.
    pub phase: u32,
    pub mode: u32,
    /// The mode's constant: beta as a fraction of r (paper, scale-free), k (nearest); the largest r' / r (curvature).
    pub param: f32,
}
push_struct!(ProbePush, PROBE);

pub fn record(
    k: &crate::gather::GridReader,
    cmd: vk::CommandBuffer,
    params: &Buffer,
    hits: &HitBuffers,
    grid: &Grid,
    push: &ProbePush,
) -> Result<()> {
    // Phase 0 takes GROUP hit points per thread (neighbours.glsl), phase 1 one.
    let threads = if push.phase == 0 {
        push.count.div_ceil(k.group)
    } else {
        push.count
    };
    k.pipeline.dispatch_slices(
        cmd,
        &crate::gather::grid_reader_bindings(params, hits, grid),
        bytemuck::bytes_of(push),
        threads as u64,
    )
}

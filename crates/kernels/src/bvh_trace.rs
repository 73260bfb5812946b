//! Test kernel `shaders/bvh/bvh_trace.comp`: the nearest triangle hit per ray through the BVH traversal of
//! `shaders/common/bvh.glsl`. Not a pipeline stage: it checks the GLSL traversal against the CPU reference.

use anyhow::{bail, Result};
use bytemuck::{Pod, Zeroable};
use ppm_vk_device::{vk, Buffer, ComputePipeline};

use crate::{gpu_struct, push_struct};

/// lavapipe's iterations per SIMD group over all loops of an invocation (`BVH_LOOP_LIMIT` in bvh.glsl).
pub const LOOP_LIMIT: u32 = crate::reflected::constants::BVH_LOOP_LIMIT;
/// The largest step budget this kernel may pass: a traversal loop costs its longest lane's steps plus one,
/// and the kernel has no other loop.
pub const MAX_BUDGET: u32 = LOOP_LIMIT - 1;
/// Entries of the traversal stack (`BVH_MAX_DEPTH` in bvh.glsl): a BVH deeper than this cannot be traced.
pub const MAX_DEPTH: u32 = crate::reflected::constants::BVH_MAX_DEPTH;
/// `TraceHit::triangle` of a miss.
pub const NO_HIT: u32 = u32::MAX;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TraceRay {
    pub origin: [f32; 3],
    pub tmin: f32,
    /// Need not be unit: t is in units of its length.
    pub dir: [f32; 3],
    pub tmax: f32,
}
gpu_struct!(TraceRay {
    origin,
    tmin,
    dir,
    tmax
});

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TraceHit {
    /// Geometric normal, front side counter-clockwise; 0 on a miss.
    pub normal: [f32; 3],
    /// The ray's tmax on a miss.
    pub t: f32,
    /// Barycentric weights of v1 and v2.
    pub bary: [f32; 2],
    /// Index into the leaf-ordered triangles, or [`NO_HIT`].
    pub triangle: u32,
    /// Node visits plus triangle tests.
    pub steps: u32,
    /// 1: stopped at the step budget; the hit is not final.
    pub cut: u32,
    /// `bvh_subgroup_cost`: the loop iterations the traversal cost this lane's subgroup.
    pub subgroup_cost: u32,
    pub subgroup_size: u32,
    /// The root's first child, read through the typed alias of the node buffer (checks the layout the
    /// traversal's 64-bit reads assume).
    pub root_child: u32,
}
gpu_struct!(TraceHit {
    normal,
    t,
    bary,
    triangle,
    steps,
    cut,
    subgroup_cost,
    subgroup_size,
    root_child
});

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TracePush {
    pub count: u32,
    /// Steps each traversal may take, at most [`MAX_BUDGET`].
    pub budget: u32,
    /// 1: shadow rays, whose traversal ends at the first hit it finds (any hit, not the nearest).
    pub any_hit: u32,
}
push_struct!(TracePush, BVH_TRACE);

/// Records the traversal of `push.count` rays from `rays` into `hits` (both `count` records long).
pub fn record(
    k: &ComputePipeline,
    cmd: vk::CommandBuffer,
    nodes: &Buffer,
    triangles: &Buffer,
    rays: &Buffer,
    hits: &Buffer,
    push: &TracePush,
) -> Result<()> {
    if push.budget > MAX_BUDGET {
        bail!(
            "bvh_trace: a step budget of {} is more than lavapipe's loop limit allows ({MAX_BUDGET})",
            push.budget
        );
    }
    k.dispatch(
        cmd,
        // The nodes and triangles twice: as texels for the traversal, as typed records for the checks.
        &[nodes, triangles, rays, hits, nodes, triangles],
        bytemuck::bytes_of(push),
        push.count as u64,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The limits stated here are the ones bvh.glsl uses.
    #[test]
    fn constants_match_the_glsl() {
        let glsl = crate::reflected::SOURCES
            .iter()
            .find(|(p, _)| *p == "common/bvh.glsl")
            .unwrap()
            .1;
        for line in [
            format!("const uint BVH_MAX_DEPTH = {MAX_DEPTH}u;"),
            format!("const uint BVH_LOOP_LIMIT = {LOOP_LIMIT}u;"),
            format!("const uint BVH_NONE = 0x{NO_HIT:x}u;"),
            format!("const uint BVH_LEAF = 0x{:x}u;", crate::layout::BVH_LEAF),
        ] {
            assert!(glsl.lines().any(|l| l.starts_with(&line)), "bvh.glsl lacks `{line}`");
        }
    }
}

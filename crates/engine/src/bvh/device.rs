//! The Vulkan side of the BVH: a tree in device buffers, and the test kernel that traces rays through it.

use anyhow::{bail, Context as _, Result};
use ppm_vk_device::{Buffer, ComputePipeline, Context};
use ppm_vk_kernels::bvh_trace::{self, TraceHit, TracePush, TraceRay};

use super::Bvh;

/// A BVH in device buffers, for a kernel that includes `shaders/common/bvh.glsl`: bind `nodes` (the 4-wide
/// tree) to its `BvhNode bvh_nodes[]` and `triangles` to its `Triangle bvh_triangles[]`.
pub struct DeviceBvh {
    pub nodes: Buffer,
    pub triangles: Buffer,
}

impl DeviceBvh {
    pub fn new(ctx: &Context, bvh: &Bvh) -> Result<DeviceBvh> {
        // build() never makes a tree the GPU cannot walk (its stack holds three children of MAX_DEPTH
        // levels), but a Bvh may have been put together or changed by hand, and a bad index would read out
        // of bounds there.
        bvh.validate_wide()
            .context("uploading a BVH the GPU traversal cannot take")?;
        Ok(DeviceBvh {
            nodes: ctx
                .buffer_from("bvh nodes", &bvh.wide)
                .context("uploading the BVH's nodes")?,
            triangles: ctx
                .buffer_from("bvh triangles", &bvh.triangles)
                .context("uploading the BVH's triangles")?,
        })
    }
}

/// The test kernel `bvh_trace.comp`: nearest hits of a batch of rays on the GPU.
pub struct BvhTracer {
    pipeline: ComputePipeline,
}

impl BvhTracer {
    pub fn new(ctx: &Context) -> Result<BvhTracer> {
        Ok(BvhTracer {
            pipeline: ppm_vk_kernels::pipeline(ctx, &ppm_vk_kernels::reflected::BVH_TRACE)?,
        })
    }

    /// The nearest hit of each ray, each traversal taking at most `budget` steps (at most
    /// [`bvh_trace::MAX_BUDGET`]); records of cut traversals keep `cut = 1`. See [`BvhTracer::trace`].
    pub fn trace_unchecked(
        &self,
        ctx: &Context,
        bvh: &DeviceBvh,
        rays: &[TraceRay],
        budget: u32,
    ) -> Result<Vec<TraceHit>> {
        self.dispatch(ctx, bvh, rays, budget, false)
    }

    /// Shadow rays: each traversal ends at the first hit it finds (any hit in (tmin, tmax), not the
    /// nearest); records as [`BvhTracer::trace_unchecked`]'s.
    pub fn trace_any_unchecked(
        &self,
        ctx: &Context,
        bvh: &DeviceBvh,
        rays: &[TraceRay],
        budget: u32,
    ) -> Result<Vec<TraceHit>> {
        self.dispatch(ctx, bvh, rays, budget, true)
    }

    fn dispatch(
        &self,
        ctx: &Context,
        bvh: &DeviceBvh,
        rays: &[TraceRay],
        budget: u32,
        any_hit: bool,
    ) -> Result<Vec<TraceHit>> {
        if rays.is_empty() {
            return Ok(Vec::new());
        }
        let ray_buf = ctx.buffer_from("bvh trace rays", rays).context("uploading the rays")?;
        let hit_buf = Buffer::new(
            ctx,
            "bvh trace hits",
            std::mem::size_of_val(rays) as u64 / std::mem::size_of::<TraceRay>() as u64
                * std::mem::size_of::<TraceHit>() as u64,
            ppm_vk_device::BufferKind::Storage,
        )?;
        let push = TracePush {
            count: rays.len() as u32,
            budget,
            any_hit: any_hit as u32,
        };
        ctx.run(|cmd| {
            bvh_trace::record(
                &self.pipeline,
                cmd,
                &bvh.nodes,
                &bvh.triangles,
                &ray_buf,
                &hit_buf,
                &push,
            )
        })
        .context("tracing rays through the BVH")?;
        ctx.download_prefix(&hit_buf, rays.len())
            .context("reading the BVH hits back")
    }

    /// [`BvhTracer::trace_unchecked`] that fails if any traversal was cut at the budget: its hit would be
    /// wrong without a word (on lavapipe the device's own loop limit cuts the same way, silently).
    pub fn trace(&self, ctx: &Context, bvh: &DeviceBvh, rays: &[TraceRay], budget: u32) -> Result<Vec<TraceHit>> {
        let hits = self.trace_unchecked(ctx, bvh, rays, budget)?;
        let cut: Vec<usize> = hits
            .iter()
            .enumerate()
            .filter(|(_, h)| h.cut != 0)
            .map(|(i, _)| i)
            .collect();
        if let Some(&first) = cut.first() {
            bail!(
                "{} of {} BVH traversals were cut at the budget of {budget} loop steps (node visits + triangle \
                 tests; lavapipe ends a SIMD group's loops after {} iterations), first ray {first}: too many \
                 overlapping triangles along the ray",
                cut.len(),
                hits.len(),
                bvh_trace::LOOP_LIMIT
            );
        }
        Ok(hits)
    }
}

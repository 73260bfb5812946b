//! Stage 1, `shaders/ray/ray.comp`: camera rays to diffuse hit points.

use anyhow::Result;
use bytemuck::{Pod, Zeroable};
use ppm_vk_device::{vk, Buffer, BufferSlice, ComputePipeline};

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
    /// Paths per pixel (in the pixels the pilot marked) that collect the emission seen through mirrors and
    /// glass (ray.comp), and with direct light sampled the direct light at their diffuse ends.
    pub emission_samples: u32,
    /// 1: trace the hit-point path; 0: only the emission samples.
    pub trace_hits: u32,
    /// Which dispatch of the eye pass this is: an eye pass whose emission samples do not fit one thread's
    /// loop budget runs in several (`PathLimits::emission_per_dispatch`), each with its own streams.
    pub chunk: u32,
    /// 1: eye pass 0, a pilot whose emission samples only mark the pixels that need them (ray.comp).
    pub pilot: u32,
    /// Emission samples (with direct light sampled: light samples too) per pixel the pilot did not mark;
    /// `emission_samples` is the count in the pixels it marked (and the pilot's most).
    pub light_samples: u32,
    /// The pilot's samples in every pixel; it takes the rest of `emission_samples` only where one of them
    /// met a mirror, smooth glass or a smooth coat ([`MARK_CHAIN`]).
    pub pilot_samples: u32,
    /// Samples per pixel (outside the pilot) where the pilot marked a rough lobe ([`MARK_ROUGH`]): at least
    /// `emission_samples` (`Settings::rough_pixel_samples`).
    pub rough_samples: u32,
    /// Samples per pixel one dispatch takes: dispatch `chunk` takes samples `chunk * per_dispatch` on.
    pub per_dispatch: u32,
    /// The dispatch's first pixel and its pixel count: the bound per-pixel slices start there (the
    /// renderer's tiles), while streams and camera rays keep the pixel's index in the image.
    pub first_pixel: u32,
    pub tile_pixels: u32,
}

/// A pilot mark (ray.comp's `busy`): the pilot saw the front of an emitter that no shadow ray takes, in the
/// pixel or beside it.
pub const MARK_EMISSION: u32 = 1;
/// A pilot mark: one of the pilot's shadow rays reached a light, in the pixel or beside it.
pub const MARK_LIT: u32 = 2;
/// A pilot mark: one of the pilot's paths sampled through a rough conductor or rough glass, in the pixel or
/// beside it.
pub const MARK_ROUGH: u32 = 4;
/// The pilot's own bit, read only by its later dispatches: one of its paths in the pixel left a vertex by a
/// mirror, smooth glass or a smooth coat, which can show a light as an image a pixel wide, so the pixel
/// takes the pilot's whole count. The renderer clears it before the marks spread (`spread_marks`).
pub const MARK_CHAIN: u32 = 8;
/// A pilot mark: one of the pilot's chains left a curved mirror or glass (a sphere, or a shading normal
/// off its face) and then passed near an area light, in the pixel or beside it: the pixel takes all the
/// emission samples, as for [`MARK_EMISSION`] (ray.comp's `passes_near_light`).
pub const MARK_NEAR: u32 = 16;
/// The renderer's mark for SPPM's glass splits (`Settings::glass_splits`): the pixel or a neighbour had a
/// pilot chain leave a curved mirror or glass ([`MARK_CURVED`]), so its eye path takes both Fresnel
/// branches at glass while it has slots, and the gather and update visit its split slots; elsewhere one
/// branch, drawn by Fresnel, and one slot (ray.comp).
pub const MARK_SPLIT: u32 = 32;
/// The pilot's own bit: one of its chains in the pixel followed a curved vertex (a sphere, or a shading
/// normal off its face), where a flat pane's chain would not. The renderer turns it into [`MARK_SPLIT`]
/// and clears it before the marks spread.
pub const MARK_CURVED: u32 = 64;

/// `RayPush::jitter` for a random position in every pixel (SPPM's box filter).
pub const JITTER_RANDOM: [f32; 2] = [-1.0, -1.0];
push_struct!(RayPush, RAY);

/// The scene as the tracing kernels see it (bindings 0-7 of `ray` and `photon`).
pub struct SceneBuffers<'a> {
    pub params: &'a Buffer,
    pub spheres: &'a Buffer,
    pub quads: &'a Buffer,
    pub materials: &'a Buffer,
    /// The triangle BVH (`BvhNode`, `Triangle`); one empty leaf without meshes.
    pub bvh_nodes: &'a Buffer,
    pub bvh_triangles: &'a Buffer,
    /// The textures (texture.glsl) and the triangles' texture coordinates and vertex normals (shading.glsl);
    /// a zeroed texel each without.
    pub textures: &'a Buffer,
    pub triangle_texels: &'a Buffer,
}

impl SceneBuffers<'_> {
    /// Bindings 0-7 in order.
    pub fn bindings(&self) -> [&Buffer; 8] {
        [
            self.params,
            self.spheres,
            self.quads,
            self.materials,
            self.bvh_nodes,
            self.bvh_triangles,
            self.textures,
            self.triangle_texels,
        ]
    }
}

/// Writes `hit_slots` hit points per pixel into `hit_points` (with `push.trace_hits`), adds the emission
/// samples to `direct` (rgb, double) and their count to its w, and counts eye paths cut at the depth
/// backstop in `cut`.
// One argument per buffer the kernel binds, in binding order (the reflected layout checks it).
#[allow(clippy::too_many_arguments)]
pub fn record(
    k: &ComputePipeline,
    cmd: vk::CommandBuffer,
    scene: &SceneBuffers,
    hit_points: BufferSlice,
    direct: BufferSlice,
    cut: &Buffer,
    busy: BufferSlice,
    lights: &Buffer,
    push: &RayPush,
) -> Result<()> {
    let scene = scene.bindings().map(Buffer::whole);
    let own = [hit_points, direct, cut.whole(), busy, lights.whole()];
    k.dispatch_slices(
        cmd,
        &[&scene[..], &own[..]].concat(),
        bytemuck::bytes_of(push),
        push.tile_pixels as u64,
    )
}

//! The GLSL compute kernels of ppm-vk, compiled from `shaders/` by shaderc at build time, with typed
//! bindings. Knows nothing of scenes or files.
//!
//! One module per pipeline stage, in pipeline order: [`ray`] -> [`probe`] (once) -> [`photon`] -> [`lookup`]
//! -> [`gather`] -> [`update`] -> [`resolve`], and for a window [`tonemap`]. Each kernel's storage-buffer count, push-constant size and workgroup size come from
//! SPIR-V reflection ([`reflected`]); the records they share are in [`layout`], each checked at compile
//! time against glslang's std430 offsets. [`bvh_trace`] is a test kernel of the BVH traversal
//! (`shaders/common/bvh.glsl`), not a stage.

pub mod layout;

/// What build.rs reflected from each kernel's SPIR-V.
// Generated code (build.rs writes it): its style is the generator's, not a reader's.
#[allow(clippy::all)]
pub mod reflected {
    /// A compiled kernel and its interface.
    #[derive(Clone, Copy, Debug)]
    pub struct KernelInfo {
        pub name: &'static str,
        /// The folder under shaders/: the pipeline stage.
        pub stage: &'static str,
        /// Its source file, relative to shaders/.
        pub source: &'static str,
        pub spirv: &'static [u8],
        /// The names of its storage-buffer blocks and texel buffers, binding 0 first.
        pub bindings: &'static [&'static str],
        /// Bit b: binding b is a uniform texel buffer (read with texelFetch), not a storage buffer.
        pub texel_bindings: u32,
        pub push_size: u32,
        pub local_size: u32,
    }
    include!(concat!(env!("OUT_DIR"), "/reflected.rs"));

    /// Every kernel, in pipeline order, then the test kernel of the BVH traversal.
    pub const ALL: &[KernelInfo] = &[
        RAY,
        PROBE,
        PHOTON,
        PHOTON_RESUME,
        GRID_DISPATCH,
        GRID_COUNT,
        GRID_SCAN,
        GRID_OFFSETS,
        GRID_PARTITION,
        GRID_SCATTER,
        GATHER,
        UPDATE,
        RESOLVE,
        TONEMAP,
        BVH_TRACE,
    ];
}

pub mod bvh_trace;
pub mod gather;
pub mod inline_pairs;
pub mod lookup;
pub mod photon;
pub mod probe;
pub mod ray;
pub mod resolve;
pub mod specialize;
pub mod spirv_cache;
pub mod tonemap;
pub mod update;

use anyhow::{Context as _, Result};
use ppm_vk_device::{ComputePipeline, Context, PipelineDesc};

/// Creates the pipeline of one reflected kernel.
pub fn pipeline(ctx: &Context, k: &reflected::KernelInfo) -> Result<ComputePipeline> {
    let words = ash::util::read_spv(&mut std::io::Cursor::new(k.spirv))
        .with_context(|| format!("reading the SPIR-V of kernel {}", k.name))?;
    pipeline_from(ctx, k, &words)
}

/// Creates a pipeline with `k`'s interface from other SPIR-V of the same kernel (a specialised variant,
/// see [`specialize`]: it binds a subset of the same buffers).
pub fn pipeline_from(ctx: &Context, k: &reflected::KernelInfo, words: &[u32]) -> Result<ComputePipeline> {
    ComputePipeline::new(
        ctx,
        &PipelineDesc {
            name: k.name,
            spirv: words,
            bindings: k.bindings.len() as u32,
            texel_bindings: k.texel_bindings,
            push_size: k.push_size,
            local_size: k.local_size,
        },
    )
}

/// Checks at compile time that a `#[repr(C)]` struct matches the std430 layout glslang gave the GLSL
/// struct of the same name: size, every member's offset, and the member count.
#[macro_export]
macro_rules! gpu_struct {
    ($ty:ident { $($field:ident),+ $(,)? }) => {
        const _: () = {
            use $crate::reflected::layout::$ty as glsl;
            assert!(::core::mem::size_of::<$ty>() == glsl::SIZE, concat!(stringify!($ty), ": size differs from the GLSL std430 layout"));
            $(assert!(::core::mem::offset_of!($ty, $field) == glsl::$field,
                concat!(stringify!($ty), ".", stringify!($field), ": offset differs from the GLSL std430 layout"));)+
            assert!([$(stringify!($field)),+].len() == glsl::MEMBERS, concat!(stringify!($ty), ": member count differs from GLSL"));
        };
    };
}

/// Checks a push-constant struct against its kernel's reflected push-constant size.
#[macro_export]
macro_rules! push_struct {
    ($ty:ident, $kernel:ident) => {
        const _: () = assert!(
            ::core::mem::size_of::<$ty>() == $crate::reflected::$kernel.push_size as usize,
            concat!(
                stringify!($ty),
                ": size differs from the push-constant block of kernel ",
                stringify!($kernel)
            )
        );
    };
}

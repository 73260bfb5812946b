//! ppm-vk's device crate: thin, RAII wrappers over ash for compute work.
//!
//! It knows nothing of photons. It owns the Vulkan instance and device ([`Context`]), buffers
//! ([`Buffer`]), compute pipelines whose bindings are pushed per dispatch ([`ComputePipeline`]),
//! one-shot submission ([`Context::run`]) and named timestamp scopes ([`Profiler`]). Every Vulkan object it
//! makes carries a debug name ([`Context::name_object`]), and pipelines come through a pipeline cache kept
//! on disk between runs ([`ContextOptions::pipeline_cache`]). A viewer presents through a window's
//! [`Swapchain`].

mod buffer;
mod context;
mod pipeline;
mod pipeline_cache;
mod profiler;
mod swapchain;

pub use buffer::{Buffer, BufferKind, BufferSlice};
pub use context::{barrier, Context, ContextOptions, DeviceInfo, MemoryUsage};
pub use pipeline::{ComputePipeline, PipelineDesc};
pub use profiler::{Profiler, ScopeTiming};
pub use raw_window_handle;
pub use swapchain::{Presented, Swapchain};

pub use ash::vk;

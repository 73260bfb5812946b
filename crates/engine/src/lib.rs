//! ppm-vk's engine: progressive photon mapping (Hachisuka et al. 2008) as Vulkan compute kernels, following
//! Lee and Shin, "Improved Progressive Photon Mapping Using Photon Probing".
//!
//! Embedding it takes a device, a scene, a renderer, passes and an image:
//! ```no_run
//! # fn main() -> Result<(), ppm_vk_engine::Error> {
//! use ppm_vk_engine::{open_device, ContextOptions, Renderer, Scene, Settings};
//! let ctx = open_device(&ContextOptions::default())?;
//! let scene = Scene::load("scenes/cornell-spheres.toml")?;
//! let mut renderer = Renderer::new(&ctx, &scene, Settings { photons_per_pass: 200_000, ..Settings::default() })?;
//! for _ in 0..20 {
//!     let stats = renderer.pass()?;
//!     println!("pass {}: {:.1} ms", stats.index, stats.wall_ms);
//! }
//! renderer.image()?.save("cornell.exr")?;
//! # Ok(())
//! # }
//! ```
//! Every fallible call returns [`Error`], whose cases say what went wrong in terms a program can act
//! on: a scene error with its file, line, column and field, a device limit with what to lower, an I/O
//! error with its path, a device failure, a cancelled pass ([`CancelToken`]).
//!
//! The `test-hooks` feature makes public what only the tests and the CPU twin of every kernel (the
//! dev-only crate `ppm-vk-reference`) need: the record layouts and the renderer's hooks that read and write
//! device state.

pub mod checkpoint;
pub mod distributed;
mod error;
mod image_io;
pub mod metrics;
pub mod present;
mod renderer;
pub mod report;
pub mod settings;
/// The scene crate ([`ppm_vk_scene`]): the format-neutral scene and its readers.
pub use ppm_vk_scene as scene;
mod stats;

/// The BVH over a scene's triangles (binned SAH, widened to 4): public for the CPU twin and tools.
pub mod bvh;
/// The scene lowered to the kernels' records (`GpuScene`): public for the CPU twin and tools.
pub mod lower;
#[cfg(feature = "test-hooks")]
pub use ppm_vk_kernels::layout;

pub use bvh::BvhStats;
pub use checkpoint::Checkpoint;
pub use error::{Error, Result};
pub use image_io::RgbImage;
pub use ppm_vk_device::{raw_window_handle, Context, ContextOptions, DeviceInfo, ScopeTiming};
pub use ppm_vk_kernels::layout::PathCounters;
pub use ppm_vk_kernels::photon::PathLimits;
pub use renderer::{spread_marks, CancelToken, Renderer, TILE_ALIGN_PIXELS};
pub use scene::Scene;
pub use settings::{DirectLight, GlossyLight, Mode, ProbeMode, Settings};
pub use stats::{KernelSetup, PassStats, PhotonVariant, PilotMarks, ProbeReport, SetupTimes};

/// Opens a Vulkan device (see [`ContextOptions`]); a failure is [`Error::Device`].
pub fn open_device(options: &ContextOptions) -> Result<Context> {
    Context::new(options).map_err(Error::device("opening a Vulkan device"))
}

/// The devices the Vulkan loader sees, with what each lacks for ppm-vk.
pub fn list_devices() -> Result<Vec<DeviceInfo>> {
    Context::list_devices().map_err(Error::device("listing Vulkan devices"))
}

//! ppm-vk's engine: progressive photon mapping (Hachisuka et al. 2008) as Vulkan compute kernels, following
//! Lee and Shin, "Improved Progressive Photon Mapping Using Photon Probing".
//!
//! Embedding it takes a context, a scene, a renderer, passes and an image:
//! ```no_run
//! # fn main() -> anyhow::Result<()> {
//! use ppm_vk_engine::{Context, ContextOptions, Renderer, Scene, Settings};
//! let ctx = Context::new(&ContextOptions::default())?;
//! let scene = Scene::load("scenes/cornell-spheres.toml".as_ref())?;
//! let mut renderer = Renderer::new(&ctx, &scene, Settings { photons_per_pass: 200_000, ..Settings::default() })?;
//! for _ in 0..20 {
//!     let stats = renderer.pass()?;
//!     println!("pass {}: {:.1} ms", stats.index, stats.wall_ms);
//! }
//! renderer.image()?.save("cornell.exr".as_ref())?;
//! # Ok(())
//! # }
//! ```
//! Every kernel has a CPU twin in [`reference`] that the tests compare against on identical inputs.

pub mod bvh;
pub mod checkpoint;
pub mod gpu_scene;
pub mod image_io;
pub mod metrics;
pub mod reference;
pub mod renderer;
pub mod report;
pub mod scene;
pub mod settings;

pub use checkpoint::Checkpoint;
pub use image_io::RgbImage;
pub use ppm_vk_device::{Context, ContextOptions, DeviceInfo, ScopeTiming};
pub use ppm_vk_kernels::layout;
pub use renderer::{PassStats, PhotonVariant, ProbeReport, Renderer};
pub use scene::Scene;
pub use settings::{Mode, ProbeMode, Settings};

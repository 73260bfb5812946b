//! ppm-vk's materials on the host: each BSDF's math (its parameters, the pure parts of its eval, sample and
//! pdf) and the tables derived from it, one module per BSDF beside its GLSL of the same name in
//! `shaders/materials/` (tests/pairs.rs holds them to it), and the leaf math they share (`math`, `rng`).
//! It depends on glam alone: the scene reads materials into these types, the engine lowers them for the
//! kernels, and the CPU twin of the kernels (crates/reference) walks a scene with them, so nothing here knows a
//! scene or the kernels' record layout.

pub mod blend;
pub mod conductor;
pub mod mask;
pub mod math;
pub mod microfacet;
pub mod normal_map;
pub mod plastic;
pub mod rng;
pub mod rough_conductor;
pub mod rough_dielectric;
pub mod rough_plastic;
#[cfg(any(test, feature = "test-support"))]
pub mod testing;
pub mod thin_dielectric;

pub use microfacet::Microfacet;

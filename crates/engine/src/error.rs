//! The error type is the scene crate's ([`ppm_vk_scene::Error`], re-exported as [`crate::Error`]): one
//! type from the scene readers up. This adds what only the engine needs: device failures from the
//! device crate's `anyhow` results.

pub use ppm_vk_scene::error::{Error, Result};

/// `anyhow::Result` from the device crate into [`Error::Device`]: `ctx.run(..).device("the ray pass")?`.
pub(crate) trait DeviceContext<T> {
    fn device(self, context: &str) -> Result<T>;
}

impl<T> DeviceContext<T> for anyhow::Result<T> {
    fn device(self, context: &str) -> Result<T> {
        self.map_err(|e| Error::Device {
            context: context.to_string(),
            error: e.into(),
        })
    }
}

//! Showing a render in a window, for a viewer (`ppm-vk view`) or an embedder with its own window: the
//! estimate resolved (eq. 1-2), tone-mapped on the device (`shaders/resolve/tonemap.comp`) into a buffer
//! of the window's size and copied into a swapchain image. The tone mapping is `RgbImage::save_png`'s
//! (2^exposure, clamp, the sRGB OETF), so a window of the image's size shows what `render` writes to a PNG.

use ppm_vk_device::raw_window_handle::{RawDisplayHandle, RawWindowHandle};
use ppm_vk_device::{Buffer, BufferKind, ComputePipeline, Context, Presented, Swapchain};
use ppm_vk_kernels::reflected;
use ppm_vk_kernels::tonemap::{self, TonemapPush};

use crate::error::DeviceContext as _;
use crate::image_io::{write_atomically, write_error};
use crate::{Error, Renderer, Result};

/// A window's swapchain and the kernel that fills it from a [`Renderer`]'s image.
pub struct Presenter {
    // Field order is drop order: the buffer and the pipeline before the swapchain's device goes.
    frame: Buffer,
    kernel: ComputePipeline,
    swapchain: Swapchain,
    ctx: Context,
}

/// A frame as the window showed it: 8-bit RGBA, rows top first.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
}

impl Frame {
    /// Writes the frame as an 8-bit RGBA PNG, atomically as every image ppm-vk writes.
    pub fn save_png(&self, path: impl AsRef<std::path::Path>) -> Result<()> {
        let path = path.as_ref();
        let image =
            image::ImageBuffer::<image::Rgba<u8>, &[u8]>::from_raw(self.width, self.height, self.rgba.as_slice())
                .ok_or_else(|| Error::io(path, std::io::Error::other("frame size and data disagree")))?;
        write_atomically(path, "png", |w| Ok(image.write_to(w, image::ImageFormat::Png)?))
            .map_err(|e| write_error(path, e))
    }
}

impl Presenter {
    /// The swapchain of a window of `size` pixels, on a context opened for its display
    /// ([`ContextOptions::present`](crate::ContextOptions::present)).
    ///
    /// # Safety
    /// `display` and `window` must be the handles of a live window that outlives the presenter.
    pub unsafe fn new(
        ctx: &Context,
        display: RawDisplayHandle,
        window: RawWindowHandle,
        size: (u32, u32),
    ) -> Result<Presenter> {
        let swapchain = Swapchain::new(ctx, display, window, size).device("opening the window's swapchain")?;
        let kernel = ppm_vk_kernels::pipeline(ctx, &reflected::TONEMAP).device("creating the tone-mapping kernel")?;
        let frame = frame_buffer(ctx, swapchain.extent())?;
        Ok(Presenter {
            frame,
            kernel,
            swapchain,
            ctx: ctx.clone(),
        })
    }

    /// The swapchain images' size (the window's, as the surface has it).
    pub fn extent(&self) -> (u32, u32) {
        self.swapchain.extent()
    }

    /// Makes the swapchain again for a window now `size` pixels.
    pub fn resize(&mut self, size: (u32, u32)) -> Result<()> {
        self.swapchain.recreate(size).device("recreating the swapchain")?;
        let needed = bytes(self.swapchain.extent());
        if self.frame.size() < needed {
            self.frame = frame_buffer(&self.ctx, self.swapchain.extent())?;
        }
        Ok(())
    }

    /// Resolves `renderer`'s estimate and shows it at 2^`exposure`. With `read_back`, also returns the
    /// frame read from the swapchain image it was presented from. `Ok(None)` with `read_back` never
    /// happens; without it, `None` is the normal answer. A stale swapchain (the window changed under it) is
    /// made again for `size` and the frame presented once more.
    pub fn present(
        &mut self,
        renderer: &mut Renderer,
        exposure: f32,
        read_back: bool,
        size: (u32, u32),
    ) -> Result<Option<Frame>> {
        renderer.resolve()?;
        for _ in 0..2 {
            let extent = self.swapchain.extent();
            let (w, h) = (renderer.camera().width, renderer.camera().height);
            let push = TonemapPush::fit((w, h), extent, exposure, self.swapchain.bgra());
            let (kernel, frame, image) = (&self.kernel, &self.frame, renderer.image_buffer());
            let (presented, bytes) = self
                .swapchain
                .present(
                    frame,
                    |cmd| tonemap::record(kernel, cmd, image, frame, &push),
                    read_back,
                )
                .device("showing the frame")?;
            match presented {
                Presented::Shown => return Ok(bytes.map(|b| self.frame_of(b, extent))),
                Presented::Stale => self.resize(size)?,
            }
        }
        Err(Error::device("showing the frame")(anyhow::anyhow!(
            "the window's surface stayed out of date after the swapchain was made again"
        )))
    }

    fn frame_of(&self, mut bytes: Vec<u8>, (width, height): (u32, u32)) -> Frame {
        if self.swapchain.bgra() {
            for px in bytes.chunks_exact_mut(4) {
                px.swap(0, 2);
            }
        }
        Frame {
            width,
            height,
            rgba: bytes,
        }
    }
}

fn bytes((w, h): (u32, u32)) -> u64 {
    w as u64 * h as u64 * 4
}

fn frame_buffer(ctx: &Context, extent: (u32, u32)) -> Result<Buffer> {
    Buffer::new(ctx, "window frame", bytes(extent), BufferKind::Storage).device("allocating the window's frame")
}

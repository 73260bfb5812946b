//! A window's surface and swapchain, for a viewer: images are written by transfer commands (a compute
//! kernel fills a buffer, the buffer is copied into the image), never rendered to, so no render pass or
//! graphics pipeline is needed.
//!
//! Synchronisation is the simplest that is correct: acquiring waits on a fence, the copy is submitted and
//! waited for ([`Context::run`]), then the image is presented. The host has waited for everything the image
//! depends on, so present needs no semaphore. A viewer's frame is one small copy; nothing is gained by
//! overlapping it with the next pass.

use anyhow::{anyhow, bail, Context as _, Result};
use ash::vk;
use raw_window_handle::{RawDisplayHandle, RawWindowHandle};

use crate::{Buffer, BufferKind, Context};

/// What [`Swapchain::present`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Presented {
    /// The frame is on screen.
    Shown,
    /// The window changed (resized, or the surface is out of date): call [`Swapchain::recreate`] with its
    /// new size and present again. Nothing was shown.
    Stale,
}

/// A window's surface and its swapchain. Dropping it destroys both; the window must outlive it.
pub struct Swapchain {
    ctx: Context,
    surface_loader: ash::khr::surface::Instance,
    surface: vk::SurfaceKHR,
    loader: ash::khr::swapchain::Device,
    raw: vk::SwapchainKHR,
    images: Vec<vk::Image>,
    format: vk::SurfaceFormatKHR,
    extent: vk::Extent2D,
    present_mode: vk::PresentModeKHR,
    /// Signalled when an acquired image may be written.
    acquired: vk::Fence,
    /// Whether images can be copied from, for [`Swapchain::present`]'s read-back.
    readable: bool,
}

impl Swapchain {
    /// The surface of a window and a swapchain of `size` (the window's inner size in pixels).
    ///
    /// # Safety
    /// `display` and `window` must be valid handles of a live window that outlives the swapchain.
    pub unsafe fn new(
        ctx: &Context,
        display: RawDisplayHandle,
        window: RawWindowHandle,
        size: (u32, u32),
    ) -> Result<Swapchain> {
        if !ctx.presents() {
            bail!("the device was opened without presentation (ContextOptions::present)");
        }
        let surface = ash_window::create_surface(ctx.entry(), ctx.instance(), display, window, None)
            .context("creating the window's Vulkan surface")?;
        let surface_loader = ash::khr::surface::Instance::new(ctx.entry(), ctx.instance());
        let destroy_surface = |e: anyhow::Error| {
            surface_loader.destroy_surface(surface, None);
            e
        };
        let pd = ctx.physical_device();
        let supported = surface_loader
            .get_physical_device_surface_support(pd, ctx.queue_family(), surface)
            .context("asking whether the queue can present")
            .map_err(destroy_surface)?;
        if !supported {
            return Err(destroy_surface(anyhow!(
                "{}'s compute queue cannot present to this window",
                ctx.info().name
            )));
        }
        let formats = surface_loader
            .get_physical_device_surface_formats(pd, surface)
            .context("listing the surface's formats")
            .map_err(destroy_surface)?;
        // 8-bit BGRA or RGBA, UNORM or SRGB: the kernel writes sRGB-encoded bytes, and a copy never converts,
        // so either encoding shows the same bytes.
        let format = [
            vk::Format::B8G8R8A8_UNORM,
            vk::Format::R8G8B8A8_UNORM,
            vk::Format::B8G8R8A8_SRGB,
            vk::Format::R8G8B8A8_SRGB,
        ]
        .iter()
        .find_map(|&f| formats.iter().find(|s| s.format == f).copied())
        .ok_or_else(|| destroy_surface(anyhow!("the surface offers no 8-bit RGBA or BGRA format: {formats:?}")))?;
        let modes = surface_loader
            .get_physical_device_surface_present_modes(pd, surface)
            .context("listing the surface's present modes")
            .map_err(destroy_surface)?;
        // Never wait for a vertical blank behind a pass: mailbox, else immediate, else FIFO (always there).
        let present_mode = [vk::PresentModeKHR::MAILBOX, vk::PresentModeKHR::IMMEDIATE]
            .into_iter()
            .find(|m| modes.contains(m))
            .unwrap_or(vk::PresentModeKHR::FIFO);
        let device = ctx.device();
        let acquired = device
            .create_fence(&vk::FenceCreateInfo::default(), None)
            .context("creating a fence")
            .map_err(destroy_surface)?;
        let mut swapchain = Swapchain {
            ctx: ctx.clone(),
            loader: ash::khr::swapchain::Device::new(ctx.instance(), device),
            surface_loader,
            surface,
            raw: vk::SwapchainKHR::null(),
            images: Vec::new(),
            format,
            extent: vk::Extent2D::default(),
            present_mode,
            acquired,
            readable: false,
        };
        swapchain.recreate(size)?;
        Ok(swapchain)
    }

    /// Makes the swapchain again for a window now `size` pixels (after a resize, or [`Presented::Stale`]).
    pub fn recreate(&mut self, size: (u32, u32)) -> Result<()> {
        let caps = unsafe {
            self.surface_loader
                .get_physical_device_surface_capabilities(self.ctx.physical_device(), self.surface)
        }
        .context("reading the surface's capabilities")?;
        let needed = vk::ImageUsageFlags::TRANSFER_DST;
        if !caps.supported_usage_flags.contains(needed) {
            bail!("the surface's images cannot be written by a copy (no TRANSFER_DST usage)");
        }
        self.readable = caps.supported_usage_flags.contains(vk::ImageUsageFlags::TRANSFER_SRC);
        let usage = match self.readable {
            true => needed | vk::ImageUsageFlags::TRANSFER_SRC,
            false => needed,
        };
        // The surface decides the size where it has one; else the window's, within the surface's bounds.
        let extent = match caps.current_extent.width {
            u32::MAX => vk::Extent2D {
                width: size.0.clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: size.1.clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            },
            _ => caps.current_extent,
        };
        let mut count = caps.min_image_count + 1;
        if caps.max_image_count > 0 {
            count = count.min(caps.max_image_count);
        }
        let composite = [
            vk::CompositeAlphaFlagsKHR::OPAQUE,
            vk::CompositeAlphaFlagsKHR::INHERIT,
            vk::CompositeAlphaFlagsKHR::PRE_MULTIPLIED,
            vk::CompositeAlphaFlagsKHR::POST_MULTIPLIED,
        ]
        .into_iter()
        .find(|&c| caps.supported_composite_alpha.contains(c))
        .unwrap_or(vk::CompositeAlphaFlagsKHR::OPAQUE);
        let old = self.raw;
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(self.surface)
            .min_image_count(count)
            .image_format(self.format.format)
            .image_color_space(self.format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(usage)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(composite)
            .present_mode(self.present_mode)
            .clipped(true)
            .old_swapchain(old);
        // The old swapchain's images may still be presented from: wait before it goes.
        unsafe { self.ctx.device().device_wait_idle() }.context("waiting for the device before a new swapchain")?;
        self.images.clear();
        let raw = unsafe { self.loader.create_swapchain(&info, None) }.context("creating the swapchain");
        if old != vk::SwapchainKHR::null() {
            unsafe { self.loader.destroy_swapchain(old, None) };
            self.raw = vk::SwapchainKHR::null();
        }
        self.raw = raw?;
        self.images =
            unsafe { self.loader.get_swapchain_images(self.raw) }.context("listing the swapchain's images")?;
        for (i, &image) in self.images.iter().enumerate() {
            self.ctx.name_object(image, &format!("swapchain image {i}"));
        }
        self.extent = extent;
        Ok(())
    }

    /// The images' size in pixels.
    pub fn extent(&self) -> (u32, u32) {
        (self.extent.width, self.extent.height)
    }

    /// Whether the images' bytes are in B, G, R, A order (else R, G, B, A).
    pub fn bgra(&self) -> bool {
        matches!(
            self.format.format,
            vk::Format::B8G8R8A8_UNORM | vk::Format::B8G8R8A8_SRGB
        )
    }

    /// Acquires an image, copies `pixels` (a buffer of extent.0 x extent.1 packed 8-bit texels in the
    /// images' byte order, rows top first) into it after `record` has filled the buffer, and presents it.
    /// With `read_back`, the presented bytes are also copied into a host buffer and returned: what the
    /// window shows, read from the swapchain image itself.
    pub fn present(
        &mut self,
        pixels: &Buffer,
        record: impl FnOnce(vk::CommandBuffer) -> Result<()>,
        read_back: bool,
    ) -> Result<(Presented, Option<Vec<u8>>)> {
        let (w, h) = self.extent();
        let bytes = w as u64 * h as u64 * 4;
        if pixels.size() < bytes {
            bail!(
                "the frame buffer holds {} bytes, the swapchain's {w}x{h} images need {bytes}",
                pixels.size()
            );
        }
        if read_back && !self.readable {
            bail!("this surface's images cannot be read back (no TRANSFER_SRC usage): no screenshot");
        }
        let device = self.ctx.device().clone();
        let acquire = unsafe {
            self.loader
                .acquire_next_image(self.raw, u64::MAX, vk::Semaphore::null(), self.acquired)
        };
        let index = match acquire {
            Ok((index, _suboptimal)) => index,
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => return Ok((Presented::Stale, None)),
            Err(e) => return Err(anyhow!(e).context("acquiring a swapchain image")),
        };
        unsafe {
            device
                .wait_for_fences(&[self.acquired], true, u64::MAX)
                .context("waiting for a swapchain image")?;
            device
                .reset_fences(&[self.acquired])
                .context("resetting the acquire fence")?;
        }
        let image = self.images[index as usize];
        let readback = match read_back {
            true => Some(Buffer::new(&self.ctx, "screenshot", bytes, BufferKind::Readback)?),
            false => None,
        };
        let region = vk::BufferImageCopy::default()
            .image_subresource(color_layers())
            .image_extent(vk::Extent3D {
                width: w,
                height: h,
                depth: 1,
            });
        self.ctx
            .run(|cmd| {
                record(cmd)?;
                unsafe {
                    transition(
                        &device,
                        cmd,
                        image,
                        (vk::ImageLayout::UNDEFINED, vk::ImageLayout::TRANSFER_DST_OPTIMAL),
                        (vk::AccessFlags::SHADER_WRITE, vk::AccessFlags::TRANSFER_WRITE),
                        vk::PipelineStageFlags::COMPUTE_SHADER,
                    );
                    device.cmd_copy_buffer_to_image(
                        cmd,
                        pixels.raw(),
                        image,
                        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                        &[region],
                    );
                    let mut layout = vk::ImageLayout::TRANSFER_DST_OPTIMAL;
                    if let Some(rb) = &readback {
                        transition(
                            &device,
                            cmd,
                            image,
                            (layout, vk::ImageLayout::TRANSFER_SRC_OPTIMAL),
                            (vk::AccessFlags::TRANSFER_WRITE, vk::AccessFlags::TRANSFER_READ),
                            vk::PipelineStageFlags::TRANSFER,
                        );
                        layout = vk::ImageLayout::TRANSFER_SRC_OPTIMAL;
                        device.cmd_copy_image_to_buffer(cmd, image, layout, rb.raw(), &[region]);
                        let to_host = [vk::MemoryBarrier::default()
                            .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
                            .dst_access_mask(vk::AccessFlags::HOST_READ)];
                        device.cmd_pipeline_barrier(
                            cmd,
                            vk::PipelineStageFlags::TRANSFER,
                            vk::PipelineStageFlags::HOST,
                            vk::DependencyFlags::empty(),
                            &to_host,
                            &[],
                            &[],
                        );
                    }
                    transition(
                        &device,
                        cmd,
                        image,
                        (layout, vk::ImageLayout::PRESENT_SRC_KHR),
                        (vk::AccessFlags::TRANSFER_WRITE, vk::AccessFlags::empty()),
                        vk::PipelineStageFlags::TRANSFER,
                    );
                }
                Ok(())
            })
            .context("copying the frame into the swapchain image")?;
        let shot = match &readback {
            Some(rb) => Some(rb.mapped()?[..bytes as usize].to_vec()),
            None => None,
        };
        let swapchains = [self.raw];
        let indices = [index];
        let info = vk::PresentInfoKHR::default()
            .swapchains(&swapchains)
            .image_indices(&indices);
        match self
            .ctx
            .with_queue(|q| unsafe { self.loader.queue_present(q, &info) })?
        {
            Ok(_suboptimal) => Ok((Presented::Shown, shot)),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok((Presented::Stale, shot)),
            Err(e) => Err(anyhow!(e).context("presenting the frame")),
        }
    }
}

fn color_layers() -> vk::ImageSubresourceLayers {
    vk::ImageSubresourceLayers::default()
        .aspect_mask(vk::ImageAspectFlags::COLOR)
        .layer_count(1)
}

/// A layout transition of a whole colour image, after `src_stage`'s `access.0` and before transfers'
/// `access.1`.
unsafe fn transition(
    device: &ash::Device,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    layouts: (vk::ImageLayout, vk::ImageLayout),
    access: (vk::AccessFlags, vk::AccessFlags),
    src_stage: vk::PipelineStageFlags,
) {
    let range = vk::ImageSubresourceRange::default()
        .aspect_mask(vk::ImageAspectFlags::COLOR)
        .level_count(1)
        .layer_count(1);
    let barrier = [vk::ImageMemoryBarrier::default()
        .old_layout(layouts.0)
        .new_layout(layouts.1)
        .src_access_mask(access.0)
        .dst_access_mask(access.1)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(range)];
    let dst_stage = match layouts.1 {
        vk::ImageLayout::PRESENT_SRC_KHR => vk::PipelineStageFlags::BOTTOM_OF_PIPE,
        _ => vk::PipelineStageFlags::TRANSFER,
    };
    device.cmd_pipeline_barrier(
        cmd,
        src_stage,
        dst_stage,
        vk::DependencyFlags::empty(),
        &[],
        &[],
        &barrier,
    );
}

impl Drop for Swapchain {
    fn drop(&mut self) {
        unsafe {
            let device = self.ctx.device();
            let _ = device.device_wait_idle();
            if self.raw != vk::SwapchainKHR::null() {
                self.loader.destroy_swapchain(self.raw, None);
            }
            device.destroy_fence(self.acquired, None);
            self.surface_loader.destroy_surface(self.surface, None);
        }
    }
}

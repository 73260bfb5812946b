//! Storage buffers with their memory, freed on drop.

use std::sync::Arc;

use anyhow::{anyhow, bail, Context as _, Result};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

use crate::context::{Context, Shared};

/// Where a buffer lives and who touches it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BufferKind {
    /// Kernel working memory; filled by kernels, `fill` or [`Context::upload`].
    Storage,
    /// Host-visible, for reading results back (the target of a copy).
    Readback,
    /// Host-visible, written by the host (the source of a copy).
    Upload,
}

/// A Vulkan buffer and its memory. Dropping it frees both.
pub struct Buffer {
    shared: Arc<Shared>,
    raw: vk::Buffer,
    allocation: Option<Allocation>,
    size: u64,
    name: String,
    /// A `Storage` buffer's view as 16-byte texels (R32G32B32A32_UINT), for kernels that read it as a
    /// uniform texel buffer; `None` where it has more texels than the device allows in one view.
    texels: Option<vk::BufferView>,
}

/// Bytes of one texel of a buffer's texel view (R32G32B32A32_UINT).
pub const TEXEL_BYTES: u64 = 16;

impl Buffer {
    /// A buffer of `size` bytes (at least 4: Vulkan forbids empty buffers, and an empty scene list is legal).
    /// A storage buffer may be larger than the device's largest storage binding
    /// (`maxStorageBufferRange`): a kernel then binds it in [`BufferSlice`]s of at most that range, which
    /// [`ComputePipeline`](crate::ComputePipeline) checks at every dispatch.
    pub fn new(ctx: &Context, name: &str, size: u64, kind: BufferKind) -> Result<Buffer> {
        let size = size.max(4).next_multiple_of(4);
        let (usage, location) = match kind {
            BufferKind::Storage => (
                vk::BufferUsageFlags::STORAGE_BUFFER
                    | vk::BufferUsageFlags::TRANSFER_DST
                    | vk::BufferUsageFlags::TRANSFER_SRC
                    | vk::BufferUsageFlags::INDIRECT_BUFFER
                    | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER,
                MemoryLocation::GpuOnly,
            ),
            BufferKind::Readback => (vk::BufferUsageFlags::TRANSFER_DST, MemoryLocation::GpuToCpu),
            BufferKind::Upload => (vk::BufferUsageFlags::TRANSFER_SRC, MemoryLocation::CpuToGpu),
        };
        let shared = ctx.shared().clone();
        let device = &shared.device;
        let info = vk::BufferCreateInfo::default()
            .size(size)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        let raw = unsafe { device.create_buffer(&info, None) }.with_context(|| format!("creating buffer {name:?}"))?;
        ctx.name_object(raw, name);
        let requirements = unsafe { device.get_buffer_memory_requirements(raw) };
        let allocation = {
            let mut guard = shared
                .allocator
                .lock()
                .map_err(|_| anyhow!("allocator lock poisoned"))?;
            let allocator = guard.as_mut().ok_or_else(|| anyhow!("allocator already destroyed"))?;
            let a = allocator.allocate(&AllocationCreateDesc {
                name,
                requirements,
                location,
                linear: true,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            });
            let reserved = allocator.generate_report().total_capacity_bytes;
            shared
                .peak_reserved
                .fetch_max(reserved, std::sync::atomic::Ordering::Relaxed);
            a
        };
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                unsafe { device.destroy_buffer(raw, None) };
                return Err(anyhow!(e)).with_context(|| {
                    format!(
                        "allocating {} MiB for buffer {name:?} (device memory exhausted?)",
                        size >> 20
                    )
                });
            }
        };
        if let Err(e) = unsafe { device.bind_buffer_memory(raw, allocation.memory(), allocation.offset()) } {
            unsafe { device.destroy_buffer(raw, None) };
            if let Ok(mut a) = shared.allocator.lock() {
                if let Some(a) = a.as_mut() {
                    let _ = a.free(allocation);
                }
            }
            return Err(e).with_context(|| format!("binding memory of buffer {name:?}"));
        }
        let mut buffer = Buffer {
            shared,
            raw,
            allocation: Some(allocation),
            size,
            name: name.to_string(),
            texels: None,
        };
        let texels = size / TEXEL_BYTES;
        if kind == BufferKind::Storage && texels > 0 && texels <= ctx.limits().max_texel_buffer_elements as u64 {
            let info = vk::BufferViewCreateInfo::default()
                .buffer(raw)
                .format(vk::Format::R32G32B32A32_UINT)
                .offset(0)
                .range(texels * TEXEL_BYTES);
            let view = unsafe { buffer.shared.device.create_buffer_view(&info, None) }
                .with_context(|| format!("creating the texel view of buffer {name:?}"))?;
            ctx.name_object(view, &format!("{name} texels"));
            buffer.texels = Some(view);
        }
        Ok(buffer)
    }

    /// The whole buffer as one binding.
    pub fn whole(&self) -> BufferSlice<'_> {
        BufferSlice {
            buffer: self,
            offset: 0,
            range: self.size,
        }
    }

    /// `range` bytes from byte `offset` as one binding (checked against the buffer and the device when
    /// a kernel binds it).
    pub fn slice(&self, offset: u64, range: u64) -> BufferSlice<'_> {
        BufferSlice {
            buffer: self,
            offset,
            range,
        }
    }

    /// The buffer as 16-byte texels, for a kernel's uniform texel buffer binding.
    pub fn texel_view(&self) -> Result<vk::BufferView> {
        self.texels.ok_or_else(|| {
            anyhow!(
                "buffer {:?} ({} MiB) has no texel view: more texels than the device allows in one, or not a storage buffer",
                self.name,
                self.size >> 20
            )
        })
    }

    pub fn raw(&self) -> vk::Buffer {
        self.raw
    }

    pub fn size(&self) -> u64 {
        self.size
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    /// The host mapping of a `Readback` or `Upload` buffer.
    pub fn mapped(&self) -> Result<&[u8]> {
        self.allocation
            .as_ref()
            .and_then(|a| a.mapped_slice())
            .ok_or_else(|| anyhow!("buffer {:?} is not host-visible", self.name))
    }

    pub fn mapped_mut(&mut self) -> Result<&mut [u8]> {
        let name = self.name.clone();
        self.allocation
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .ok_or_else(|| anyhow!("buffer {name:?} is not host-visible"))
    }

    /// Records a fill of the whole buffer with a repeated 32-bit word.
    pub fn cmd_fill(&self, cmd: vk::CommandBuffer, word: u32) {
        unsafe {
            self.shared
                .device
                .cmd_fill_buffer(cmd, self.raw, 0, vk::WHOLE_SIZE, word)
        };
    }

    /// Records a copy of `size` bytes from the start of `self` into `dst`.
    pub fn cmd_copy_to(&self, cmd: vk::CommandBuffer, dst: &Buffer, size: u64) {
        self.cmd_copy(cmd, dst, 0, 0, size);
    }

    /// Records a copy of `size` bytes from `self` at `src_offset` into `dst` at `dst_offset` (clamped to
    /// both buffers).
    pub fn cmd_copy(&self, cmd: vk::CommandBuffer, dst: &Buffer, src_offset: u64, dst_offset: u64, size: u64) {
        let size = size
            .min(self.size.saturating_sub(src_offset))
            .min(dst.size.saturating_sub(dst_offset));
        if size == 0 {
            return;
        }
        let region = [vk::BufferCopy {
            src_offset,
            dst_offset,
            size,
        }];
        unsafe { self.shared.device.cmd_copy_buffer(cmd, self.raw, dst.raw, &region) };
    }
}

/// Part of a [`Buffer`] bound as one storage descriptor: a kernel sees its first byte as element 0.
#[derive(Clone, Copy)]
pub struct BufferSlice<'a> {
    pub buffer: &'a Buffer,
    pub offset: u64,
    pub range: u64,
}

impl<'a> From<&'a Buffer> for BufferSlice<'a> {
    fn from(buffer: &'a Buffer) -> BufferSlice<'a> {
        buffer.whole()
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        if let Some(view) = self.texels.take() {
            unsafe { self.shared.device.destroy_buffer_view(view, None) };
        }
        unsafe { self.shared.device.destroy_buffer(self.raw, None) };
        if let Some(a) = self.allocation.take() {
            if let Ok(mut alloc) = self.shared.allocator.lock() {
                if let Some(alloc) = alloc.as_mut() {
                    let _ = alloc.free(a);
                }
            }
        }
    }
}

impl Context {
    /// A storage buffer holding `data`, uploaded through a staging buffer.
    pub fn buffer_from<T: bytemuck::Pod>(&self, name: &str, data: &[T]) -> Result<Buffer> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let buffer = Buffer::new(self, name, bytes.len() as u64, BufferKind::Storage)?;
        self.upload(&buffer, bytes)?;
        Ok(buffer)
    }

    /// Copies `bytes` into the start of a storage buffer and waits.
    pub fn upload(&self, dst: &Buffer, bytes: &[u8]) -> Result<()> {
        if bytes.is_empty() {
            return Ok(());
        }
        if bytes.len() as u64 > dst.size() {
            bail!(
                "upload of {} bytes into buffer {:?} of {} bytes",
                bytes.len(),
                dst.name(),
                dst.size()
            );
        }
        let mut staging = Buffer::new(self, "staging upload", bytes.len() as u64, BufferKind::Upload)?;
        staging.mapped_mut()?[..bytes.len()].copy_from_slice(bytes);
        self.run(|cmd| {
            staging.cmd_copy_to(cmd, dst, bytes.len() as u64);
            Ok(())
        })
    }

    /// Reads a whole storage buffer back as `T`s (waits for the GPU).
    pub fn download<T: bytemuck::Pod>(&self, src: &Buffer) -> Result<Vec<T>> {
        let n = src.size() as usize / std::mem::size_of::<T>();
        self.download_prefix(src, n)
    }

    /// Reads the first `count` `T`s of a storage buffer back.
    pub fn download_prefix<T: bytemuck::Pod>(&self, src: &Buffer, count: usize) -> Result<Vec<T>> {
        let bytes = (count * std::mem::size_of::<T>()) as u64;
        if bytes > src.size() {
            bail!(
                "reading {bytes} bytes from buffer {:?} of {} bytes",
                src.name(),
                src.size()
            );
        }
        if count == 0 {
            return Ok(Vec::new());
        }
        let staging = Buffer::new(self, "staging readback", bytes, BufferKind::Readback)?;
        self.run(|cmd| {
            crate::context::barrier(self, cmd);
            src.cmd_copy_to(cmd, &staging, bytes);
            Ok(())
        })?;
        let mapped = &staging.mapped()?[..bytes as usize];
        // The mapping has no alignment promise for T: copy out element by element.
        Ok(mapped
            .chunks_exact(std::mem::size_of::<T>())
            .map(bytemuck::pod_read_unaligned)
            .collect())
    }
}

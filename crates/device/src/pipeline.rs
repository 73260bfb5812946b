//! Compute pipelines whose storage buffers are pushed per dispatch (VK_KHR_push_descriptor), so no
//! descriptor pools or sets live anywhere.

use std::sync::Arc;

use anyhow::{bail, Context as _, Result};
use ash::vk;

use crate::buffer::{Buffer, BufferSlice};
use crate::context::{Context, Shared};

/// What a pipeline is made from; the kernel crate fills this from SPIR-V reflection.
pub struct PipelineDesc<'a> {
    pub name: &'a str,
    pub spirv: &'a [u32],
    /// Buffer bindings 0..n of set 0, in order: storage buffers, but for those in `texel_bindings`.
    pub bindings: u32,
    /// Bit b: binding b is a uniform texel buffer (the buffer's 16-byte texel view, `Buffer::texel_view`).
    pub texel_bindings: u32,
    /// Size of the push-constant block in bytes (0 for none).
    pub push_size: u32,
    /// The kernel's local workgroup size (x only: every kernel here is one-dimensional).
    pub local_size: u32,
}

/// A compute pipeline with its layouts. Dropping it destroys them.
pub struct ComputePipeline {
    shared: Arc<Shared>,
    name: String,
    pipeline: vk::Pipeline,
    layout: vk::PipelineLayout,
    set_layout: vk::DescriptorSetLayout,
    bindings: u32,
    texel_bindings: u32,
    push_size: u32,
    local_size: u32,
    /// The device's largest storage binding and the alignment of a binding's offset, checked per dispatch.
    max_range: u64,
    offset_alignment: u64,
}

impl ComputePipeline {
    pub fn new(ctx: &Context, desc: &PipelineDesc) -> Result<ComputePipeline> {
        let shared = ctx.shared().clone();
        let device = &shared.device;
        let name = desc.name;
        let binding_infos: Vec<_> = (0..desc.bindings)
            .map(|b| {
                let texel = desc.texel_bindings >> b & 1 != 0;
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b)
                    .descriptor_type(if texel {
                        vk::DescriptorType::UNIFORM_TEXEL_BUFFER
                    } else {
                        vk::DescriptorType::STORAGE_BUFFER
                    })
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        let set_info = vk::DescriptorSetLayoutCreateInfo::default()
            .flags(vk::DescriptorSetLayoutCreateFlags::PUSH_DESCRIPTOR_KHR)
            .bindings(&binding_infos);
        let set_layout = unsafe { device.create_descriptor_set_layout(&set_info, None) }
            .with_context(|| format!("creating the descriptor set layout of kernel {name}"))?;
        ctx.name_object(set_layout, &format!("{name} bindings"));
        // Build the rest inside a closure so a failure still destroys what was made.
        let mut out = ComputePipeline {
            shared: shared.clone(),
            name: name.to_string(),
            pipeline: vk::Pipeline::null(),
            layout: vk::PipelineLayout::null(),
            set_layout,
            bindings: desc.bindings,
            texel_bindings: desc.texel_bindings,
            push_size: desc.push_size,
            local_size: desc.local_size,
            max_range: ctx.limits().max_storage_buffer_range as u64,
            offset_alignment: ctx.limits().min_storage_buffer_offset_alignment.max(1),
        };
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::COMPUTE)
            .offset(0)
            .size(desc.push_size)];
        let set_layouts = [set_layout];
        let mut layout_info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
        if desc.push_size > 0 {
            layout_info = layout_info.push_constant_ranges(&ranges);
        }
        out.layout = unsafe { device.create_pipeline_layout(&layout_info, None) }
            .with_context(|| format!("creating the pipeline layout of kernel {name}"))?;
        ctx.name_object(out.layout, &format!("{name} layout"));
        let module_info = vk::ShaderModuleCreateInfo::default().code(desc.spirv);
        let module = unsafe { device.create_shader_module(&module_info, None) }
            .with_context(|| format!("creating the shader module of kernel {name}"))?;
        ctx.name_object(module, name);
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module)
            .name(c"main");
        let info = [vk::ComputePipelineCreateInfo::default().stage(stage).layout(out.layout)];
        // Through the context's pipeline cache: a kernel compiled by an earlier run is not compiled again.
        let created = unsafe { device.create_compute_pipelines(ctx.pipeline_cache(), &info, None) };
        unsafe { device.destroy_shader_module(module, None) };
        out.pipeline = created
            .map_err(|(_, e)| e)
            .with_context(|| format!("compiling kernel {name}"))?[0];
        ctx.name_object(out.pipeline, name);
        Ok(out)
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    pub fn local_size(&self) -> u32 {
        self.local_size
    }

    /// Records one dispatch covering `invocations` threads (rounded up to whole workgroups; the kernel
    /// bounds-checks), with `buffers` at bindings 0.. and `push` as its push constants.
    pub fn dispatch(&self, cmd: vk::CommandBuffer, buffers: &[&Buffer], push: &[u8], invocations: u64) -> Result<()> {
        let slices: Vec<BufferSlice> = buffers.iter().map(|b| b.whole()).collect();
        self.dispatch_slices(cmd, &slices, push, invocations)
    }

    /// [`ComputePipeline::dispatch`] with parts of buffers at the bindings: each kernel's element 0 is
    /// its slice's first byte.
    pub fn dispatch_slices(
        &self,
        cmd: vk::CommandBuffer,
        buffers: &[BufferSlice],
        push: &[u8],
        invocations: u64,
    ) -> Result<()> {
        let groups = invocations.div_ceil(self.local_size as u64);
        // Spread over y when x would exceed the 65535 limit many devices (lavapipe included) have; kernels
        // linearise gl_WorkGroupID with gl_NumWorkGroups.
        let (gx, gy) = if groups <= 65535 {
            (groups, 1)
        } else {
            (65535, groups.div_ceil(65535))
        };
        if gy > 65535 {
            bail!(
                "kernel {}: {invocations} invocations are more than one dispatch can hold",
                self.name
            );
        }
        if groups == 0 {
            return Ok(());
        }
        self.bind(cmd, buffers, push)?;
        unsafe { self.shared.device.cmd_dispatch(cmd, gx as u32, gy as u32, 1) };
        Ok(())
    }

    /// Records a dispatch of exactly `groups` workgroups.
    pub fn dispatch_groups(
        &self,
        cmd: vk::CommandBuffer,
        buffers: &[&Buffer],
        push: &[u8],
        groups: [u32; 3],
    ) -> Result<()> {
        if groups.contains(&0) {
            return Ok(());
        }
        self.bind(cmd, &whole(buffers), push)?;
        unsafe { self.shared.device.cmd_dispatch(cmd, groups[0], groups[1], groups[2]) };
        Ok(())
    }

    /// Records a dispatch whose workgroup counts a kernel wrote: the `VkDispatchIndirectCommand` (three
    /// u32) at byte `offset` of `args`, read when the dispatch runs (after a [`barrier`]).
    pub fn dispatch_indirect(
        &self,
        cmd: vk::CommandBuffer,
        buffers: &[&Buffer],
        push: &[u8],
        args: &Buffer,
        offset: u64,
    ) -> Result<()> {
        self.bind(cmd, &whole(buffers), push)?;
        unsafe { self.shared.device.cmd_dispatch_indirect(cmd, args.raw(), offset) };
        Ok(())
    }

    /// Binds the pipeline, `buffers` at bindings 0.. and `push` as its push constants.
    fn bind(&self, cmd: vk::CommandBuffer, buffers: &[BufferSlice], push: &[u8]) -> Result<()> {
        if buffers.len() != self.bindings as usize {
            bail!(
                "kernel {} takes {} buffers, got {}",
                self.name,
                self.bindings,
                buffers.len()
            );
        }
        if push.len() != self.push_size as usize {
            bail!(
                "kernel {} takes {} bytes of push constants, got {}",
                self.name,
                self.push_size,
                push.len()
            );
        }
        for (i, b) in buffers.iter().enumerate() {
            self.check_slice(i, b)?;
        }
        let device = &self.shared.device;
        let infos: Vec<[vk::DescriptorBufferInfo; 1]> = buffers
            .iter()
            .map(|b| {
                [vk::DescriptorBufferInfo {
                    buffer: b.buffer.raw(),
                    offset: b.offset,
                    range: b.range,
                }]
            })
            .collect();
        let views: Vec<[vk::BufferView; 1]> = buffers
            .iter()
            .enumerate()
            .map(|(i, b)| match self.texel_bindings >> i & 1 {
                0 => Ok([vk::BufferView::null()]),
                _ => b
                    .buffer
                    .texel_view()
                    .map(|v| [v])
                    .with_context(|| format!("kernel {}, binding {i}", self.name)),
            })
            .collect::<Result<_>>()?;
        let writes: Vec<vk::WriteDescriptorSet> = infos
            .iter()
            .zip(&views)
            .enumerate()
            .map(|(i, (info, view))| {
                let w = vk::WriteDescriptorSet::default().dst_binding(i as u32);
                match self.texel_bindings >> i & 1 {
                    0 => w.descriptor_type(vk::DescriptorType::STORAGE_BUFFER).buffer_info(info),
                    _ => w
                        .descriptor_type(vk::DescriptorType::UNIFORM_TEXEL_BUFFER)
                        .texel_buffer_view(view),
                }
            })
            .collect();
        unsafe {
            device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.pipeline);
            self.shared.push_descriptor.cmd_push_descriptor_set(
                cmd,
                vk::PipelineBindPoint::COMPUTE,
                self.layout,
                0,
                &writes,
            );
            if !push.is_empty() {
                device.cmd_push_constants(cmd, self.layout, vk::ShaderStageFlags::COMPUTE, 0, push);
            }
        }
        Ok(())
    }
}

impl ComputePipeline {
    /// Fails, naming the kernel, binding and buffer, unless `b` lies inside its buffer, starts at an
    /// offset the device can bind and spans at most its largest storage binding (a texel binding: the
    /// whole buffer, its texel view).
    fn check_slice(&self, binding: usize, b: &BufferSlice) -> Result<()> {
        let (name, size) = (b.buffer.name(), b.buffer.size());
        let what = || format!("kernel {}, binding {binding} (buffer {name:?})", self.name);
        if b.offset.checked_add(b.range).is_none_or(|end| end > size) || b.range == 0 {
            bail!(
                "{}: slice of {} bytes at {} outside the buffer's {size} bytes",
                what(),
                b.range,
                b.offset
            );
        }
        if self.texel_bindings >> binding & 1 != 0 {
            if (b.offset, b.range) != (0, size) {
                bail!("{}: a texel binding takes the whole buffer", what());
            }
            return Ok(());
        }
        // `checked_rem`: `is_multiple_of` is newer than the workspace's rust-version.
        if b.offset.checked_rem(self.offset_alignment) != Some(0) {
            bail!(
                "{}: offset {} is not a multiple of the device's storage offset alignment {}",
                what(),
                b.offset,
                self.offset_alignment
            );
        }
        if b.range > self.max_range {
            bail!(
                "{}: {} MiB in one binding, more than this device's largest storage binding ({} MiB)",
                what(),
                b.range >> 20,
                self.max_range >> 20
            );
        }
        Ok(())
    }
}

/// Every buffer as one whole binding.
fn whole<'a>(buffers: &[&'a Buffer]) -> Vec<BufferSlice<'a>> {
    buffers.iter().map(|b| b.whole()).collect()
}

impl Drop for ComputePipeline {
    fn drop(&mut self) {
        unsafe {
            let d = &self.shared.device;
            d.destroy_pipeline(self.pipeline, None);
            d.destroy_pipeline_layout(self.layout, None);
            d.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}

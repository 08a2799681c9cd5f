//! Safe recording into a command buffer: synchronization2 barriers, push
//! descriptors checked against reflection, dispatch, (indirect) draws,
//! dynamic rendering, debug labels and timestamps.

use super::context::Context;
use super::pipeline::Pipeline;
use super::query::TimestampPool;
use super::resources::{aspect_of, Buffer, Image};
use super::shader::{Binding, BindingKind};
use ash::vk;
use std::ffi::CString;

/// A resource bound to a reflected binding.
pub enum Resource<'a> {
    Buffer(&'a Buffer),
    /// (buffer, offset, size)
    BufferRange(&'a Buffer, u64, u64),
    /// An image in the given layout (GENERAL for storage images).
    Image(&'a Image, vk::ImageLayout),
    /// One mip of an image, in the given layout.
    ImageMip(&'a Image, u32, vk::ImageLayout),
    Sampler(vk::Sampler),
}

pub struct Recorder<'a> {
    ctx: &'a Context,
    cmd: vk::CommandBuffer,
}

/// A color attachment for `begin_rendering`, cleared to `clear`.
pub struct ColorTarget<'a> {
    pub image: &'a Image,
    pub clear: [f32; 4],
}

impl<'a> Recorder<'a> {
    /// Records into a command buffer the caller owns (e.g. an engine's).
    ///
    /// # Safety
    /// `cmd` must be a command buffer of `ctx`'s device in the recording
    /// state, allocated from a pool of a queue family that supports the
    /// commands recorded, and not recorded into elsewhere meanwhile.
    pub unsafe fn from_raw(ctx: &'a Context, cmd: vk::CommandBuffer) -> Self {
        Recorder { ctx, cmd }
    }

    pub fn context(&self) -> &'a Context {
        self.ctx
    }

    pub fn raw(&self) -> vk::CommandBuffer {
        self.cmd
    }

    fn d(&self) -> &ash::Device {
        &self.ctx.shared.device
    }

    /// Makes all earlier writes visible to all later reads (on lavapipe every
    /// barrier drains all work anyway; on real GPUs passes pick narrower ones).
    pub fn barrier(&mut self, src: vk::PipelineStageFlags2, dst: vk::PipelineStageFlags2) {
        let mb = [vk::MemoryBarrier2::default()
            .src_stage_mask(src)
            .src_access_mask(vk::AccessFlags2::MEMORY_WRITE)
            .dst_stage_mask(dst)
            .dst_access_mask(vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE)];
        let dep = vk::DependencyInfo::default().memory_barriers(&mb);
        // SAFETY: recording state guaranteed by construction.
        unsafe { self.d().cmd_pipeline_barrier2(self.cmd, &dep) };
    }

    /// Full barrier plus a layout transition of every subresource of `image`.
    pub fn image_layout(&mut self, image: &Image, old: vk::ImageLayout, new: vk::ImageLayout) {
        let range = vk::ImageSubresourceRange::default()
            .aspect_mask(aspect_of(image.format))
            .level_count(vk::REMAINING_MIP_LEVELS)
            .layer_count(vk::REMAINING_ARRAY_LAYERS);
        let ib = [vk::ImageMemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
            .src_access_mask(vk::AccessFlags2::MEMORY_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
            .dst_access_mask(vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE)
            .old_layout(old)
            .new_layout(new)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(image.raw)
            .subresource_range(range)];
        let dep = vk::DependencyInfo::default().image_memory_barriers(&ib);
        // SAFETY: image is live for the borrow; recording state by construction.
        unsafe { self.d().cmd_pipeline_barrier2(self.cmd, &dep) };
    }

    pub fn bind_pipeline(&mut self, p: &Pipeline) {
        // SAFETY: live pipeline.
        unsafe { self.d().cmd_bind_pipeline(self.cmd, p.bind_point, p.raw) };
    }

    /// Binds resources to `p`'s reflected bindings; the kind of each resource
    /// must match the shader's declaration (a programmer error otherwise).
    pub fn push_descriptors(&mut self, p: &Pipeline, bindings: &[(Binding, Resource)]) {
        let mut buffer_infos = Vec::with_capacity(bindings.len());
        let mut image_infos = Vec::with_capacity(bindings.len());
        for (b, r) in bindings {
            assert!(p.bindings.contains(b), "{}: binding {} is not part of pipeline {}", b.name, b.binding, p.name);
            match r {
                Resource::Buffer(buf) => {
                    buffer_infos.push(vk::DescriptorBufferInfo { buffer: buf.raw, offset: 0, range: vk::WHOLE_SIZE })
                }
                Resource::BufferRange(buf, offset, size) => {
                    buffer_infos.push(vk::DescriptorBufferInfo { buffer: buf.raw, offset: *offset, range: *size })
                }
                Resource::Image(img, layout) => image_infos.push(vk::DescriptorImageInfo {
                    sampler: vk::Sampler::null(),
                    image_view: img.view(),
                    image_layout: *layout,
                }),
                Resource::ImageMip(img, mip, layout) => image_infos.push(vk::DescriptorImageInfo {
                    sampler: vk::Sampler::null(),
                    image_view: img.mip_view(*mip),
                    image_layout: *layout,
                }),
                Resource::Sampler(s) => image_infos.push(vk::DescriptorImageInfo {
                    sampler: *s,
                    image_view: vk::ImageView::null(),
                    image_layout: vk::ImageLayout::UNDEFINED,
                }),
            }
        }
        let (mut bi, mut ii) = (0, 0);
        let writes: Vec<vk::WriteDescriptorSet> = bindings
            .iter()
            .map(|(b, r)| {
                let w = vk::WriteDescriptorSet::default().dst_binding(b.binding).descriptor_type(b.kind.vk());
                match (r, b.kind) {
                    (
                        Resource::Buffer(_) | Resource::BufferRange(..),
                        BindingKind::StorageBuffer | BindingKind::UniformBuffer,
                    ) => {
                        bi += 1;
                        w.buffer_info(&buffer_infos[bi - 1..bi])
                    }
                    (
                        Resource::Image(..) | Resource::ImageMip(..),
                        BindingKind::SampledImage | BindingKind::StorageImage,
                    )
                    | (Resource::Sampler(_), BindingKind::Sampler) => {
                        ii += 1;
                        w.image_info(&image_infos[ii - 1..ii])
                    }
                    _ => panic!("{}: resource does not match binding kind {:?}", b.name, b.kind),
                }
            })
            .collect();
        // SAFETY: the set layout has the push-descriptor flag; the resources
        // are live for the borrow and deferred-destroyed after the frame.
        unsafe {
            self.ctx.shared.push_descriptor.cmd_push_descriptor_set(self.cmd, p.bind_point, p.layout, 0, &writes)
        };
    }

    /// `data` must be exactly the reflected push-constant block.
    pub fn push_constants<T: bytemuck::Pod>(&mut self, p: &Pipeline, data: &T) {
        let bytes = bytemuck::bytes_of(data);
        assert_eq!(
            bytes.len() as u32,
            p.push_size,
            "{}: push constants are {} bytes, shader expects {}",
            p.name,
            bytes.len(),
            p.push_size
        );
        // SAFETY: size checked against the layout's range.
        unsafe { self.d().cmd_push_constants(self.cmd, p.layout, p.push_stages, 0, bytes) };
    }

    pub fn dispatch(&mut self, x: u32, y: u32, z: u32) {
        // SAFETY: recording state by construction.
        unsafe { self.d().cmd_dispatch(self.cmd, x, y, z) };
    }

    pub fn dispatch_indirect(&mut self, args: &Buffer, offset: u64) {
        // SAFETY: live buffer; bounds are the validation layer's to check.
        unsafe { self.d().cmd_dispatch_indirect(self.cmd, args.raw, offset) };
    }

    /// Begins dynamic rendering into `colors` (+ optional depth cleared to
    /// 0, reversed-Z), with a full-target viewport and scissor.
    pub fn begin_rendering(&mut self, colors: &[ColorTarget], depth: Option<&Image>) {
        let extent =
            colors.first().map(|c| c.image.extent).or(depth.map(|d| d.extent)).expect("begin_rendering needs a target");
        let color_atts: Vec<_> = colors
            .iter()
            .map(|c| {
                vk::RenderingAttachmentInfo::default()
                    .image_view(c.image.view())
                    .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                    .load_op(vk::AttachmentLoadOp::CLEAR)
                    .store_op(vk::AttachmentStoreOp::STORE)
                    .clear_value(vk::ClearValue { color: vk::ClearColorValue { float32: c.clear } })
            })
            .collect();
        let depth_att = depth.map(|d| {
            vk::RenderingAttachmentInfo::default()
                .image_view(d.view())
                .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
                .load_op(vk::AttachmentLoadOp::CLEAR)
                .store_op(vk::AttachmentStoreOp::STORE)
                .clear_value(vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 0.0, stencil: 0 } })
        });
        let area = vk::Rect2D {
            offset: vk::Offset2D { x: 0, y: 0 },
            extent: vk::Extent2D { width: extent[0], height: extent[1] },
        };
        let mut info = vk::RenderingInfo::default().render_area(area).layer_count(1).color_attachments(&color_atts);
        if let Some(d) = depth_att.as_ref() {
            info = info.depth_attachment(d);
        }
        let viewport = vk::Viewport {
            x: 0.0,
            y: 0.0,
            width: extent[0] as f32,
            height: extent[1] as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        // SAFETY: attachments are live and in the layouts named above.
        unsafe {
            self.d().cmd_begin_rendering(self.cmd, &info);
            self.d().cmd_set_viewport(self.cmd, 0, &[viewport]);
            self.d().cmd_set_scissor(self.cmd, 0, &[area]);
        }
    }

    pub fn end_rendering(&mut self) {
        // SAFETY: paired with begin_rendering by the caller.
        unsafe { self.d().cmd_end_rendering(self.cmd) };
    }

    pub fn draw(&mut self, vertices: u32, instances: u32) {
        // SAFETY: inside a rendering scope with a bound graphics pipeline.
        unsafe { self.d().cmd_draw(self.cmd, vertices, instances, 0, 0) };
    }

    pub fn draw_indexed(&mut self, indices: &Buffer, index_count: u32, instances: u32) {
        // SAFETY: live u32 index buffer.
        unsafe {
            self.d().cmd_bind_index_buffer(self.cmd, indices.raw, 0, vk::IndexType::UINT32);
            self.d().cmd_draw_indexed(self.cmd, index_count, instances, 0, 0, 0);
        }
    }

    /// One `VkDrawIndexedIndirectCommand` at `offset` of `args` (written on
    /// the GPU), drawing with the u32 `indices`.
    pub fn draw_indexed_indirect(&mut self, indices: &Buffer, args: &Buffer, offset: u64) {
        let size = std::mem::size_of::<vk::DrawIndexedIndirectCommand>() as u64;
        assert!(
            offset.is_multiple_of(4) && offset + size <= args.size,
            "indirect draw at {offset} overruns {} ({} bytes)",
            args.name,
            args.size
        );
        // SAFETY: live buffers, the command's range checked above;
        // multiDrawIndirect is not needed for one draw.
        unsafe {
            self.d().cmd_bind_index_buffer(self.cmd, indices.raw, 0, vk::IndexType::UINT32);
            self.d().cmd_draw_indexed_indirect(self.cmd, args.raw, offset, 1, size as u32);
        }
    }

    /// `VkDrawIndexedIndirectCommand`s from `args`, count read from `count`.
    pub fn draw_indexed_indirect_count(
        &mut self,
        indices: &Buffer,
        args: &Buffer,
        count: &Buffer,
        count_offset: u64,
        max_draws: u32,
    ) {
        let stride = std::mem::size_of::<vk::DrawIndexedIndirectCommand>() as u32;
        // SAFETY: live buffers; drawIndirectCount is a required feature.
        unsafe {
            self.d().cmd_bind_index_buffer(self.cmd, indices.raw, 0, vk::IndexType::UINT32);
            self.d().cmd_draw_indexed_indirect_count(self.cmd, args.raw, 0, count.raw, count_offset, max_draws, stride);
        }
    }

    pub fn fill_buffer(&mut self, buf: &Buffer, value: u32) {
        // SAFETY: live buffer, whole range.
        unsafe { self.d().cmd_fill_buffer(self.cmd, buf.raw, 0, vk::WHOLE_SIZE, value) };
    }

    /// Writes up to 64 KiB of `data` at `offset` inline in the command buffer.
    pub fn update_buffer(&mut self, buf: &Buffer, offset: u64, data: &[u8]) {
        assert!(
            data.len() <= 65536 && data.len().is_multiple_of(4) && offset + data.len() as u64 <= buf.size,
            "update of {}",
            buf.name
        );
        // SAFETY: size, alignment and range checked above.
        unsafe { self.d().cmd_update_buffer(self.cmd, buf.raw, offset, data) };
    }

    /// Clears every mip and layer of an integer colour image in GENERAL layout.
    pub fn clear_color_u32(&mut self, img: &Image, value: u32) {
        let range = vk::ImageSubresourceRange::default()
            .aspect_mask(vk::ImageAspectFlags::COLOR)
            .level_count(vk::REMAINING_MIP_LEVELS)
            .layer_count(vk::REMAINING_ARRAY_LAYERS);
        let color = vk::ClearColorValue { uint32: [value; 4] };
        // SAFETY: live image in GENERAL (valid for clears).
        unsafe { self.d().cmd_clear_color_image(self.cmd, img.raw, vk::ImageLayout::GENERAL, &color, &[range]) };
    }

    pub fn copy_buffer(&mut self, src: &Buffer, dst: &Buffer, size: u64) {
        assert!(size <= src.size && size <= dst.size, "copy of {size} bytes overruns {} or {}", src.name, dst.name);
        // SAFETY: live buffers, size checked.
        unsafe {
            self.d().cmd_copy_buffer(
                self.cmd,
                src.raw,
                dst.raw,
                &[vk::BufferCopy { src_offset: 0, dst_offset: 0, size }],
            )
        };
    }

    /// Copies one mip of one layer of `img` (in TRANSFER_SRC_OPTIMAL), tightly packed.
    pub fn copy_image_to_buffer(&mut self, img: &Image, mip: u32, layer: u32, dst: &Buffer) {
        let region = packed_region(img, mip, layer, 0);
        // SAFETY: live objects; the layer validates sizes.
        unsafe {
            self.d().cmd_copy_image_to_buffer(
                self.cmd,
                img.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                dst.raw,
                &[region],
            )
        };
    }

    /// Copies tightly packed texels at `offset` of `src` into one mip of one
    /// layer of `img`, which must be in TRANSFER_DST_OPTIMAL.
    pub fn copy_buffer_to_image(&mut self, src: &Buffer, offset: u64, img: &Image, mip: u32, layer: u32) {
        let region = packed_region(img, mip, layer, offset);
        // SAFETY: live objects; the caller put the image in TRANSFER_DST_OPTIMAL.
        unsafe {
            self.d().cmd_copy_buffer_to_image(
                self.cmd,
                src.raw,
                img.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[region],
            )
        };
    }

    /// Opens a debug-utils label (RenderDoc / Nsight show the pass by name).
    pub fn begin_label(&mut self, name: &str) {
        if let Some(dd) = &self.ctx.shared.debug_device {
            let name = CString::new(name).unwrap_or_default();
            // SAFETY: valid command buffer; debug utils loaded.
            unsafe { dd.cmd_begin_debug_utils_label(self.cmd, &vk::DebugUtilsLabelEXT::default().label_name(&name)) };
        }
    }

    pub fn end_label(&mut self) {
        if let Some(dd) = &self.ctx.shared.debug_device {
            // SAFETY: paired with begin_label.
            unsafe { dd.cmd_end_debug_utils_label(self.cmd) };
        }
    }

    pub fn reset_queries(&mut self, pool: &TimestampPool, first: u32, count: u32) {
        // SAFETY: range within the pool (asserted by the pool's user).
        unsafe { self.d().cmd_reset_query_pool(self.cmd, pool.raw, first, count) };
    }

    pub fn write_timestamp(&mut self, pool: &TimestampPool, index: u32) {
        assert!(index < pool.capacity, "timestamp {index} outside pool of {}", pool.capacity);
        // SAFETY: index checked; the query was reset this frame.
        unsafe { self.d().cmd_write_timestamp2(self.cmd, vk::PipelineStageFlags2::ALL_COMMANDS, pool.raw, index) };
    }
}

/// One whole mip of one layer, tightly packed at `offset` in the buffer.
fn packed_region(img: &Image, mip: u32, layer: u32, offset: u64) -> vk::BufferImageCopy {
    vk::BufferImageCopy::default()
        .buffer_offset(offset)
        .image_subresource(vk::ImageSubresourceLayers {
            aspect_mask: aspect_of(img.format),
            mip_level: mip,
            base_array_layer: layer,
            layer_count: 1,
        })
        .image_extent(vk::Extent3D {
            width: (img.extent[0] >> mip).max(1),
            height: (img.extent[1] >> mip).max(1),
            depth: 1,
        })
}

//! Safe recording into a command buffer: synchronization2 barriers and
//! layout transitions, push descriptors checked against reflection,
//! dispatches and (indirect) draws, dynamic rendering. Transfers, labels and
//! queries are in `transfer.rs`.
//!
//! "Safe" is checked, not assumed: the recorder tracks whether a rendering
//! scope is open and which pipeline is bound at each bind point, every
//! image carries the layout its recorded transitions leave it in, and
//! indirect arguments are bounds- and usage-checked. A violation is a
//! programmer error and panics before the command reaches Vulkan.

use super::access_log::Access;
use super::context::Context;
use super::pipeline::Pipeline;
use super::resources::{aspect_of, depth_layout, has_stencil, Buffer, Image};
use super::shader::{Binding, BindingKind};
use ash::vk;

/// A resource bound to a reflected binding.
#[derive(Clone, Copy)]
pub enum Resource<'a> {
    Buffer(&'a Buffer),
    /// (buffer, offset, size)
    BufferRange(&'a Buffer, u64, u64),
    /// An image that must be in the given layout (GENERAL for storage images).
    Image(&'a Image, vk::ImageLayout),
    /// One mip of an image, which must be in the given layout.
    ImageMip(&'a Image, u32, vk::ImageLayout),
    Sampler(vk::Sampler),
}

pub struct Recorder<'a> {
    pub(super) ctx: &'a Context,
    pub(super) cmd: vk::CommandBuffer,
    /// A dynamic rendering scope is open.
    pub(super) rendering: bool,
    /// The open scope's colour attachment count, whether it has depth, and
    /// its size (`clear_rect`).
    scope: (u32, bool, [u32; 2]),
    /// What the commands touched, when asked (`log_accesses`).
    accesses: Option<Vec<Access>>,
    /// Host-read buffers the GPU wrote since the last barrier to the host
    /// stage (`host_unpublished`).
    unpublished: Vec<String>,
    compute: Option<vk::Pipeline>,
    graphics: Option<vk::Pipeline>,
}

/// A color attachment for `begin_rendering`: cleared to `clear`, or its
/// contents kept when `None` (a later pass drawing over an earlier one).
pub struct ColorTarget<'a> {
    pub image: &'a Image,
    pub clear: Option<[f32; 4]>,
}

/// The depth attachment for `begin_rendering`: cleared to `clear`
/// (reversed-Z: 0 is far) or kept when `None`. A depth-stencil format is
/// attached as both; its stencil is cleared to 0 with the depth when
/// `clear_stencil`, else kept. `read_only`: in the read-only layout (no
/// depth or stencil writes; the depth may be sampled meanwhile).
pub struct DepthTarget<'a> {
    pub image: &'a Image,
    pub clear: Option<f32>,
    pub clear_stencil: bool,
    pub read_only: bool,
}

impl<'a> Recorder<'a> {
    /// Records into a command buffer the caller owns (e.g. an engine's).
    ///
    /// # Safety
    /// `cmd` must be a command buffer of `ctx`'s device in the recording
    /// state, outside any render pass or rendering scope, allocated from a
    /// pool of a queue family that supports the commands recorded, and not
    /// recorded into elsewhere while this recorder lives. Images used here
    /// must be in the layouts their [`Image::layout`] reports.
    pub unsafe fn from_raw(ctx: &'a Context, cmd: vk::CommandBuffer) -> Self {
        Recorder {
            ctx,
            cmd,
            rendering: false,
            scope: (0, false, [0, 0]),
            accesses: None,
            unpublished: Vec::new(),
            compute: None,
            graphics: None,
        }
    }

    /// Host-read buffers written since the last barrier to the host stage:
    /// the host may see stale data in them even after the fence. The frame
    /// executor asserts every pass leaves none (who writes one publishes it,
    /// not whichever pass happens to come later).
    pub fn host_unpublished(&self) -> &[String] {
        &self.unpublished
    }

    pub(super) fn published_to_host(&mut self) {
        self.unpublished.clear();
    }

    /// From now on, notes what each command touches (tests: what two
    /// submissions that may overlap share, `access_log`).
    pub fn log_accesses(&mut self) {
        self.accesses.get_or_insert_with(Vec::new);
    }

    /// What was noted since `log_accesses` or the last call.
    pub fn take_accesses(&mut self) -> Vec<Access> {
        self.accesses.as_mut().map(std::mem::take).unwrap_or_default()
    }

    pub(super) fn note_buffer(&mut self, b: &Buffer, write: bool) {
        if write && b.host_read && !self.unpublished.contains(&b.name) {
            self.unpublished.push(b.name.clone());
        }
        if let Some(log) = &mut self.accesses {
            log.push(Access::new(b.raw, &b.name, write, None));
        }
    }

    pub(super) fn note_image(&mut self, i: &Image, write: bool, layer: Option<u32>) {
        if let Some(log) = &mut self.accesses {
            log.push(Access::new(i.raw, &i.name, write, layer));
        }
    }

    pub fn context(&self) -> &'a Context {
        self.ctx
    }

    pub fn raw(&self) -> vk::CommandBuffer {
        self.cmd
    }

    /// True while a `begin_rendering` scope is open.
    pub fn is_rendering(&self) -> bool {
        self.rendering
    }

    pub(super) fn d(&self) -> &ash::Device {
        &self.ctx.shared.device
    }

    pub(super) fn outside_rendering(&self, what: &str) {
        assert!(!self.rendering, "{what} inside a rendering scope (call end_rendering first)");
    }

    /// Makes all earlier writes visible to all later reads (on lavapipe every
    /// barrier drains all work anyway; on real GPUs passes pick narrower ones).
    pub fn barrier(&mut self, src: vk::PipelineStageFlags2, dst: vk::PipelineStageFlags2) {
        self.outside_rendering("barrier");
        let mb = [vk::MemoryBarrier2::default()
            .src_stage_mask(src)
            .src_access_mask(vk::AccessFlags2::MEMORY_WRITE)
            .dst_stage_mask(dst)
            .dst_access_mask(vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE)];
        let dep = vk::DependencyInfo::default().memory_barriers(&mb);
        // SAFETY: recording state by construction; outside rendering (checked).
        unsafe { self.d().cmd_pipeline_barrier2(self.cmd, &dep) };
        if dst.contains(vk::PipelineStageFlags2::HOST) {
            self.published_to_host();
        }
    }

    /// Full barrier plus a transition of every subresource of `image` from
    /// its tracked layout to `new` (contents kept).
    pub fn transition(&mut self, image: &Image, new: vk::ImageLayout) {
        self.layout_barrier(image, image.layout(), new);
    }

    /// Like `transition`, but from UNDEFINED: the contents may be dropped
    /// (a target that is cleared next).
    pub fn discard_to(&mut self, image: &Image, new: vk::ImageLayout) {
        self.layout_barrier(image, vk::ImageLayout::UNDEFINED, new);
    }

    fn layout_barrier(&mut self, image: &Image, old: vk::ImageLayout, new: vk::ImageLayout) {
        self.outside_rendering("layout transition");
        // A layout transition rewrites the image.
        self.note_image(image, true, None);
        assert_ne!(new, vk::ImageLayout::UNDEFINED, "{}: cannot transition to UNDEFINED", image.name);
        let ib = [image_barrier(image, None, old, new)];
        let dep = vk::DependencyInfo::default().image_memory_barriers(&ib);
        // SAFETY: image is live for the borrow; `old` is its tracked layout
        // (or UNDEFINED, always valid); outside rendering (checked).
        unsafe { self.d().cmd_pipeline_barrier2(self.cmd, &dep) };
        image.set_layout(new);
    }

    pub fn bind_pipeline(&mut self, p: &Pipeline) {
        match p.bind_point {
            vk::PipelineBindPoint::COMPUTE => self.compute = Some(p.raw),
            _ => self.graphics = Some(p.raw),
        }
        // SAFETY: live pipeline.
        unsafe { self.d().cmd_bind_pipeline(self.cmd, p.bind_point, p.raw) };
    }

    fn assert_bound(&self, p: &Pipeline, what: &str) {
        let bound = if p.bind_point == vk::PipelineBindPoint::COMPUTE { self.compute } else { self.graphics };
        assert_eq!(bound, Some(p.raw), "{what} for pipeline {}, which is not the bound one", p.name);
    }

    /// Binds resources to `p`'s reflected bindings; the kind of each resource
    /// must match the shader's declaration and each image must be in the
    /// layout named (programmer errors otherwise).
    pub fn push_descriptors(&mut self, p: &Pipeline, bindings: &[(Binding, Resource)]) {
        self.assert_bound(p, "push_descriptors");
        let mut buffer_infos = Vec::with_capacity(bindings.len());
        let mut image_infos = Vec::with_capacity(bindings.len());
        for (b, r) in bindings {
            let Some(merged) = p.bindings.iter().find(|m| *m == b) else {
                panic!("{}: binding {} is not part of pipeline {}", b.name, b.binding, p.name)
            };
            match r {
                Resource::Buffer(buf) | Resource::BufferRange(buf, ..) => self.note_buffer(buf, merged.writes),
                Resource::Image(img, _) | Resource::ImageMip(img, ..) => self.note_image(img, merged.writes, None),
                Resource::Sampler(_) => {}
            }
            let image_info = |img: &Image, view, layout: vk::ImageLayout| {
                assert_eq!(img.layout(), layout, "{}: image {} bound as {layout:?}", b.name, img.name);
                vk::DescriptorImageInfo { sampler: vk::Sampler::null(), image_view: view, image_layout: layout }
            };
            match r {
                Resource::Buffer(buf) => {
                    buffer_infos.push(vk::DescriptorBufferInfo { buffer: buf.raw, offset: 0, range: vk::WHOLE_SIZE })
                }
                Resource::BufferRange(buf, offset, size) => {
                    assert!(offset + size <= buf.size, "{}: range {offset}+{size} overruns {}", b.name, buf.name);
                    buffer_infos.push(vk::DescriptorBufferInfo { buffer: buf.raw, offset: *offset, range: *size })
                }
                Resource::Image(img, layout) => {
                    let view = if b.kind == BindingKind::SampledImage { img.sample_view() } else { img.view() };
                    image_infos.push(image_info(img, view, *layout))
                }
                Resource::ImageMip(img, mip, layout) => image_infos.push(image_info(img, img.mip_view(*mip), *layout)),
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
        self.assert_bound(p, "push_constants");
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
        self.outside_rendering("dispatch");
        assert!(self.compute.is_some(), "dispatch with no compute pipeline bound");
        let max = self.ctx.info().limits.max_compute_workgroup_count;
        assert!(x <= max[0] && y <= max[1] && z <= max[2], "dispatch {x}x{y}x{z} exceeds the device's {max:?}");
        // SAFETY: outside rendering, compute pipeline bound, counts in limits (checked).
        unsafe { self.d().cmd_dispatch(self.cmd, x, y, z) };
    }

    /// One `VkDispatchIndirectCommand` at `offset` of `args` (written on the
    /// GPU; its counts are the shader writer's to keep in limits).
    pub fn dispatch_indirect(&mut self, args: &Buffer, offset: u64) {
        self.outside_rendering("dispatch_indirect");
        assert!(self.compute.is_some(), "dispatch_indirect with no compute pipeline bound");
        indirect_range(args, offset, std::mem::size_of::<vk::DispatchIndirectCommand>() as u64);
        self.note_buffer(args, false);
        // SAFETY: live buffer with INDIRECT usage, range checked; pipeline bound.
        unsafe { self.d().cmd_dispatch_indirect(self.cmd, args.raw, offset) };
    }

    /// Begins dynamic rendering into `colors` (+ optional depth), with a
    /// full-target viewport and scissor. The targets must be in
    /// COLOR_ATTACHMENT_OPTIMAL / the [`depth_layout`] of their format.
    pub fn begin_rendering(&mut self, colors: &[ColorTarget], depth_target: Option<DepthTarget>) {
        let depth = depth_target.as_ref().map(|d| (d.image, depth_layout(d.image.format, d.read_only)));
        self.outside_rendering("begin_rendering");
        colors.iter().for_each(|c| self.note_image(c.image, true, None));
        if let Some(d) = &depth_target {
            self.note_image(d.image, !d.read_only, None);
        }
        let extent = colors
            .first()
            .map(|c| c.image.extent)
            .or(depth.map(|d| d.0.extent))
            .expect("begin_rendering needs a target");
        for (img, layout) in colors.iter().map(|c| (c.image, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)).chain(depth) {
            assert_eq!(img.layout(), layout, "render target {} is not in {layout:?}", img.name);
            assert_eq!(img.extent, extent, "render target {} differs in size from the first", img.name);
        }
        let color_atts: Vec<_> = colors
            .iter()
            .map(|c| {
                vk::RenderingAttachmentInfo::default()
                    .image_view(c.image.view())
                    .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                    .load_op(if c.clear.is_some() { vk::AttachmentLoadOp::CLEAR } else { vk::AttachmentLoadOp::LOAD })
                    .store_op(vk::AttachmentStoreOp::STORE)
                    .clear_value(vk::ClearValue { color: vk::ClearColorValue { float32: c.clear.unwrap_or_default() } })
            })
            .collect();
        let depth_att = depth_target.as_ref().map(|d| {
            let load = if d.clear.is_some() { vk::AttachmentLoadOp::CLEAR } else { vk::AttachmentLoadOp::LOAD };
            let store = if d.read_only { vk::AttachmentStoreOp::NONE } else { vk::AttachmentStoreOp::STORE };
            let depth = d.clear.unwrap_or_default();
            vk::RenderingAttachmentInfo::default()
                .image_view(d.image.view())
                .image_layout(depth_layout(d.image.format, d.read_only))
                .load_op(load)
                .store_op(store)
                .clear_value(vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth, stencil: 0 } })
        });
        let stencil_att = depth_target.as_ref().filter(|d| has_stencil(d.image.format)).and_then(|d| {
            let keep = d.clear.is_none() || !d.clear_stencil;
            depth_att.map(|a| if keep { a.load_op(vk::AttachmentLoadOp::LOAD) } else { a })
        });
        let area = vk::Rect2D {
            offset: vk::Offset2D { x: 0, y: 0 },
            extent: vk::Extent2D { width: extent[0], height: extent[1] },
        };
        let mut info = vk::RenderingInfo::default().render_area(area).layer_count(1).color_attachments(&color_atts);
        if let Some(d) = depth_att.as_ref() {
            info = info.depth_attachment(d);
        }
        if let Some(st) = stencil_att.as_ref() {
            info = info.stencil_attachment(st);
        }
        let viewport = vk::Viewport {
            x: 0.0,
            y: 0.0,
            width: extent[0] as f32,
            height: extent[1] as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        // SAFETY: attachments are live, equally sized and in the layouts
        // named above (checked); no scope was open (checked).
        unsafe {
            self.d().cmd_begin_rendering(self.cmd, &info);
            self.d().cmd_set_viewport(self.cmd, 0, &[viewport]);
            self.d().cmd_set_scissor(self.cmd, 0, &[area]);
        }
        self.rendering = true;
        self.scope = (colors.len() as u32, depth_target.is_some(), extent);
    }

    /// Clears `rect` (x0, y0, x1, y1 in pixels, row 0 at the top) of every
    /// colour attachment of the open scope to `color` and of its depth to
    /// `depth`: an engine's flat stand-in geometry (tools, tests).
    pub fn clear_rect(&mut self, rect: [u32; 4], color: [f32; 4], depth: Option<f32>) {
        let (colors, has_depth, extent) = self.scope;
        assert!(self.rendering, "clear_rect outside a rendering scope");
        assert!(depth.is_none() || has_depth, "clear_rect of depth in a scope without depth");
        assert!(rect[0] < rect[2] && rect[1] < rect[3] && rect[2] <= extent[0] && rect[3] <= extent[1], "{rect:?}");
        let mut clears: Vec<vk::ClearAttachment> = (0..colors)
            .map(|i| vk::ClearAttachment {
                aspect_mask: vk::ImageAspectFlags::COLOR,
                color_attachment: i,
                clear_value: vk::ClearValue { color: vk::ClearColorValue { float32: color } },
            })
            .collect();
        if let Some(d) = depth {
            clears.push(vk::ClearAttachment {
                aspect_mask: vk::ImageAspectFlags::DEPTH,
                color_attachment: 0,
                clear_value: vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: d, stencil: 0 } },
            });
        }
        let r = vk::ClearRect {
            rect: vk::Rect2D {
                offset: vk::Offset2D { x: rect[0] as i32, y: rect[1] as i32 },
                extent: vk::Extent2D { width: rect[2] - rect[0], height: rect[3] - rect[1] },
            },
            base_array_layer: 0,
            layer_count: 1,
        };
        // SAFETY: inside a rendering scope (checked) whose attachments are
        // the ones addressed; the rect lies inside the render area (checked).
        unsafe { self.d().cmd_clear_attachments(self.cmd, &clears, &[r]) };
    }

    pub fn end_rendering(&mut self) {
        assert!(self.rendering, "end_rendering without begin_rendering");
        // SAFETY: a scope is open (checked).
        unsafe { self.d().cmd_end_rendering(self.cmd) };
        self.rendering = false;
    }

    fn drawable(&self, what: &str) {
        assert!(self.rendering, "{what} outside a rendering scope");
        assert!(self.graphics.is_some(), "{what} with no graphics pipeline bound");
    }

    pub fn draw(&mut self, vertices: u32, instances: u32) {
        self.drawable("draw");
        // SAFETY: inside a rendering scope with a bound graphics pipeline (checked).
        unsafe { self.d().cmd_draw(self.cmd, vertices, instances, 0, 0) };
    }

    pub fn draw_indexed(&mut self, indices: &Buffer, index_count: u32, instances: u32) {
        self.drawable("draw_indexed");
        index_buffer(indices, index_count);
        self.note_buffer(indices, false);
        // SAFETY: rendering, pipeline bound, index range checked.
        unsafe {
            self.d().cmd_bind_index_buffer(self.cmd, indices.raw, 0, vk::IndexType::UINT32);
            self.d().cmd_draw_indexed(self.cmd, index_count, instances, 0, 0, 0);
        }
    }

    /// One `VkDrawIndirectCommand` at `offset` of `args` (written on the GPU).
    pub fn draw_indirect(&mut self, args: &Buffer, offset: u64) {
        self.drawable("draw_indirect");
        let size = std::mem::size_of::<vk::DrawIndirectCommand>() as u64;
        indirect_range(args, offset, size);
        self.note_buffer(args, false);
        // SAFETY: rendering, pipeline bound, the command's range and usage checked.
        unsafe { self.d().cmd_draw_indirect(self.cmd, args.raw, offset, 1, size as u32) };
    }

    /// One `VkDrawIndexedIndirectCommand` at `offset` of `args` (written on
    /// the GPU), drawing with the u32 `indices`.
    pub fn draw_indexed_indirect(&mut self, indices: &Buffer, args: &Buffer, offset: u64) {
        self.drawable("draw_indexed_indirect");
        let size = std::mem::size_of::<vk::DrawIndexedIndirectCommand>() as u64;
        indirect_range(args, offset, size);
        index_buffer(indices, 0);
        self.note_buffer(args, false);
        self.note_buffer(indices, false);
        // SAFETY: rendering, pipeline bound, the command's range and the
        // usages checked; multiDrawIndirect is not needed for one draw.
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
        self.drawable("draw_indexed_indirect_count");
        let stride = std::mem::size_of::<vk::DrawIndexedIndirectCommand>() as u32;
        indirect_range(args, 0, u64::from(stride) * u64::from(max_draws));
        indirect_range(count, count_offset, 4);
        index_buffer(indices, 0);
        for b in [args, count, indices] {
            self.note_buffer(b, false);
        }
        // SAFETY: rendering, pipeline bound, ranges and usages checked;
        // drawIndirectCount is a required feature.
        unsafe {
            self.d().cmd_bind_index_buffer(self.cmd, indices.raw, 0, vk::IndexType::UINT32);
            self.d().cmd_draw_indexed_indirect_count(self.cmd, args.raw, 0, count.raw, count_offset, max_draws, stride);
        }
    }
}

impl Drop for Recorder<'_> {
    fn drop(&mut self) {
        // A scope left open would make the caller's next command invalid.
        if !std::thread::panicking() {
            assert!(!self.rendering, "recorder dropped inside a rendering scope");
        }
    }
}

/// `size` bytes of indirect arguments at `offset` of `args`: aligned, in
/// bounds, and the buffer made for indirect use.
fn indirect_range(args: &Buffer, offset: u64, size: u64) {
    assert!(
        offset.is_multiple_of(4) && offset + size <= args.size,
        "indirect arguments at {offset} (+{size}) overrun {} ({} bytes)",
        args.name,
        args.size
    );
    assert!(args.usage.contains(vk::BufferUsageFlags::INDIRECT_BUFFER), "{} lacks INDIRECT_BUFFER usage", args.name);
}

/// A u32 index buffer holding at least `count` indices.
fn index_buffer(indices: &Buffer, count: u32) {
    assert!(indices.usage.contains(vk::BufferUsageFlags::INDEX_BUFFER), "{} lacks INDEX_BUFFER usage", indices.name);
    assert!(u64::from(count) * 4 <= indices.size, "{count} indices overrun {}", indices.name);
}

/// A full barrier (every earlier write before every later access) with a
/// layout change of every mip of `image`'s layer `layer`, or of all its
/// layers.
pub(super) fn image_barrier(
    image: &Image,
    layer: Option<u32>,
    old: vk::ImageLayout,
    new: vk::ImageLayout,
) -> vk::ImageMemoryBarrier2<'static> {
    let range =
        vk::ImageSubresourceRange::default().aspect_mask(aspect_of(image.format)).level_count(vk::REMAINING_MIP_LEVELS);
    let range = match layer {
        Some(l) => range.base_array_layer(l).layer_count(1),
        None => range.layer_count(vk::REMAINING_ARRAY_LAYERS),
    };
    vk::ImageMemoryBarrier2::default()
        .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
        .src_access_mask(vk::AccessFlags2::MEMORY_WRITE)
        .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
        .dst_access_mask(vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE)
        .old_layout(old)
        .new_layout(new)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image.raw)
        .subresource_range(range)
}

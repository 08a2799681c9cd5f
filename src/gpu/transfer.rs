//! Transfers (fills, inline updates, clears, copies), debug labels and
//! timestamp queries of the [`Recorder`]; each checks the ranges and image
//! layouts it relies on (see `commands.rs`).

use super::commands::Recorder;
use super::query::{StatisticsPool, TimestampPool};
use super::resources::{aspect_of, has_stencil, Buffer, Image};
use ash::vk;
use std::ffi::CString;

impl Recorder<'_> {
    pub fn fill_buffer(&mut self, buf: &Buffer, value: u32) {
        self.note_buffer(buf, true);
        self.outside_rendering("fill_buffer");
        // SAFETY: live buffer, whole range, outside rendering (checked).
        unsafe { self.d().cmd_fill_buffer(self.cmd, buf.raw, 0, vk::WHOLE_SIZE, value) };
    }

    /// Writes up to 64 KiB of `data` at `offset` inline in the command buffer.
    pub fn update_buffer(&mut self, buf: &Buffer, offset: u64, data: &[u8]) {
        self.note_buffer(buf, true);
        self.outside_rendering("update_buffer");
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
        self.note_image(img, true, None);
        self.outside_rendering("clear_color_u32");
        assert_eq!(img.layout(), vk::ImageLayout::GENERAL, "clear of {}", img.name);
        let range = vk::ImageSubresourceRange::default()
            .aspect_mask(vk::ImageAspectFlags::COLOR)
            .level_count(vk::REMAINING_MIP_LEVELS)
            .layer_count(vk::REMAINING_ARRAY_LAYERS);
        let color = vk::ClearColorValue { uint32: [value; 4] };
        // SAFETY: live image in GENERAL (checked; valid for clears).
        unsafe { self.d().cmd_clear_color_image(self.cmd, img.raw, vk::ImageLayout::GENERAL, &color, &[range]) };
    }

    pub fn copy_buffer(&mut self, src: &Buffer, dst: &Buffer, size: u64) {
        self.note_buffer(src, false);
        self.note_buffer(dst, true);
        self.outside_rendering("copy_buffer");
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

    /// Copies `size` bytes from `src` at `src_offset` to `dst` at `dst_offset`.
    pub fn copy_buffer_region(&mut self, src: &Buffer, src_offset: u64, dst: &Buffer, dst_offset: u64, size: u64) {
        self.note_buffer(src, false);
        self.note_buffer(dst, true);
        self.outside_rendering("copy_buffer_region");
        assert!(
            src_offset + size <= src.size && dst_offset + size <= dst.size,
            "copy of {size} bytes overruns {} or {}",
            src.name,
            dst.name
        );
        // SAFETY: live buffers, ranges checked.
        unsafe {
            self.d().cmd_copy_buffer(self.cmd, src.raw, dst.raw, &[vk::BufferCopy { src_offset, dst_offset, size }])
        };
    }

    /// Makes earlier transfer writes visible to host reads once the
    /// submission has completed (readback rings).
    pub fn transfer_to_host_barrier(&mut self) {
        self.outside_rendering("transfer_to_host_barrier");
        let mb = [vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::ALL_TRANSFER)
            .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::HOST)
            .dst_access_mask(vk::AccessFlags2::HOST_READ)];
        let dep = vk::DependencyInfo::default().memory_barriers(&mb);
        // SAFETY: recording state by construction; outside rendering (checked).
        unsafe { self.d().cmd_pipeline_barrier2(self.cmd, &dep) };
        self.published_to_host();
    }

    /// Copies one mip of one layer of `img` (in TRANSFER_SRC_OPTIMAL), tightly packed.
    pub fn copy_image_to_buffer(&mut self, img: &Image, mip: u32, layer: u32, dst: &Buffer) {
        self.note_image(img, false, None);
        self.note_buffer(dst, true);
        self.outside_rendering("copy_image_to_buffer");
        assert_eq!(img.layout(), vk::ImageLayout::TRANSFER_SRC_OPTIMAL, "copy from {}", img.name);
        let region = packed_region(img, mip, layer, 0);
        // SAFETY: live objects, layout checked; the layer validates sizes.
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

    /// Copies the stencil aspect of a depth-stencil image (mip 0, layer 0;
    /// TRANSFER_SRC_OPTIMAL) to `dst`, a byte per texel.
    pub fn copy_stencil_to_buffer(&mut self, img: &Image, dst: &Buffer) {
        self.note_image(img, false, None);
        self.note_buffer(dst, true);
        self.outside_rendering("copy_stencil_to_buffer");
        assert!(has_stencil(img.format), "{} has no stencil aspect", img.name);
        assert_eq!(img.layout(), vk::ImageLayout::TRANSFER_SRC_OPTIMAL, "copy from {}", img.name);
        let mut region = packed_region(img, 0, 0, 0);
        region.image_subresource.aspect_mask = vk::ImageAspectFlags::STENCIL;
        // SAFETY: live objects, aspect and layout checked; the layer
        // validates sizes.
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

    /// Copies mip 0 of `src` (TRANSFER_SRC_OPTIMAL) over mip 0 of `dst`
    /// (TRANSFER_DST_OPTIMAL), scaled to fit and converted between colour
    /// formats (e.g. RGBA to a swapchain's BGRA), nearest texel.
    pub fn blit(&mut self, src: &Image, dst: &Image) {
        self.note_image(src, false, None);
        self.note_image(dst, true, None);
        self.outside_rendering("blit");
        assert_eq!(src.layout(), vk::ImageLayout::TRANSFER_SRC_OPTIMAL, "blit from {}", src.name);
        assert_eq!(dst.layout(), vk::ImageLayout::TRANSFER_DST_OPTIMAL, "blit into {}", dst.name);
        let corner = |e: [u32; 2]| [vk::Offset3D::default(), vk::Offset3D { x: e[0] as i32, y: e[1] as i32, z: 1 }];
        let layer = vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::COLOR).layer_count(1);
        let region = vk::ImageBlit2::default()
            .src_subresource(layer)
            .src_offsets(corner(src.extent))
            .dst_subresource(layer)
            .dst_offsets(corner(dst.extent));
        let regions = [region];
        let info = vk::BlitImageInfo2::default()
            .src_image(src.raw)
            .src_image_layout(vk::ImageLayout::TRANSFER_SRC_OPTIMAL)
            .dst_image(dst.raw)
            .dst_image_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
            .regions(&regions)
            .filter(vk::Filter::NEAREST);
        // SAFETY: live images in the layouts named (checked); the layer
        // validates formats and usage.
        unsafe { self.d().cmd_blit_image2(self.cmd, &info) };
    }

    /// Copies tightly packed texels at `offset` of `src` into one mip of one
    /// layer of `img`, which must be in TRANSFER_DST_OPTIMAL.
    pub fn copy_buffer_to_image(&mut self, src: &Buffer, offset: u64, img: &Image, mip: u32, layer: u32) {
        self.note_buffer(src, false);
        self.note_image(img, true, Some(layer));
        self.outside_rendering("copy_buffer_to_image");
        assert_eq!(img.layout(), vk::ImageLayout::TRANSFER_DST_OPTIMAL, "copy into {}", img.name);
        assert!(mip < img.mip_levels && layer < img.array_layers, "mip {mip} layer {layer} of {}", img.name);
        let region = packed_region(img, mip, layer, offset);
        // SAFETY: live objects, layout and subresource checked.
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

    /// Copies packed texels from `src` at each offset into mip 0 of one
    /// layer of an array image, touching only those layers: each goes from
    /// the image's tracked layout to TRANSFER_DST and back, so work on
    /// another queue may sample the image's other layers meanwhile (the
    /// node atlases under async compute). After the copies the layers are
    /// visible to every later command.
    pub fn copy_into_layers(&mut self, src: &Buffer, copies: &[(u64, &Image, u32)]) {
        self.outside_rendering("copy_into_layers");
        if copies.is_empty() {
            return;
        }
        let barrier = |img: &Image, layer: u32, old, new| {
            assert!(layer < img.array_layers, "layer {layer} of {}", img.name);
            super::commands::image_barrier(img, Some(layer), old, new)
        };
        self.note_buffer(src, false);
        for &(_, img, layer) in copies {
            self.note_image(img, true, Some(layer));
        }
        let dst = vk::ImageLayout::TRANSFER_DST_OPTIMAL;
        let to: Vec<_> = copies.iter().map(|&(_, img, layer)| barrier(img, layer, img.layout(), dst)).collect();
        let back: Vec<_> = copies.iter().map(|&(_, img, layer)| barrier(img, layer, dst, img.layout())).collect();
        // SAFETY: live objects; each layer goes from the image's tracked
        // layout (every subresource is in it) to TRANSFER_DST, is written
        // within its bounds (checked by packed_region's caller below), and
        // goes back, so the tracked layout stays true; outside rendering.
        unsafe {
            self.d().cmd_pipeline_barrier2(self.cmd, &vk::DependencyInfo::default().image_memory_barriers(&to));
            for &(offset, img, layer) in copies {
                let region = packed_region(img, 0, layer, offset);
                self.d().cmd_copy_buffer_to_image(self.cmd, src.raw, img.raw, dst, &[region]);
            }
            self.d().cmd_pipeline_barrier2(self.cmd, &vk::DependencyInfo::default().image_memory_barriers(&back));
        }
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
        self.outside_rendering("reset_queries");
        assert!(first + count <= pool.capacity, "queries {first}+{count} outside pool of {}", pool.capacity);
        // SAFETY: range checked, outside rendering.
        unsafe { self.d().cmd_reset_query_pool(self.cmd, pool.raw, first, count) };
    }

    pub fn reset_statistics(&mut self, pool: &StatisticsPool) {
        self.outside_rendering("reset_statistics");
        // SAFETY: the whole pool, outside rendering.
        unsafe { self.d().cmd_reset_query_pool(self.cmd, pool.raw, 0, pool.capacity) };
    }

    /// Begins statistics query `index`, ended by `end_statistics` in this
    /// command buffer outside rendering too (a query may not straddle a
    /// render pass's edge).
    pub fn begin_statistics(&mut self, pool: &StatisticsPool, index: u32) {
        self.outside_rendering("begin_statistics");
        assert!(index < pool.capacity, "query {index} outside pool of {}", pool.capacity);
        // SAFETY: index checked, outside rendering; the query was reset this frame.
        unsafe { self.d().cmd_begin_query(self.cmd, pool.raw, index, vk::QueryControlFlags::empty()) };
    }

    pub fn end_statistics(&mut self, pool: &StatisticsPool, index: u32) {
        self.outside_rendering("end_statistics");
        assert!(index < pool.capacity, "query {index} outside pool of {}", pool.capacity);
        // SAFETY: index checked, outside rendering, begun by begin_statistics.
        unsafe { self.d().cmd_end_query(self.cmd, pool.raw, index) };
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
            // Copies address one aspect: the depth of a depth-stencil image.
            aspect_mask: if has_stencil(img.format) { vk::ImageAspectFlags::DEPTH } else { aspect_of(img.format) },
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

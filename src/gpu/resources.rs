//! Buffers and images from small `*Desc` structs with debug names. Dropping a
//! resource retires it: it is destroyed once every frame submitted before the
//! drop has completed (see `Context::frame_completed`).

use super::context::{Context, Shared};
use crate::error::{vk_err, Error, Result};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
pub use gpu_allocator::MemoryLocation;
use serde::Serialize;
use std::sync::atomic::{AtomicI32, AtomicI64, Ordering};
use std::sync::Arc;

/// Live-object counters; tests assert they are all zero at teardown.
#[derive(Default)]
pub(crate) struct LiveCounters {
    pub buffers: AtomicI64,
    pub images: AtomicI64,
    pub pipelines: AtomicI64,
    pub query_pools: AtomicI64,
    pub samplers: AtomicI64,
    pub command_pools: AtomicI64,
    pub sync_objects: AtomicI64,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct LiveObjects {
    pub buffers: i64,
    pub images: i64,
    pub pipelines: i64,
    pub query_pools: i64,
    pub samplers: i64,
    pub command_pools: i64,
    pub sync_objects: i64,
}

impl LiveObjects {
    pub fn total(&self) -> i64 {
        self.buffers
            + self.images
            + self.pipelines
            + self.query_pools
            + self.samplers
            + self.command_pools
            + self.sync_objects
    }
}

impl LiveCounters {
    pub fn snapshot(&self) -> LiveObjects {
        let l = |a: &AtomicI64| a.load(Ordering::Acquire);
        LiveObjects {
            buffers: l(&self.buffers),
            images: l(&self.images),
            pipelines: l(&self.pipelines),
            query_pools: l(&self.query_pools),
            samplers: l(&self.samplers),
            command_pools: l(&self.command_pools),
            sync_objects: l(&self.sync_objects),
        }
    }
}

pub(crate) fn inc(c: &AtomicI64) {
    c.fetch_add(1, Ordering::AcqRel);
}

/// A Vulkan object waiting for the frames that may use it to finish.
pub(crate) enum Garbage {
    Buffer(vk::Buffer, Allocation),
    /// No allocation: an image someone else owns (a swapchain's, an
    /// engine's); only the views vista made for it are destroyed.
    Image(vk::Image, Vec<vk::ImageView>, Option<Allocation>),
    Pipeline(vk::Pipeline, vk::PipelineLayout, vk::DescriptorSetLayout),
    QueryPool(vk::QueryPool),
    Sampler(vk::Sampler),
    CommandPool(vk::CommandPool),
    Fence(vk::Fence),
    Semaphore(vk::Semaphore),
}

impl Garbage {
    pub(crate) fn destroy(self, s: &Shared) {
        let d = &s.device;
        let free = |a: Allocation| {
            let _ = s.allocator.lock().unwrap_or_else(|e| e.into_inner()).free(a);
        };
        let dec = |c: &AtomicI64| c.fetch_sub(1, Ordering::AcqRel);
        // SAFETY: retired objects are no longer used by the host, and every
        // frame that could use them on the GPU has completed.
        unsafe {
            match self {
                Garbage::Buffer(b, a) => {
                    d.destroy_buffer(b, None);
                    free(a);
                    dec(&s.live.buffers);
                }
                Garbage::Image(i, views, a) => {
                    for v in views {
                        d.destroy_image_view(v, None);
                    }
                    if let Some(a) = a {
                        d.destroy_image(i, None);
                        free(a);
                    }
                    dec(&s.live.images);
                }
                Garbage::Pipeline(p, l, sl) => {
                    d.destroy_pipeline(p, None);
                    d.destroy_pipeline_layout(l, None);
                    d.destroy_descriptor_set_layout(sl, None);
                    dec(&s.live.pipelines);
                }
                Garbage::Sampler(x) => {
                    d.destroy_sampler(x, None);
                    dec(&s.live.samplers);
                }
                Garbage::QueryPool(q) => {
                    d.destroy_query_pool(q, None);
                    dec(&s.live.query_pools);
                }
                Garbage::CommandPool(p) => {
                    d.destroy_command_pool(p, None);
                    dec(&s.live.command_pools);
                }
                Garbage::Fence(f) => {
                    d.destroy_fence(f, None);
                    dec(&s.live.sync_objects);
                }
                Garbage::Semaphore(x) => {
                    d.destroy_semaphore(x, None);
                    dec(&s.live.sync_objects);
                }
            }
        }
    }
}

#[derive(Debug, Clone)]
pub struct BufferDesc<'a> {
    pub name: &'a str,
    pub size: u64,
    pub usage: vk::BufferUsageFlags,
    /// `CpuToGpu` / `GpuToCpu` buffers are persistently mapped.
    pub location: MemoryLocation,
}

pub struct Buffer {
    pub(crate) raw: vk::Buffer,
    allocation: Option<Allocation>,
    pub size: u64,
    /// What the buffer was created for; the recorder checks it.
    pub usage: vk::BufferUsageFlags,
    pub name: String,
    /// The host reads it (`GpuToCpu`): a GPU write must be followed by a
    /// barrier to the host stage, which the recorder checks per pass.
    pub host_read: bool,
    shared: Arc<Shared>,
}

fn allocate(
    s: &Shared,
    name: &str,
    requirements: vk::MemoryRequirements,
    location: MemoryLocation,
    linear: bool,
) -> Result<Allocation> {
    if s.faults.allocation_fails() {
        return Err(Error::OutOfDeviceMemory);
    }
    let desc = AllocationCreateDesc {
        name,
        requirements,
        location,
        linear,
        allocation_scheme: AllocationScheme::GpuAllocatorManaged,
    };
    s.allocator.lock().unwrap_or_else(|e| e.into_inner()).allocate(&desc).map_err(|source| match source {
        gpu_allocator::AllocationError::OutOfMemory => Error::OutOfDeviceMemory,
        source => Error::Allocation { name: name.into(), source },
    })
}

impl Buffer {
    /// A GPU-only buffer holding `bytes` (a 4-byte placeholder when empty:
    /// a binding needs a buffer), uploaded and waited for; `usage` gains
    /// TRANSFER_DST.
    pub fn with_data(ctx: &Context, name: &str, bytes: &[u8], usage: vk::BufferUsageFlags) -> Result<Buffer> {
        let usage = usage | vk::BufferUsageFlags::TRANSFER_DST;
        let size = bytes.len().max(4) as u64;
        let b = Buffer::new(ctx, &BufferDesc { name, size, usage, location: MemoryLocation::GpuOnly })?;
        if !bytes.is_empty() {
            ctx.upload(&b, bytes)?;
        }
        Ok(b)
    }

    pub fn new(ctx: &Context, desc: &BufferDesc) -> Result<Buffer> {
        if desc.size == 0 {
            return Err(Error::BadInput(format!("buffer {:?} has size 0", desc.name)));
        }
        let s = &ctx.shared;
        let families = s.concurrent_families();
        let info = vk::BufferCreateInfo::default().size(desc.size).usage(desc.usage);
        let info = match &families {
            Some(f) => info.sharing_mode(vk::SharingMode::CONCURRENT).queue_family_indices(f),
            None => info.sharing_mode(vk::SharingMode::EXCLUSIVE),
        };
        // SAFETY: valid device and create info.
        let raw = unsafe { s.device.create_buffer(&info, None) }.map_err(vk_err("vkCreateBuffer"))?;
        // SAFETY: raw is a live buffer of this device.
        let req = unsafe { s.device.get_buffer_memory_requirements(raw) };
        let allocation = match allocate(s, desc.name, req, desc.location, true) {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: the buffer was never bound or used.
                unsafe { s.device.destroy_buffer(raw, None) };
                return Err(e);
            }
        };
        // SAFETY: fresh allocation sized and aligned by the buffer's requirements.
        if let Err(e) = unsafe { s.device.bind_buffer_memory(raw, allocation.memory(), allocation.offset()) } {
            // SAFETY: nothing uses either object yet.
            unsafe { s.device.destroy_buffer(raw, None) };
            let _ = s.allocator.lock().unwrap_or_else(|e| e.into_inner()).free(allocation);
            return Err(Error::vk("vkBindBufferMemory", e));
        }
        inc(&s.live.buffers);
        ctx.set_name(raw, desc.name);
        Ok(Buffer {
            raw,
            allocation: Some(allocation),
            size: desc.size,
            usage: desc.usage,
            name: desc.name.to_string(),
            host_read: desc.location == MemoryLocation::GpuToCpu,
            shared: s.clone(),
        })
    }

    /// The mapped bytes of a host-visible buffer.
    /// Device memory bound to it (the allocation, alignment included).
    pub fn memory_bytes(&self) -> u64 {
        self.allocation.as_ref().map_or(0, |a| a.size())
    }

    pub fn mapped(&self) -> Option<&[u8]> {
        self.allocation.as_ref()?.mapped_slice().map(|s| &s[..self.size as usize])
    }

    pub fn mapped_mut(&mut self) -> Option<&mut [u8]> {
        let size = self.size as usize;
        self.allocation.as_mut()?.mapped_slice_mut().map(|s| &mut s[..size])
    }

    pub fn raw(&self) -> vk::Buffer {
        self.raw
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        if let Some(a) = self.allocation.take() {
            self.shared.retire(Garbage::Buffer(self.raw, a));
        }
    }
}

#[derive(Debug, Clone)]
pub struct ImageDesc<'a> {
    pub name: &'a str,
    pub format: vk::Format,
    pub extent: [u32; 2],
    pub mip_levels: u32,
    pub array_layers: u32,
    pub usage: vk::ImageUsageFlags,
}

pub struct Image {
    pub(crate) raw: vk::Image,
    /// The whole image; then one view per mip when it has several (storage
    /// writes address a single mip); last, for depth-stencil formats, a
    /// depth-only view (a sampled view may have one aspect only).
    pub(crate) views: Vec<vk::ImageView>,
    /// `None` for an image made by [`Image::from_raw`]: the VkImage is not
    /// vista's to destroy, only its views.
    allocation: Option<Allocation>,
    pub format: vk::Format,
    pub extent: [u32; 2],
    pub mip_levels: u32,
    pub array_layers: u32,
    pub usage: vk::ImageUsageFlags,
    pub name: String,
    /// Layout of every subresource after the last command recorded for it
    /// (see [`Image::layout`]).
    layout: AtomicI32,
    shared: Arc<Shared>,
}

pub(crate) fn aspect_of(format: vk::Format) -> vk::ImageAspectFlags {
    match format {
        vk::Format::D32_SFLOAT | vk::Format::D16_UNORM => vk::ImageAspectFlags::DEPTH,
        vk::Format::D32_SFLOAT_S8_UINT | vk::Format::D24_UNORM_S8_UINT => {
            vk::ImageAspectFlags::DEPTH | vk::ImageAspectFlags::STENCIL
        }
        _ => vk::ImageAspectFlags::COLOR,
    }
}

/// Whether a depth format has a stencil aspect.
pub fn has_stencil(format: vk::Format) -> bool {
    aspect_of(format).contains(vk::ImageAspectFlags::STENCIL)
}

/// The attachment layout of a depth(-stencil) target: writable, or
/// read-only (the depth then may also be sampled while attached).
pub fn depth_layout(format: vk::Format, read_only: bool) -> vk::ImageLayout {
    match (has_stencil(format), read_only) {
        (true, false) => vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
        (true, true) => vk::ImageLayout::DEPTH_STENCIL_READ_ONLY_OPTIMAL,
        (false, false) => vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
        (false, true) => vk::ImageLayout::DEPTH_READ_ONLY_OPTIMAL,
    }
}

/// The whole image's view; one per mip when it has several (storage writes
/// address a single mip); last, for depth-stencil formats, a depth-only view
/// (a sampled view may have one aspect only). On failure none is left.
fn create_views(
    d: &ash::Device,
    raw: vk::Image,
    desc: &ImageDesc,
) -> std::result::Result<Vec<vk::ImageView>, vk::Result> {
    let view_type = if desc.array_layers > 1 { vk::ImageViewType::TYPE_2D_ARRAY } else { vk::ImageViewType::TYPE_2D };
    let view_info = |base_mip: u32, mips: u32, aspect: vk::ImageAspectFlags| {
        vk::ImageViewCreateInfo::default().image(raw).view_type(view_type).format(desc.format).subresource_range(
            vk::ImageSubresourceRange::default()
                .aspect_mask(aspect)
                .base_mip_level(base_mip)
                .level_count(mips)
                .layer_count(desc.array_layers),
        )
    };
    let aspect = aspect_of(desc.format);
    let mut infos = vec![view_info(0, desc.mip_levels, aspect)];
    if desc.mip_levels > 1 {
        infos.extend((0..desc.mip_levels).map(|m| view_info(m, 1, aspect)));
    }
    if has_stencil(desc.format) {
        infos.push(view_info(0, desc.mip_levels, vk::ImageAspectFlags::DEPTH));
    }
    let mut views = Vec::with_capacity(infos.len());
    for info in &infos {
        // SAFETY: the image is bound (or owned by the caller); the view
        // covers existing subresources.
        match unsafe { d.create_image_view(info, None) } {
            Ok(v) => views.push(v),
            Err(e) => {
                // SAFETY: nothing uses these views yet.
                views.iter().for_each(|v| unsafe { d.destroy_image_view(*v, None) });
                return Err(e);
            }
        }
    }
    Ok(views)
}

impl Image {
    /// Wraps an image someone else created and owns (an engine's target, a
    /// swapchain image): vista makes and destroys only its views, tracks its
    /// layout from `layout` on, and never frees it.
    ///
    /// # Safety
    /// `raw` must be a live image of `ctx`'s device created with `desc`'s
    /// format, extent, mips, layers and usage (at least), 2D, one sample,
    /// optimal tiling, every subresource in `layout` once the commands
    /// recorded so far execute, and it must outlive the returned `Image`
    /// and every frame that uses it.
    pub unsafe fn from_raw(ctx: &Context, raw: vk::Image, desc: &ImageDesc, layout: vk::ImageLayout) -> Result<Image> {
        let s = &ctx.shared;
        let views = create_views(&s.device, raw, desc).map_err(vk_err("vkCreateImageView"))?;
        inc(&s.live.images);
        views.iter().for_each(|v| ctx.set_name(*v, desc.name));
        Ok(Image::assemble(s, raw, views, None, desc, layout))
    }

    /// Vista's own image when it has an allocation, else someone else's.
    fn assemble(
        s: &Arc<Shared>,
        raw: vk::Image,
        views: Vec<vk::ImageView>,
        allocation: Option<Allocation>,
        desc: &ImageDesc,
        layout: vk::ImageLayout,
    ) -> Image {
        Image {
            raw,
            views,
            allocation,
            format: desc.format,
            extent: desc.extent,
            mip_levels: desc.mip_levels,
            array_layers: desc.array_layers,
            usage: desc.usage,
            name: desc.name.to_string(),
            layout: AtomicI32::new(layout.as_raw()),
            shared: s.clone(),
        }
    }

    /// The layout every subresource is in once the commands recorded so far
    /// have executed. The recorder sets it on each transition and checks it
    /// wherever a command needs a layout. It follows recording order, which
    /// is submission order on vista's queues: a command buffer recorded and
    /// then dropped unsubmitted leaves it wrong (a programmer error).
    pub fn layout(&self) -> vk::ImageLayout {
        vk::ImageLayout::from_raw(self.layout.load(Ordering::Relaxed))
    }

    /// Tells the tracker that commands recorded outside vista's recorder
    /// (an engine's own barriers) leave the image in `layout`.
    ///
    /// # Safety
    /// Once the commands recorded so far execute, every subresource of the
    /// image must be in `layout`; vista's checks and barriers rely on it.
    pub unsafe fn assume_layout(&self, layout: vk::ImageLayout) {
        self.set_layout(layout);
    }

    pub(crate) fn set_layout(&self, layout: vk::ImageLayout) {
        self.layout.store(layout.as_raw(), Ordering::Relaxed);
    }

    pub fn new(ctx: &Context, desc: &ImageDesc) -> Result<Image> {
        let max = ctx.info().limits.max_image_dimension_2d;
        let [w, h] = desc.extent;
        if w == 0 || h == 0 || w > max || h > max || desc.mip_levels == 0 || desc.array_layers == 0 {
            return Err(Error::BadInput(format!(
                "image {:?}: extent {w}x{h}, {} mips, {} layers (max side {max})",
                desc.name, desc.mip_levels, desc.array_layers
            )));
        }
        let s = &ctx.shared;
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(desc.format)
            .extent(vk::Extent3D { width: w, height: h, depth: 1 })
            .mip_levels(desc.mip_levels)
            .array_layers(desc.array_layers)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(desc.usage)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        let families = s.concurrent_families();
        let info = match &families {
            Some(f) => info.sharing_mode(vk::SharingMode::CONCURRENT).queue_family_indices(f),
            None => info.sharing_mode(vk::SharingMode::EXCLUSIVE),
        };
        // SAFETY: valid device and create info.
        let raw = unsafe { s.device.create_image(&info, None) }.map_err(vk_err("vkCreateImage"))?;
        // SAFETY: raw is a live image of this device.
        let req = unsafe { s.device.get_image_memory_requirements(raw) };
        let allocation = match allocate(s, desc.name, req, MemoryLocation::GpuOnly, false) {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: never bound or used.
                unsafe { s.device.destroy_image(raw, None) };
                return Err(e);
            }
        };
        // SAFETY: binding a fresh allocation sized by the image's requirements.
        let bound = unsafe { s.device.bind_image_memory(raw, allocation.memory(), allocation.offset()) };
        let views = bound.and_then(|()| create_views(&s.device, raw, desc));
        let views = match views {
            Ok(v) => v,
            Err(e) => {
                // SAFETY: nothing uses the image yet; its views are gone.
                unsafe { s.device.destroy_image(raw, None) };
                let _ = s.allocator.lock().unwrap_or_else(|e| e.into_inner()).free(allocation);
                return Err(Error::vk("vkBindImageMemory/vkCreateImageView", e));
            }
        };
        inc(&s.live.images);
        ctx.set_name(raw, desc.name);
        views.iter().for_each(|v| ctx.set_name(*v, desc.name));
        Ok(Image::assemble(s, raw, views, Some(allocation), desc, vk::ImageLayout::UNDEFINED))
    }

    /// Device memory bound to it (the allocation, alignment included).
    pub fn memory_bytes(&self) -> u64 {
        self.allocation.as_ref().map_or(0, |a| a.size())
    }

    pub fn raw(&self) -> vk::Image {
        self.raw
    }

    /// View of every mip and layer.
    pub fn view(&self) -> vk::ImageView {
        self.views[0]
    }

    /// The view shaders sample: every mip and layer, the depth aspect only
    /// for depth-stencil formats.
    pub fn sample_view(&self) -> vk::ImageView {
        if has_stencil(self.format) {
            *self.views.last().expect("depth-stencil images have a depth view")
        } else {
            self.views[0]
        }
    }

    /// View of one mip (all layers).
    pub fn mip_view(&self, mip: u32) -> vk::ImageView {
        assert!(mip < self.mip_levels, "{}: mip {mip} of {}", self.name, self.mip_levels);
        if self.mip_levels == 1 {
            self.views[0]
        } else {
            self.views[1 + mip as usize]
        }
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        let views = std::mem::take(&mut self.views);
        self.shared.retire(Garbage::Image(self.raw, views, self.allocation.take()));
    }
}

#[derive(Debug, Clone)]
pub struct SamplerDesc<'a> {
    pub name: &'a str,
    pub filter: vk::Filter,
    pub address_mode: vk::SamplerAddressMode,
}

pub struct Sampler {
    pub(crate) raw: vk::Sampler,
    shared: Arc<Shared>,
}

impl Sampler {
    pub fn new(ctx: &Context, desc: &SamplerDesc) -> Result<Sampler> {
        Self::create(ctx, desc, vk::SamplerMipmapMode::NEAREST)
    }

    /// Like `new`, filtering between mips too (trilinear with LINEAR).
    pub fn mipmapped(ctx: &Context, desc: &SamplerDesc) -> Result<Sampler> {
        Self::create(ctx, desc, vk::SamplerMipmapMode::LINEAR)
    }

    fn create(ctx: &Context, desc: &SamplerDesc, mipmap: vk::SamplerMipmapMode) -> Result<Sampler> {
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(desc.filter)
            .min_filter(desc.filter)
            .mipmap_mode(mipmap)
            .address_mode_u(desc.address_mode)
            .address_mode_v(desc.address_mode)
            .address_mode_w(desc.address_mode)
            .max_lod(vk::LOD_CLAMP_NONE);
        // SAFETY: valid device and create info.
        let raw = unsafe { ctx.shared.device.create_sampler(&info, None) }.map_err(vk_err("vkCreateSampler"))?;
        inc(&ctx.shared.live.samplers);
        ctx.set_name(raw, desc.name);
        Ok(Sampler { raw, shared: ctx.shared.clone() })
    }

    pub fn raw(&self) -> vk::Sampler {
        self.raw
    }
}

impl Drop for Sampler {
    fn drop(&mut self) {
        self.shared.retire(Garbage::Sampler(self.raw));
    }
}

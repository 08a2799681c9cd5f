//! The engine's render targets, made by the engine and lent to vista for
//! the output the run asks for: the display image (LDR, what the engine
//! presents), a float HDR target (`--output hdr`), a G-buffer of two
//! images (`--output gbuffer`: base colour + roughness in RGBA8 sRGB, the
//! world normal as a 10-bit vector) and a depth-stencil target (vista sets
//! stencil bit 0 on terrain pixels, which the engine counts).

use ash::vk;
use vista::passes::terrain_geometry::{DepthOptions, COLOR_FORMAT};
use vista::targets::{Channel, GbufferAttachment, GbufferLayout, NormalEncoding};

pub const SIZE: [u32; 2] = [640, 360];
pub const EXTENT: vk::Extent2D = vk::Extent2D { width: SIZE[0], height: SIZE[1] };
pub const HDR_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
/// The engine's depth: reversed-Z float depth with a stencil, loaded by
/// vista (the engine draws its occluder first), terrain stencil bit 0.
pub const DEPTH: DepthOptions =
    DepthOptions { format: vk::Format::D32_SFLOAT_S8_UINT, terrain_stencil_bit: Some(0), load: true };
pub const TERRAIN_BIT: u8 = 1;

/// Sampled by the engine's own lighting or tonemap pass, written by vista
/// or the engine as attachments, copied from for the screenshot.
pub const COLOR_USAGE: vk::ImageUsageFlags = vk::ImageUsageFlags::from_raw(
    vk::ImageUsageFlags::COLOR_ATTACHMENT.as_raw()
        | vk::ImageUsageFlags::SAMPLED.as_raw()
        | vk::ImageUsageFlags::TRANSFER_SRC.as_raw(),
);
/// Sampled by vista (its tile shading and depth pyramid) and by the
/// engine's lighting; its stencil copied out to count terrain pixels.
pub const DEPTH_USAGE: vk::ImageUsageFlags = vk::ImageUsageFlags::from_raw(
    vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT.as_raw()
        | vk::ImageUsageFlags::SAMPLED.as_raw()
        | vk::ImageUsageFlags::TRANSFER_SRC.as_raw(),
);

/// The engine's G-buffer, as it tells vista (`Output::Gbuffer`).
pub fn gbuffer_layout() -> GbufferLayout {
    use Channel::*;
    let attachment = |name: &str, format, channels| GbufferAttachment { name: name.into(), format, channels };
    GbufferLayout {
        attachments: vec![
            attachment("engine_base_roughness", vk::Format::R8G8B8A8_SRGB, [BaseR, BaseG, BaseB, Roughness]),
            attachment("engine_normal", vk::Format::A2B10G10R10_UNORM_PACK32, [NormalX, NormalY, NormalZ, Zero]),
        ],
        normal: NormalEncoding::Vector,
    }
}

/// What vista writes this run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    Lit,
    Hdr,
    Gbuffer,
}

pub struct Target {
    pub image: vk::Image,
    memory: vk::DeviceMemory,
    /// The whole image (a depth-stencil's both aspects).
    pub view: vk::ImageView,
    /// What a shader samples (a depth-stencil's depth aspect).
    pub sampled: vk::ImageView,
    pub format: vk::Format,
}

/// Every image the engine renders into; which vista writes depends on the
/// mode (`ldr` itself with `lit`, `hdr` with `hdr`, `gbuffer` with
/// `gbuffer`; the depth in every mode).
pub struct Targets {
    pub ldr: Target,
    pub hdr: Option<Target>,
    pub gbuffer: Vec<Target>,
    pub depth: Target,
}

impl Targets {
    /// # Safety
    /// `d` is the engine's device, `mem` its memory properties.
    pub unsafe fn new(d: &ash::Device, mem: &vk::PhysicalDeviceMemoryProperties, mode: Mode) -> Result<Self, String> {
        let colour = |format| unsafe { target(d, mem, format, COLOR_USAGE, vk::ImageAspectFlags::COLOR) };
        let depth_aspects = vk::ImageAspectFlags::DEPTH | vk::ImageAspectFlags::STENCIL;
        Ok(Targets {
            ldr: colour(COLOR_FORMAT)?,
            hdr: if mode == Mode::Hdr { Some(colour(HDR_FORMAT)?) } else { None },
            gbuffer: match mode {
                Mode::Gbuffer => gbuffer_layout().formats().into_iter().map(colour).collect::<Result<_, _>>()?,
                _ => Vec::new(),
            },
            depth: unsafe { target(d, mem, DEPTH.format, DEPTH_USAGE, depth_aspects)? },
        })
    }

    /// The colour images the engine's pass before vista draws into.
    pub fn engine_colours(&self, mode: Mode) -> Vec<&Target> {
        match mode {
            Mode::Lit => vec![&self.ldr],
            Mode::Hdr => self.hdr.iter().collect(),
            Mode::Gbuffer => self.gbuffer.iter().collect(),
        }
    }

    pub fn all(&self) -> impl Iterator<Item = &Target> {
        std::iter::once(&self.ldr).chain(&self.hdr).chain(&self.gbuffer).chain(std::iter::once(&self.depth))
    }

    /// # Safety
    /// The device is idle; each target is destroyed once.
    pub unsafe fn destroy(&self, d: &ash::Device) {
        for t in self.all() {
            unsafe {
                if t.sampled != t.view {
                    d.destroy_image_view(t.sampled, None);
                }
                d.destroy_image_view(t.view, None);
                d.destroy_image(t.image, None);
                d.free_memory(t.memory, None);
            }
        }
    }
}

/// # Safety
/// `d` is a live device with memory properties `mem`.
pub unsafe fn allocate(
    d: &ash::Device,
    mem: &vk::PhysicalDeviceMemoryProperties,
    req: vk::MemoryRequirements,
    flags: vk::MemoryPropertyFlags,
) -> Result<vk::DeviceMemory, String> {
    let index = (0..mem.memory_type_count)
        .find(|&i| req.memory_type_bits & (1 << i) != 0 && mem.memory_types[i as usize].property_flags.contains(flags))
        .ok_or("no memory type")?;
    let info = vk::MemoryAllocateInfo::default().allocation_size(req.size).memory_type_index(index);
    // SAFETY: valid device and allocate info.
    unsafe { d.allocate_memory(&info, None) }.map_err(|x| x.to_string())
}

unsafe fn target(
    d: &ash::Device,
    mem: &vk::PhysicalDeviceMemoryProperties,
    format: vk::Format,
    usage: vk::ImageUsageFlags,
    aspect: vk::ImageAspectFlags,
) -> Result<Target, String> {
    let info = vk::ImageCreateInfo::default()
        .image_type(vk::ImageType::TYPE_2D)
        .format(format)
        .extent(vk::Extent3D { width: SIZE[0], height: SIZE[1], depth: 1 })
        .mip_levels(1)
        .array_layers(1)
        .samples(vk::SampleCountFlags::TYPE_1)
        .tiling(vk::ImageTiling::OPTIMAL)
        .usage(usage);
    // SAFETY: plain creation, binding and viewing of the engine's image.
    unsafe {
        let image = d.create_image(&info, None).map_err(|x| x.to_string())?;
        let memory = allocate(d, mem, d.get_image_memory_requirements(image), vk::MemoryPropertyFlags::DEVICE_LOCAL)?;
        d.bind_image_memory(image, memory, 0).map_err(|x| x.to_string())?;
        let view_of = |aspect| {
            let range = vk::ImageSubresourceRange::default().aspect_mask(aspect).level_count(1).layer_count(1);
            let vi = vk::ImageViewCreateInfo::default()
                .image(image)
                .view_type(vk::ImageViewType::TYPE_2D)
                .format(format)
                .subresource_range(range);
            d.create_image_view(&vi, None).map_err(|x| x.to_string())
        };
        let view = view_of(aspect)?;
        // A shader samples one aspect of a depth-stencil image.
        let sampled =
            if aspect.contains(vk::ImageAspectFlags::DEPTH) { view_of(vk::ImageAspectFlags::DEPTH)? } else { view };
        Ok(Target { image, memory, view, sampled, format })
    }
}

/// The layout a target rests in between frames and passes: what vista is
/// told (and gives back).
pub fn rest_layout(t: &Target) -> vk::ImageLayout {
    if t.sampled != t.view {
        vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL
    } else {
        vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL
    }
}

/// A target's layout change, all of it (both aspects of the depth).
///
/// # Safety
/// `cmd` is recording outside a rendering scope; `old` is the target's layout.
pub unsafe fn transition(
    d: &ash::Device,
    cmd: vk::CommandBuffer,
    t: &Target,
    old: vk::ImageLayout,
    new: vk::ImageLayout,
) {
    let aspect = if t.sampled != t.view {
        vk::ImageAspectFlags::DEPTH | vk::ImageAspectFlags::STENCIL
    } else {
        vk::ImageAspectFlags::COLOR
    };
    // SAFETY: as the caller promises.
    unsafe { barrier(d, cmd, t.image, aspect, old, new) };
}

/// A full barrier with an image's layout change (one mip, one layer).
///
/// # Safety
/// `cmd` is recording outside a rendering scope; `old` is the image's layout.
pub unsafe fn barrier(
    d: &ash::Device,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    aspect: vk::ImageAspectFlags,
    old: vk::ImageLayout,
    new: vk::ImageLayout,
) {
    let range = vk::ImageSubresourceRange::default().aspect_mask(aspect).level_count(1).layer_count(1);
    let ib = [vk::ImageMemoryBarrier2::default()
        .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
        .src_access_mask(vk::AccessFlags2::MEMORY_WRITE)
        .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
        .dst_access_mask(vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE)
        .old_layout(old)
        .new_layout(new)
        .image(image)
        .subresource_range(range)];
    // SAFETY: the caller records into `cmd` and names the image's layout.
    unsafe { d.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&ib)) };
}

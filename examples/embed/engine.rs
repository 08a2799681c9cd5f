//! The engine's side: its own Vulkan objects, made and destroyed here, none
//! of them vista's. Two frames in flight; the queue behind a mutex the
//! engine owns (vista submits through `submitter`, never by itself).

use ash::vk;
use std::ffi::{c_void, CStr};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use vista::gpu::Context;
use vista::passes::terrain_geometry::{DepthOptions, COLOR_FORMAT};
use vista::render::View;
use vista::world::{HeightSource, WorldDesc};
use winit::raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use winit::window::Window;

pub const SIZE: [u32; 2] = [640, 360];
pub const COLOR_USAGE: vk::ImageUsageFlags = vk::ImageUsageFlags::from_raw(
    vk::ImageUsageFlags::COLOR_ATTACHMENT.as_raw() | vk::ImageUsageFlags::TRANSFER_SRC.as_raw(),
);
/// Sampled: vista's occlusion culling reads the depth.
pub const DEPTH_USAGE: vk::ImageUsageFlags = vk::ImageUsageFlags::from_raw(
    vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT.as_raw() | vk::ImageUsageFlags::SAMPLED.as_raw(),
);
/// The engine's depth: depth-only, as many engines use; vista is told so
/// (`DepthOptions`, no stencil bit) and draws into it in this layout.
pub const DEPTH: DepthOptions = DepthOptions { format: vk::Format::D32_SFLOAT, terrain_stencil_bit: None, load: false };
const DEPTH_LAYOUT: vk::ImageLayout = vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL;
const FRAMES: usize = 2;
const EXTENT: vk::Extent2D = vk::Extent2D { width: SIZE[0], height: SIZE[1] };

pub struct Target {
    pub image: vk::Image,
    memory: vk::DeviceMemory,
    view: vk::ImageView,
}

pub struct Readback {
    buffer: vk::Buffer,
    memory: vk::DeviceMemory,
}

/// Push constants of the marker: its clip-space centre and half size (NDC).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Marker {
    clip: [f32; 4],
    half: [f32; 2],
    pad: [f32; 2],
}

pub struct Engine {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    pub physical: vk::PhysicalDevice,
    pub device: ash::Device,
    pub family: u32,
    queue: Arc<Mutex<vk::Queue>>,
    messenger: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT, Box<AtomicU64>)>,
    surface_fn: ash::khr::surface::Instance,
    surface: vk::SurfaceKHR,
    swapchain_fn: ash::khr::swapchain::Device,
    swapchain: vk::SwapchainKHR,
    images: Vec<vk::Image>,
    bgra: bool,
    pool: vk::CommandPool,
    pub cmds: Vec<vk::CommandBuffer>,
    fences: Vec<vk::Fence>,
    acquired: Vec<vk::Semaphore>,
    rendered: Vec<vk::Semaphore>,
    /// vista's frame number of each slot's last submission.
    frame_of: Vec<u64>,
    next: usize,
    pub color: Target,
    pub depth: Target,
    marker: (vk::PipelineLayout, vk::Pipeline),
}

/// Counts the validation layer's messages (and prints them).
unsafe extern "system" fn on_message(
    _severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    count: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: the layer passes valid data; `count` is the engine's counter,
    // alive until the messenger is destroyed.
    unsafe {
        (*(count as *const AtomicU64)).fetch_add(1, Ordering::AcqRel);
        eprintln!("validation: {:?}", (*data).message_as_c_str());
    }
    vk::FALSE
}

impl Engine {
    pub fn new(window: &Window, validation: bool) -> Result<Engine, String> {
        let e = |what: &str| {
            let what = what.to_string();
            move |r: vk::Result| format!("{what}: {r}")
        };
        // SAFETY: this block is the engine: plain Vulkan object creation in
        // order, each create info pointing at locals that outlive the call.
        unsafe {
            let entry = ash::Entry::load().map_err(|x| format!("Vulkan loader: {x}"))?;
            let display = window.display_handle().map_err(|x| x.to_string())?.as_raw();
            let mut exts =
                ash_window::enumerate_required_extensions(display).map_err(e("surface extensions"))?.to_vec();
            let layers = [c"VK_LAYER_KHRONOS_validation".as_ptr()];
            if validation {
                exts.push(ash::ext::debug_utils::NAME.as_ptr());
            }
            let app = vk::ApplicationInfo::default().application_name(c"embed").api_version(vk::API_VERSION_1_3);
            let mut info = vk::InstanceCreateInfo::default().application_info(&app).enabled_extension_names(&exts);
            if validation {
                info = info.enabled_layer_names(&layers);
            }
            let instance = entry.create_instance(&info, None).map_err(e("vkCreateInstance"))?;
            let messenger = if validation {
                let du = ash::ext::debug_utils::Instance::new(&entry, &instance);
                let count = Box::new(AtomicU64::new(0));
                let mi = vk::DebugUtilsMessengerCreateInfoEXT::default()
                    .message_severity(
                        vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
                    )
                    .message_type(
                        vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
                    )
                    .pfn_user_callback(Some(on_message))
                    .user_data(&*count as *const AtomicU64 as *mut c_void);
                let m = du.create_debug_utils_messenger(&mi, None).map_err(e("vkCreateDebugUtilsMessengerEXT"))?;
                Some((du, m, count))
            } else {
                None
            };
            let surface_fn = ash::khr::surface::Instance::new(&entry, &instance);
            let raw_window = window.window_handle().map_err(|x| x.to_string())?.as_raw();
            let surface =
                ash_window::create_surface(&entry, &instance, display, raw_window, None).map_err(e("surface"))?;
            let physical = instance.enumerate_physical_devices().map_err(e("devices"))?[0];
            let family = instance
                .get_physical_device_queue_family_properties(physical)
                .iter()
                .position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE))
                .ok_or("no graphics queue")? as u32;
            if !surface_fn.get_physical_device_surface_support(physical, family, surface).map_err(e("support"))? {
                return Err("the graphics queue cannot present".into());
            }
            // vista's extensions and features, and the swapchain for ourselves.
            let mut dexts: Vec<_> = vista::gpu::REQUIRED_DEVICE_EXTENSIONS.iter().map(|x| x.as_ptr()).collect();
            dexts.push(ash::khr::swapchain::NAME.as_ptr());
            let mut feats = vista::gpu::required_features();
            let prio = [1.0];
            let qi = [vk::DeviceQueueCreateInfo::default().queue_family_index(family).queue_priorities(&prio)];
            let di = vk::DeviceCreateInfo::default()
                .queue_create_infos(&qi)
                .enabled_extension_names(&dexts)
                .enabled_features(&feats.core)
                .push_next(&mut feats.v12)
                .push_next(&mut feats.v13);
            let device = instance.create_device(physical, &di, None).map_err(e("vkCreateDevice"))?;
            let queue = device.get_device_queue(family, 0);
            let swapchain_fn = ash::khr::swapchain::Device::new(&instance, &device);
            let formats = surface_fn.get_physical_device_surface_formats(physical, surface).map_err(e("formats"))?;
            let bgra = formats.iter().any(|f| f.format == vk::Format::B8G8R8A8_UNORM);
            let format = if bgra { vk::Format::B8G8R8A8_UNORM } else { vk::Format::R8G8B8A8_UNORM };
            let caps = surface_fn.get_physical_device_surface_capabilities(physical, surface).map_err(e("caps"))?;
            let sci = vk::SwapchainCreateInfoKHR::default()
                .surface(surface)
                .min_image_count(caps.min_image_count.max(2))
                .image_format(format)
                .image_color_space(vk::ColorSpaceKHR::SRGB_NONLINEAR)
                .image_extent(EXTENT)
                .image_array_layers(1)
                .image_usage(vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::TRANSFER_SRC)
                .pre_transform(caps.current_transform)
                .composite_alpha(vk::CompositeAlphaFlagsKHR::OPAQUE)
                .present_mode(vk::PresentModeKHR::FIFO)
                .clipped(true);
            let swapchain = swapchain_fn.create_swapchain(&sci, None).map_err(e("vkCreateSwapchainKHR"))?;
            let images = swapchain_fn.get_swapchain_images(swapchain).map_err(e("swapchain images"))?;
            let pool = device
                .create_command_pool(
                    &vk::CommandPoolCreateInfo::default()
                        .queue_family_index(family)
                        .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                    None,
                )
                .map_err(e("pool"))?;
            let cmds = device
                .allocate_command_buffers(
                    &vk::CommandBufferAllocateInfo::default().command_pool(pool).command_buffer_count(FRAMES as u32),
                )
                .map_err(e("command buffers"))?;
            let signalled = vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED);
            let sem = || device.create_semaphore(&vk::SemaphoreCreateInfo::default(), None);
            let fences = (0..FRAMES).map(|_| device.create_fence(&signalled, None)).collect::<Result<_, _>>();
            let acquired = (0..FRAMES).map(|_| sem()).collect::<Result<_, _>>().map_err(e("semaphores"))?;
            let rendered = images.iter().map(|_| sem()).collect::<Result<_, _>>().map_err(e("semaphores"))?;
            let mem = instance.get_physical_device_memory_properties(physical);
            let color = target(&device, &mem, COLOR_FORMAT, COLOR_USAGE, vk::ImageAspectFlags::COLOR)?;
            let depth = target(&device, &mem, DEPTH.format, DEPTH_USAGE, vk::ImageAspectFlags::DEPTH)?;
            let marker = marker_pipeline(&device)?;
            Ok(Engine {
                entry,
                instance,
                physical,
                device,
                family,
                queue: Arc::new(Mutex::new(queue)),
                messenger,
                surface_fn,
                surface,
                swapchain_fn,
                swapchain,
                images,
                bgra,
                pool,
                cmds,
                fences: fences.map_err(e("fences"))?,
                acquired,
                rendered,
                frame_of: vec![0; FRAMES],
                next: 0,
                color,
                depth,
                marker,
            })
        }
    }

    pub fn queue(&self) -> vk::Queue {
        *self.queue.lock().unwrap()
    }

    /// How vista submits: on the engine's queue, under the engine's lock.
    pub fn submitter(&self) -> vista::gpu::Submitter {
        let (device, queue) = (self.device.clone(), self.queue.clone());
        Box::new(move |q, info, fence| {
            let guard = queue.lock().unwrap();
            assert_eq!(q, *guard, "vista submits to the queue it was given");
            // SAFETY: the queue is externally synchronized by the lock.
            unsafe { device.queue_submit2(*guard, std::slice::from_ref(info), fence) }
        })
    }

    /// Waits for the slot's last frame, acquires an image and begins the
    /// slot's command buffer.
    pub fn begin_frame(&mut self, ctx: &Context) -> Result<Option<(usize, u32)>, String> {
        let slot = self.next;
        // SAFETY: the engine's own objects; the fence's frame is done once
        // it signals, so its command buffer and semaphore are free again.
        unsafe {
            self.device.wait_for_fences(&[self.fences[slot]], true, u64::MAX).map_err(|x| x.to_string())?;
            ctx.frame_completed(self.frame_of[slot]);
            let (image, _) = self
                .swapchain_fn
                .acquire_next_image(self.swapchain, u64::MAX, self.acquired[slot], vk::Fence::null())
                .map_err(|x| format!("acquire: {x}"))?;
            self.device.reset_fences(&[self.fences[slot]]).map_err(|x| x.to_string())?;
            let cmd = self.cmds[slot];
            self.device.reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty()).map_err(|x| x.to_string())?;
            self.device.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default()).map_err(|x| x.to_string())?;
            Ok(Some((slot, image)))
        }
    }

    pub fn marker_push(&self, view: &View, world_m: glam::DVec3) -> Marker {
        let rel = world_m - glam::DVec3::from_array(view.camera.position_m);
        let clip = view.view_proj() * rel.extend(1.0);
        Marker { clip: clip.as_vec4().to_array(), half: [0.03, 0.03 * 640.0 / 360.0], pad: [0.0; 2] }
    }

    /// The markers over vista's picture, tested against vista's depth.
    pub fn draw_markers(&self, cmd: vk::CommandBuffer, markers: &[Marker]) {
        let d = &self.device;
        let color = vk::RenderingAttachmentInfo::default()
            .image_view(self.color.view)
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::LOAD)
            .store_op(vk::AttachmentStoreOp::STORE);
        let depth = vk::RenderingAttachmentInfo::default()
            .image_view(self.depth.view)
            .image_layout(DEPTH_LAYOUT)
            .load_op(vk::AttachmentLoadOp::LOAD)
            .store_op(vk::AttachmentStoreOp::STORE);
        let colors = [color];
        let area = vk::Rect2D { offset: vk::Offset2D::default(), extent: EXTENT };
        let info = vk::RenderingInfo::default()
            .render_area(area)
            .layer_count(1)
            .color_attachments(&colors)
            .depth_attachment(&depth);
        let viewport =
            vk::Viewport { width: SIZE[0] as f32, height: SIZE[1] as f32, max_depth: 1.0, ..Default::default() };
        // SAFETY: recording; vista left both targets in these layouts and
        // its passes end in full barriers; the pipeline matches the formats.
        unsafe {
            full_barrier(d, cmd);
            d.cmd_begin_rendering(cmd, &info);
            d.cmd_set_viewport(cmd, 0, &[viewport]);
            d.cmd_set_scissor(cmd, 0, &[area]);
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, self.marker.1);
            for m in markers {
                d.cmd_push_constants(cmd, self.marker.0, vk::ShaderStageFlags::VERTEX, 0, bytemuck::bytes_of(m));
                d.cmd_draw(cmd, 6, 1, 0, 0);
            }
            d.cmd_end_rendering(cmd);
        }
    }

    pub fn readback_buffer(&self) -> Result<Readback, String> {
        let size = u64::from(SIZE[0] * SIZE[1] * 4);
        // SAFETY: plain creation and binding of the engine's own buffer.
        unsafe {
            let buffer = self
                .device
                .create_buffer(
                    &vk::BufferCreateInfo::default().size(size).usage(vk::BufferUsageFlags::TRANSFER_DST),
                    None,
                )
                .map_err(|x| x.to_string())?;
            let req = self.device.get_buffer_memory_requirements(buffer);
            let mem = self.instance.get_physical_device_memory_properties(self.physical);
            let host = vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
            let memory = allocate(&self.device, &mem, req, host)?;
            self.device.bind_buffer_memory(buffer, memory, 0).map_err(|x| x.to_string())?;
            Ok(Readback { buffer, memory })
        }
    }

    /// Blits vista's colour into the swapchain image, copies it for a
    /// screenshot, submits and presents.
    pub fn end_frame(&mut self, ctx: &Context, slot: usize, image: u32, shot: Option<&Readback>) -> Result<(), String> {
        let (d, cmd, swap) = (&self.device, self.cmds[slot], self.images[image as usize]);
        let color = self.color.image;
        let corner = [vk::Offset3D::default(), vk::Offset3D { x: SIZE[0] as i32, y: SIZE[1] as i32, z: 1 }];
        let layer = vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::COLOR).layer_count(1);
        let blit = vk::ImageBlit::default()
            .src_subresource(layer)
            .src_offsets(corner)
            .dst_subresource(layer)
            .dst_offsets(corner);
        use vk::ImageLayout as L;
        // SAFETY: recording since begin_frame; the layouts named are the ones
        // the images are in (vista left the colour in COLOR_ATTACHMENT and
        // gets it back there, as its tracker expects).
        unsafe {
            layout(d, cmd, color, L::COLOR_ATTACHMENT_OPTIMAL, L::TRANSFER_SRC_OPTIMAL);
            layout(d, cmd, swap, L::UNDEFINED, L::TRANSFER_DST_OPTIMAL);
            d.cmd_blit_image(
                cmd,
                color,
                L::TRANSFER_SRC_OPTIMAL,
                swap,
                L::TRANSFER_DST_OPTIMAL,
                &[blit],
                vk::Filter::NEAREST,
            );
            layout(d, cmd, color, L::TRANSFER_SRC_OPTIMAL, L::COLOR_ATTACHMENT_OPTIMAL);
            if let Some(r) = shot {
                layout(d, cmd, swap, L::TRANSFER_DST_OPTIMAL, L::TRANSFER_SRC_OPTIMAL);
                let region = vk::BufferImageCopy::default().image_subresource(layer).image_extent(vk::Extent3D {
                    width: SIZE[0],
                    height: SIZE[1],
                    depth: 1,
                });
                d.cmd_copy_image_to_buffer(cmd, swap, L::TRANSFER_SRC_OPTIMAL, r.buffer, &[region]);
                layout(d, cmd, swap, L::TRANSFER_SRC_OPTIMAL, L::PRESENT_SRC_KHR);
            } else {
                layout(d, cmd, swap, L::TRANSFER_DST_OPTIMAL, L::PRESENT_SRC_KHR);
            }
            d.end_command_buffer(cmd).map_err(|x| x.to_string())?;
            let (cmds, waits, signals) = ([cmd], [self.acquired[slot]], [self.rendered[image as usize]]);
            let stages = [vk::PipelineStageFlags::ALL_COMMANDS];
            let submit = vk::SubmitInfo::default()
                .command_buffers(&cmds)
                .wait_semaphores(&waits)
                .wait_dst_stage_mask(&stages)
                .signal_semaphores(&signals);
            let queue = self.queue.lock().unwrap();
            d.queue_submit(*queue, &[submit], self.fences[slot]).map_err(|x| x.to_string())?;
            self.frame_of[slot] = ctx.frame_submitted();
            let (chains, indices) = ([self.swapchain], [image]);
            let present =
                vk::PresentInfoKHR::default().wait_semaphores(&signals).swapchains(&chains).image_indices(&indices);
            self.swapchain_fn.queue_present(*queue, &present).map_err(|x| format!("present: {x}"))?;
        }
        self.next = (slot + 1) % FRAMES;
        Ok(())
    }

    pub fn wait_idle(&self) {
        let _queue = self.queue.lock().unwrap();
        // SAFETY: all queues are held (the only one, by its lock).
        unsafe { self.device.device_wait_idle() }.expect("vkDeviceWaitIdle");
    }

    /// Writes the screenshot (the engine is idle).
    pub fn write_png(&self, r: &Readback, file: &std::path::Path) -> Result<(), String> {
        let n = (SIZE[0] * SIZE[1] * 4) as usize;
        // SAFETY: host-visible, coherent memory of the engine, idle.
        let mut rgba = unsafe {
            let p = self
                .device
                .map_memory(r.memory, 0, n as u64, vk::MemoryMapFlags::empty())
                .map_err(|x| x.to_string())?;
            let v = std::slice::from_raw_parts(p as *const u8, n).to_vec();
            self.device.unmap_memory(r.memory);
            self.device.destroy_buffer(r.buffer, None);
            self.device.free_memory(r.memory, None);
            v
        };
        if self.bgra {
            rgba.chunks_exact_mut(4).for_each(|p| p.swap(0, 2));
        }
        image::save_buffer(file, &rgba, SIZE[0], SIZE[1], image::ExtendedColorType::Rgba8).map_err(|x| x.to_string())
    }

    /// Destroys everything in reverse order of creation, once vista is gone.
    pub fn destroy(self) {
        self.wait_idle();
        let d = &self.device;
        // SAFETY: idle; each object is destroyed once, children first.
        unsafe {
            d.destroy_pipeline(self.marker.1, None);
            d.destroy_pipeline_layout(self.marker.0, None);
            for t in [&self.color, &self.depth] {
                d.destroy_image_view(t.view, None);
                d.destroy_image(t.image, None);
                d.free_memory(t.memory, None);
            }
            for s in self.acquired.iter().chain(&self.rendered) {
                d.destroy_semaphore(*s, None);
            }
            self.fences.iter().for_each(|f| d.destroy_fence(*f, None));
            d.destroy_command_pool(self.pool, None);
            self.swapchain_fn.destroy_swapchain(self.swapchain, None);
            d.destroy_device(None);
            self.surface_fn.destroy_surface(self.surface, None);
            let mut messages = 0;
            if let Some((du, m, count)) = &self.messenger {
                du.destroy_debug_utils_messenger(*m, None);
                messages = count.load(Ordering::Acquire);
            }
            self.instance.destroy_instance(None);
            if self.messenger.is_some() {
                println!("validation messages: {messages}");
            }
        }
    }
}

/// Where the markers go: one 30 m above the ground a third of the way
/// north (seen), one 100 m under it further east (the terrain hides it
/// wherever the depth test works).
pub fn marker_positions(desc: &WorldDesc, source: &dyn HeightSource) -> [glam::DVec3; 2] {
    let at = |x: f64, y: f64, dz: f64| glam::DVec3::new(x, y, f64::from(source.sample(x, y)) + dz);
    let [ex, ey] = desc.extent_m;
    [at(ex * 0.45, ey * 0.35, 30.0), at(ex * 0.6, ey * 0.3, -100.0)]
}

unsafe fn full_barrier(d: &ash::Device, cmd: vk::CommandBuffer) {
    let mb = [vk::MemoryBarrier2::default()
        .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
        .src_access_mask(vk::AccessFlags2::MEMORY_WRITE)
        .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
        .dst_access_mask(vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE)];
    // SAFETY: the caller records into `cmd`.
    unsafe { d.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&mb)) };
}

unsafe fn layout(
    d: &ash::Device,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    old: vk::ImageLayout,
    new: vk::ImageLayout,
) {
    let range =
        vk::ImageSubresourceRange::default().aspect_mask(vk::ImageAspectFlags::COLOR).level_count(1).layer_count(1);
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

unsafe fn allocate(
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
        let range = vk::ImageSubresourceRange::default().aspect_mask(aspect).level_count(1).layer_count(1);
        let vi = vk::ImageViewCreateInfo::default()
            .image(image)
            .view_type(vk::ImageViewType::TYPE_2D)
            .format(format)
            .subresource_range(range);
        let view = d.create_image_view(&vi, None).map_err(|x| x.to_string())?;
        Ok(Target { image, memory, view })
    }
}

const MARKER_VERT: &str = "#version 450
layout(push_constant) uniform Marker { vec4 clip; vec2 half_size; } m;
void main() {
    vec2 c[6] = vec2[](vec2(-1, -1), vec2(1, -1), vec2(1, 1), vec2(-1, -1), vec2(1, 1), vec2(-1, 1));
    gl_Position = m.clip + vec4(c[gl_VertexIndex] * m.half_size * m.clip.w, 0.0, 0.0);
}";
const MARKER_FRAG: &str = "#version 450
layout(location = 0) out vec4 colour;
void main() { colour = vec4(1.0, 0.0, 1.0, 1.0); }";

fn spirv(text: &str, stage: glslang::ShaderStage) -> Result<Vec<u32>, String> {
    let compiler = glslang::Compiler::acquire().ok_or("glslang")?;
    let source = glslang::ShaderSource::from(text.to_string());
    let options = glslang::CompilerOptions {
        source_language: glslang::SourceLanguage::GLSL,
        target: glslang::Target::Vulkan {
            version: glslang::VulkanVersion::Vulkan1_3,
            spirv_version: glslang::SpirvVersion::SPIRV1_6,
        },
        ..Default::default()
    };
    let input = glslang::ShaderInput::new(&source, stage, &options, None, None).map_err(|e| e.to_string())?;
    compiler.create_shader(input).map_err(|e| e.to_string())?.compile().map_err(|e| e.to_string())
}

/// A quad in clip space, depth tested (reversed-Z: GREATER_OR_EQUAL) and
/// not written; drawn into vista's colour target with vista's depth.
fn marker_pipeline(d: &ash::Device) -> Result<(vk::PipelineLayout, vk::Pipeline), String> {
    let (vs, fs) =
        (spirv(MARKER_VERT, glslang::ShaderStage::Vertex)?, spirv(MARKER_FRAG, glslang::ShaderStage::Fragment)?);
    // SAFETY: plain creation of the engine's pipeline objects.
    unsafe {
        let module = |w: &[u32]| d.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(w), None);
        let (vm, fm) = (module(&vs).map_err(|x| x.to_string())?, module(&fs).map_err(|x| x.to_string())?);
        let range = [vk::PushConstantRange::default().stage_flags(vk::ShaderStageFlags::VERTEX).size(32)];
        let layout = d
            .create_pipeline_layout(&vk::PipelineLayoutCreateInfo::default().push_constant_ranges(&range), None)
            .map_err(|x| x.to_string())?;
        let main: &CStr = c"main";
        let stages = [
            vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::VERTEX).module(vm).name(main),
            vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::FRAGMENT).module(fm).name(main),
        ];
        let vertex = vk::PipelineVertexInputStateCreateInfo::default();
        let assembly =
            vk::PipelineInputAssemblyStateCreateInfo::default().topology(vk::PrimitiveTopology::TRIANGLE_LIST);
        let viewport = vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1);
        let raster = vk::PipelineRasterizationStateCreateInfo::default().line_width(1.0);
        let ms = vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let depth = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(true)
            .depth_compare_op(vk::CompareOp::GREATER_OR_EQUAL);
        let blend = [vk::PipelineColorBlendAttachmentState::default().color_write_mask(vk::ColorComponentFlags::RGBA)];
        let blending = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend);
        let dynamic = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic);
        let formats = [COLOR_FORMAT];
        let mut rendering = vk::PipelineRenderingCreateInfo::default()
            .color_attachment_formats(&formats)
            .depth_attachment_format(DEPTH.format);
        let info = vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vertex)
            .input_assembly_state(&assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&ms)
            .depth_stencil_state(&depth)
            .color_blend_state(&blending)
            .dynamic_state(&dynamic)
            .layout(layout)
            .push_next(&mut rendering);
        let pipeline =
            d.create_graphics_pipelines(vk::PipelineCache::null(), &[info], None).map_err(|(_, x)| x.to_string())?[0];
        d.destroy_shader_module(vm, None);
        d.destroy_shader_module(fm, None);
        Ok((layout, pipeline))
    }
}

//! The engine's side: its own Vulkan objects, made and destroyed here, none
//! of them vista's. Two frames in flight; the queue behind a mutex the
//! engine owns (vista submits through `submitter`, never by itself). A
//! frame: the engine's pass (clears its targets, draws its building into
//! the depth vista then loads), vista, the engine's lighting or tonemap
//! pass (per mode) and its marker, then a blit to the swapchain.

use crate::passes::{BoxPush, LightPush, Marker, Passes};
use crate::setup::{self, vk_err, FrameObjects, Messenger};
use crate::targets::{allocate, barrier, rest_layout, transition, Mode, Target, Targets, EXTENT, SIZE, TERRAIN_BIT};
use ash::vk;
use std::sync::atomic::Ordering;
use std::sync::{Arc, Mutex};
use vista::gpu::Context;
use vista::world::{HeightSource, WorldDesc};
use winit::raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use winit::window::Window;

const FRAMES: usize = 2;

pub struct Readback {
    buffer: vk::Buffer,
    memory: vk::DeviceMemory,
}

pub struct Engine {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    pub physical: vk::PhysicalDevice,
    pub device: ash::Device,
    pub family: u32,
    queue: Arc<Mutex<vk::Queue>>,
    messenger: Option<Messenger>,
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
    pub mode: Mode,
    pub targets: Targets,
    passes: Passes,
}

impl Engine {
    pub fn new(window: &Window, validation: bool, mode: Mode) -> Result<Engine, String> {
        let e = vk_err;
        // SAFETY: this block is the engine: plain Vulkan object creation in
        // order (setup.rs), each from the live objects made before it.
        unsafe {
            let entry = ash::Entry::load().map_err(|x| format!("Vulkan loader: {x}"))?;
            let display = window.display_handle().map_err(|x| x.to_string())?.as_raw();
            let instance = setup::instance(&entry, display, validation)?;
            let messenger = setup::messenger(&entry, &instance, validation)?;
            let surface_fn = ash::khr::surface::Instance::new(&entry, &instance);
            let raw_window = window.window_handle().map_err(|x| x.to_string())?.as_raw();
            let surface =
                ash_window::create_surface(&entry, &instance, display, raw_window, None).map_err(e("surface"))?;
            let (physical, family) = setup::physical_and_family(&instance, &surface_fn, surface)?;
            let device = setup::device(&instance, physical, family)?;
            let queue = device.get_device_queue(family, 0);
            let swapchain_fn = ash::khr::swapchain::Device::new(&instance, &device);
            let (swapchain, images, bgra) = setup::swapchain(&surface_fn, &swapchain_fn, physical, surface)?;
            let FrameObjects { pool, cmds, fences, acquired, rendered } =
                setup::frame_objects(&device, family, FRAMES, images.len())?;
            let mem = instance.get_physical_device_memory_properties(physical);
            let targets = Targets::new(&device, &mem, mode)?;
            let passes = Passes::new(&device, mode, &targets)?;
            let engine = Engine {
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
                fences,
                acquired,
                rendered,
                frame_of: vec![0; FRAMES],
                next: 0,
                mode,
                targets,
                passes,
            };
            engine.rest_layouts()?;
            Ok(engine)
        }
    }

    /// Leaves UNDEFINED for the layouts the targets rest in between frames
    /// (what vista is told they are in).
    fn rest_layouts(&self) -> Result<(), String> {
        self.one_shot(|d, cmd| {
            for t in self.targets.all() {
                // SAFETY: recording the engine's own one-shot buffer.
                unsafe { transition(d, cmd, t, vk::ImageLayout::UNDEFINED, rest_layout(t)) };
            }
        })
    }

    /// Records `f` into a fresh command buffer, submits it and waits.
    fn one_shot(&self, f: impl FnOnce(&ash::Device, vk::CommandBuffer)) -> Result<(), String> {
        let d = &self.device;
        // SAFETY: the engine's pool and queue; the buffer is freed after the wait.
        unsafe {
            let info = vk::CommandBufferAllocateInfo::default().command_pool(self.pool).command_buffer_count(1);
            let cmd = d.allocate_command_buffers(&info).map_err(|x| x.to_string())?[0];
            d.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default()).map_err(|x| x.to_string())?;
            f(d, cmd);
            d.end_command_buffer(cmd).map_err(|x| x.to_string())?;
            let cmds = [cmd];
            let submit = vk::SubmitInfo::default().command_buffers(&cmds);
            {
                let queue = self.queue.lock().unwrap();
                d.queue_submit(*queue, &[submit], vk::Fence::null()).map_err(|x| x.to_string())?;
                d.queue_wait_idle(*queue).map_err(|x| x.to_string())?;
            }
            d.free_command_buffers(self.pool, &cmds);
        }
        Ok(())
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

    /// The engine's pass before vista: clears its targets (depth to far,
    /// stencil to 0) and draws its building, when `building` is given.
    pub fn engine_pass(&self, cmd: vk::CommandBuffer, light: &LightPush, building: Option<&BoxPush>) {
        let background = match self.mode {
            Mode::Lit => light.background(),
            // Radiance the tonemap turns into the background colour, near enough.
            Mode::Hdr => light.background().map(|c| c * 0.5),
            // No surface: the lighting pass draws the background by depth.
            Mode::Gbuffer => [0.0; 4],
        };
        let clear = vk::ClearValue { color: vk::ClearColorValue { float32: background } };
        let colours: Vec<_> = self
            .targets
            .engine_colours(self.mode)
            .into_iter()
            .map(|t| attachment(t.view, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, Some(clear)))
            .collect();
        let far = vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 0.0, stencil: 0 } };
        let depth = attachment(self.targets.depth.view, rest_layout(&self.targets.depth), Some(far));
        // SAFETY: recording since begin_frame; the targets rest in these layouts.
        unsafe {
            self.begin_rendering(cmd, &colours, Some(&depth));
            if let Some(b) = building {
                self.passes.draw_building(&self.device, cmd, light, b);
            }
            self.device.cmd_end_rendering(cmd);
            full_barrier(&self.device, cmd);
        }
    }

    /// After vista: the engine lights its G-buffer or tonemaps vista's
    /// radiance into the display image (per mode), then draws its markers
    /// depth-tested against the depth vista wrote; every target rests
    /// again afterwards.
    pub fn after_vista(&self, cmd: vk::CommandBuffer, light: &LightPush, markers: &[Marker]) {
        let (d, t) = (&self.device, &self.targets);
        let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        let depth_read = vk::ImageLayout::DEPTH_STENCIL_READ_ONLY_OPTIMAL;
        let inputs: Vec<&Target> = t.hdr.iter().chain(&t.gbuffer).collect();
        let ldr = attachment(t.ldr.view, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, None);
        let depth = attachment(t.depth.view, depth_read, None);
        // SAFETY: recording since begin_frame; vista's passes end in full
        // barriers and leave the targets in their rest layouts.
        unsafe {
            full_barrier(d, cmd);
            inputs.iter().for_each(|i| transition(d, cmd, i, rest_layout(i), read));
            transition(d, cmd, &t.depth, rest_layout(&t.depth), depth_read);
            self.begin_rendering(cmd, std::slice::from_ref(&ldr), None);
            self.passes.resolve(d, cmd, light);
            d.cmd_end_rendering(cmd);
            full_barrier(d, cmd);
            self.begin_rendering(cmd, std::slice::from_ref(&ldr), Some(&depth));
            self.passes.draw_markers(d, cmd, markers);
            d.cmd_end_rendering(cmd);
            inputs.iter().for_each(|i| transition(d, cmd, i, read, rest_layout(i)));
            transition(d, cmd, &t.depth, depth_read, rest_layout(&t.depth));
        }
    }

    /// # Safety
    /// `cmd` is recording outside a scope; the attachments are in the
    /// layouts they name.
    unsafe fn begin_rendering(
        &self,
        cmd: vk::CommandBuffer,
        colours: &[vk::RenderingAttachmentInfo],
        depth: Option<&vk::RenderingAttachmentInfo>,
    ) {
        let area = vk::Rect2D { offset: vk::Offset2D::default(), extent: EXTENT };
        let mut info = vk::RenderingInfo::default().render_area(area).layer_count(1).color_attachments(colours);
        if let Some(dp) = depth {
            info = info.depth_attachment(dp).stencil_attachment(dp);
        }
        let viewport =
            vk::Viewport { width: SIZE[0] as f32, height: SIZE[1] as f32, max_depth: 1.0, ..Default::default() };
        // SAFETY: as the caller promises.
        unsafe {
            self.device.cmd_begin_rendering(cmd, &info);
            self.device.cmd_set_viewport(cmd, 0, &[viewport]);
            self.device.cmd_set_scissor(cmd, 0, &[area]);
        }
    }

    /// Pixels with vista's terrain stencil bit in the last frame (the
    /// engine is idle).
    pub fn terrain_pixels(&self) -> Result<usize, String> {
        let n = (SIZE[0] * SIZE[1]) as usize;
        let r = self.host_buffer(n as u64)?;
        let depth = &self.targets.depth;
        let stencil = vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::STENCIL).layer_count(1);
        let region = vk::BufferImageCopy::default().image_subresource(stencil).image_extent(vk::Extent3D {
            width: SIZE[0],
            height: SIZE[1],
            depth: 1,
        });
        let src = vk::ImageLayout::TRANSFER_SRC_OPTIMAL;
        self.one_shot(|d, cmd| {
            // SAFETY: the engine's one-shot buffer; the depth rests between frames.
            unsafe {
                transition(d, cmd, depth, rest_layout(depth), src);
                d.cmd_copy_image_to_buffer(cmd, depth.image, src, r.buffer, &[region]);
                transition(d, cmd, depth, src, rest_layout(depth));
            }
        })?;
        let bytes = self.take(r, n)?;
        Ok(bytes.iter().filter(|&&s| s & TERRAIN_BIT != 0).count())
    }

    fn host_buffer(&self, size: u64) -> Result<Readback, String> {
        // SAFETY: the engine's own host-visible buffer.
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

    /// The buffer's first `n` bytes; frees it (the engine is idle).
    fn take(&self, r: Readback, n: usize) -> Result<Vec<u8>, String> {
        // SAFETY: host-visible, coherent memory of the engine, idle.
        unsafe {
            let p = self
                .device
                .map_memory(r.memory, 0, n as u64, vk::MemoryMapFlags::empty())
                .map_err(|x| x.to_string())?;
            let v = std::slice::from_raw_parts(p as *const u8, n).to_vec();
            self.device.unmap_memory(r.memory);
            self.device.destroy_buffer(r.buffer, None);
            self.device.free_memory(r.memory, None);
            Ok(v)
        }
    }

    pub fn readback_buffer(&self) -> Result<Readback, String> {
        self.host_buffer(u64::from(SIZE[0] * SIZE[1] * 4))
    }

    /// Blits the display image into the swapchain image, copies it for a
    /// screenshot, submits and presents.
    pub fn end_frame(&mut self, ctx: &Context, slot: usize, image: u32, shot: Option<&Readback>) -> Result<(), String> {
        let (d, cmd, swap) = (&self.device, self.cmds[slot], self.images[image as usize]);
        let color = self.targets.ldr.image;
        let corner = [vk::Offset3D::default(), vk::Offset3D { x: SIZE[0] as i32, y: SIZE[1] as i32, z: 1 }];
        let layer = vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::COLOR).layer_count(1);
        let blit = vk::ImageBlit::default()
            .src_subresource(layer)
            .src_offsets(corner)
            .dst_subresource(layer)
            .dst_offsets(corner);
        use vk::ImageLayout as L;
        // SAFETY: recording since begin_frame; the layouts named are the ones
        // the images are in (the display image rests in COLOR_ATTACHMENT).
        unsafe {
            colour_layout(d, cmd, color, L::COLOR_ATTACHMENT_OPTIMAL, L::TRANSFER_SRC_OPTIMAL);
            colour_layout(d, cmd, swap, L::UNDEFINED, L::TRANSFER_DST_OPTIMAL);
            d.cmd_blit_image(
                cmd,
                color,
                L::TRANSFER_SRC_OPTIMAL,
                swap,
                L::TRANSFER_DST_OPTIMAL,
                &[blit],
                vk::Filter::NEAREST,
            );
            colour_layout(d, cmd, color, L::TRANSFER_SRC_OPTIMAL, L::COLOR_ATTACHMENT_OPTIMAL);
            if let Some(r) = shot {
                colour_layout(d, cmd, swap, L::TRANSFER_DST_OPTIMAL, L::TRANSFER_SRC_OPTIMAL);
                let region = vk::BufferImageCopy::default().image_subresource(layer).image_extent(vk::Extent3D {
                    width: SIZE[0],
                    height: SIZE[1],
                    depth: 1,
                });
                d.cmd_copy_image_to_buffer(cmd, swap, L::TRANSFER_SRC_OPTIMAL, r.buffer, &[region]);
                colour_layout(d, cmd, swap, L::TRANSFER_SRC_OPTIMAL, L::PRESENT_SRC_KHR);
            } else {
                colour_layout(d, cmd, swap, L::TRANSFER_DST_OPTIMAL, L::PRESENT_SRC_KHR);
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
    pub fn write_png(&self, r: Readback, file: &std::path::Path) -> Result<(), String> {
        let mut rgba = self.take(r, (SIZE[0] * SIZE[1] * 4) as usize)?;
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
            self.passes.destroy(d);
            self.targets.destroy(d);
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

fn attachment(
    view: vk::ImageView,
    layout: vk::ImageLayout,
    clear: Option<vk::ClearValue>,
) -> vk::RenderingAttachmentInfo<'static> {
    vk::RenderingAttachmentInfo::default()
        .image_view(view)
        .image_layout(layout)
        .load_op(if clear.is_some() { vk::AttachmentLoadOp::CLEAR } else { vk::AttachmentLoadOp::LOAD })
        .store_op(vk::AttachmentStoreOp::STORE)
        .clear_value(clear.unwrap_or_default())
}

/// # Safety
/// As `targets::barrier`'s, for a colour image.
unsafe fn colour_layout(
    d: &ash::Device,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    old: vk::ImageLayout,
    new: vk::ImageLayout,
) {
    // SAFETY: as the caller promises.
    unsafe { barrier(d, cmd, image, vk::ImageAspectFlags::COLOR, old, new) };
}

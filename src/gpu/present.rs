//! Presenting to a window (feature `window`): a surface, its swapchain and
//! the binary semaphores that order acquisition, rendering and presentation.
//! The context must have been made with `ContextOptions::display`.
//!
//! Semaphores: one "acquired" semaphore per frame in flight, reused only
//! after [`FrameRing::wait_next`](super::FrameRing::wait_next) saw the frame
//! that waited on it complete; one "rendered" semaphore per swapchain image,
//! signalled by the frame that draws into it and waited on by its
//! presentation (the image is not acquired again before that).
//!
//! Destruction order (`Drop`, and before a swapchain is remade): wait for
//! the device, the images' views, the swapchain, the semaphores, the
//! surface last. A lost surface is remade from the window's handles.

use super::context::{Context, Shared};
use super::resources::{inc, Garbage, Image, ImageDesc};
use super::submit::BinarySync;
use crate::error::{vk_err, Error, Result};
use ash::vk;
use raw_window_handle::{RawDisplayHandle, RawWindowHandle};
use std::sync::Arc;

/// What the swapchain images can be used for: drawn into (an overlay),
/// blitted into (the terrain), read back (a screenshot).
const USAGE: vk::ImageUsageFlags = vk::ImageUsageFlags::from_raw(
    vk::ImageUsageFlags::COLOR_ATTACHMENT.as_raw()
        | vk::ImageUsageFlags::TRANSFER_DST.as_raw()
        | vk::ImageUsageFlags::TRANSFER_SRC.as_raw(),
);

/// A swapchain image acquired for one frame.
pub struct Acquired {
    pub index: u32,
    /// Pass to [`FrameRing::record_synced`](super::FrameRing::record_synced).
    pub sync: BinarySync,
}

pub struct Presenter {
    surface_fn: ash::khr::surface::Instance,
    swapchain_fn: ash::khr::swapchain::Device,
    surface: vk::SurfaceKHR,
    swapchain: vk::SwapchainKHR,
    images: Vec<Image>,
    rendered: Vec<vk::Semaphore>,
    acquired: Vec<vk::Semaphore>,
    next_acquire: usize,
    format: vk::Format,
    extent: [u32; 2],
    vsync: bool,
    /// The window's handles (vouched for in `new`), to remake a lost surface.
    display: RawDisplayHandle,
    window: RawWindowHandle,
    /// Acquiring or presenting said the surface was lost: `resize` makes a
    /// new one.
    lost: bool,
    /// Surfaces made for the window: 1 plus those remade after a loss.
    surfaces: u32,
    shared: Arc<Shared>,
}

impl Presenter {
    /// A surface for the window and a swapchain of `size` (or the window's
    /// own size where the platform fixes it); `frames_in_flight` must be the
    /// depth of the ring that records the frames.
    ///
    /// # Safety
    /// The handles must be those of a live window on the display the
    /// context was made for, and the window must outlive the presenter.
    pub unsafe fn new(
        ctx: &Context,
        display: RawDisplayHandle,
        window: RawWindowHandle,
        size: [u32; 2],
        frames_in_flight: usize,
        vsync: bool,
    ) -> Result<Presenter> {
        let s = &ctx.shared;
        let surface_fn = ash::khr::surface::Instance::new(&s.entry, &s.instance);
        let swapchain_fn = ash::khr::swapchain::Device::new(&s.instance, &s.device);
        // SAFETY: the caller vouches for the handles; the instance has the
        // display's surface extensions (ContextOptions::display).
        let surface = unsafe { ash_window::create_surface(&s.entry, &s.instance, display, window, None) }
            .map_err(vk_err("vkCreate*SurfaceKHR"))?;
        let mut p = Presenter {
            surface_fn,
            swapchain_fn,
            surface,
            swapchain: vk::SwapchainKHR::null(),
            images: Vec::new(),
            rendered: Vec::new(),
            acquired: Vec::new(),
            next_acquire: 0,
            format: vk::Format::UNDEFINED,
            extent: [0, 0],
            vsync,
            display,
            window,
            lost: false,
            surfaces: 1,
            shared: s.clone(),
        };
        // SAFETY: live surface and physical device of this instance.
        let supported =
            unsafe { p.surface_fn.get_physical_device_surface_support(s.physical, s.graphics.family, surface) }
                .map_err(vk_err("vkGetPhysicalDeviceSurfaceSupportKHR"))?;
        if !supported {
            return Err(Error::Unsupported(format!(
                "queue family {} of {} cannot present to this window",
                s.graphics.family,
                ctx.info().name
            )));
        }
        for i in 0..frames_in_flight {
            p.acquired.push(semaphore(ctx, &format!("swapchain_acquired[{i}]"))?);
        }
        p.resize(ctx, size)?;
        Ok(p)
    }

    /// The swapchain's colour format (a UNORM one where offered, so a blit
    /// of vista's UNORM image keeps its values).
    pub fn format(&self) -> vk::Format {
        self.format
    }

    /// The swapchain's size; [0, 0] while the window is minimised.
    pub fn extent(&self) -> [u32; 2] {
        self.extent
    }

    /// Surfaces made for the window so far: 1, plus one for each loss.
    pub fn surfaces_made(&self) -> u32 {
        self.surfaces
    }

    pub fn image(&self, index: u32) -> &Image {
        &self.images[index as usize]
    }

    /// Remakes the swapchain for `size` (after a resize, or when acquiring
    /// or presenting said it is out of date), and the surface first when it
    /// was lost. Waits for the device.
    pub fn resize(&mut self, ctx: &Context, size: [u32; 2]) -> Result<()> {
        if self.lost {
            self.remake_surface(ctx)?;
        }
        let s = &ctx.shared;
        // SAFETY: live surface and physical device of this instance.
        let caps = unsafe { self.surface_fn.get_physical_device_surface_capabilities(s.physical, self.surface) }
            .map_err(vk_err("vkGetPhysicalDeviceSurfaceCapabilitiesKHR"))?;
        let extent = if caps.current_extent.width != u32::MAX {
            [caps.current_extent.width, caps.current_extent.height]
        } else {
            [
                size[0].clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                size[1].clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            ]
        };
        ctx.wait_idle()?;
        self.release_images();
        if extent[0] == 0 || extent[1] == 0 {
            // Minimised: no swapchain can have this size; keep the old one
            // out of use until the window comes back.
            self.extent = [0, 0];
            return Ok(());
        }
        if !caps.supported_usage_flags.contains(USAGE) {
            return Err(Error::Unsupported(format!(
                "the window's swapchain cannot be used for {USAGE:?} (offers {:?})",
                caps.supported_usage_flags
            )));
        }
        let format = self.pick_format(ctx)?;
        let mode = self.pick_mode(ctx)?;
        let count =
            (caps.min_image_count + 1).min(if caps.max_image_count == 0 { u32::MAX } else { caps.max_image_count });
        let old = self.swapchain;
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(self.surface)
            .min_image_count(count)
            .image_format(format.format)
            .image_color_space(format.color_space)
            .image_extent(vk::Extent2D { width: extent[0], height: extent[1] })
            .image_array_layers(1)
            .image_usage(USAGE)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(vk::CompositeAlphaFlagsKHR::OPAQUE)
            .present_mode(mode)
            .clipped(true)
            .old_swapchain(old);
        // SAFETY: live surface; the device was made with VK_KHR_swapchain
        // (ContextOptions::display); the old swapchain's images are idle.
        let swapchain = unsafe { self.swapchain_fn.create_swapchain(&info, None) };
        // SAFETY: the device is idle and nothing of the old swapchain is in use.
        unsafe { self.swapchain_fn.destroy_swapchain(old, None) };
        self.swapchain = swapchain.map_err(vk_err("vkCreateSwapchainKHR"))?;
        ctx.set_name(self.swapchain, "swapchain");
        self.format = format.format;
        self.extent = extent;
        // SAFETY: the swapchain was just made.
        let raws = unsafe { self.swapchain_fn.get_swapchain_images(self.swapchain) }
            .map_err(vk_err("vkGetSwapchainImagesKHR"))?;
        for (i, raw) in raws.into_iter().enumerate() {
            let name = format!("swapchain[{i}]");
            let desc =
                ImageDesc { name: &name, format: format.format, extent, mip_levels: 1, array_layers: 1, usage: USAGE };
            // SAFETY: a live image of this swapchain, made with `desc`,
            // UNDEFINED until first used; it lives until the swapchain is
            // destroyed, after this wrapper (release_images).
            self.images.push(unsafe { Image::from_raw(ctx, raw, &desc, vk::ImageLayout::UNDEFINED) }?);
            ctx.set_name(raw, &name);
            self.rendered.push(semaphore(ctx, &format!("swapchain_rendered[{i}]"))?);
        }
        Ok(())
    }

    /// A new surface for the window after the old one was lost; the old
    /// swapchain goes with it.
    fn remake_surface(&mut self, ctx: &Context) -> Result<()> {
        let s = &ctx.shared;
        ctx.wait_idle()?;
        self.release_images();
        // SAFETY: the device is idle and no view of the swapchain's images
        // is left; the lost surface is used by nothing else.
        unsafe {
            self.swapchain_fn.destroy_swapchain(self.swapchain, None);
            self.surface_fn.destroy_surface(self.surface, None);
        }
        self.swapchain = vk::SwapchainKHR::null();
        self.surface = vk::SurfaceKHR::null();
        // SAFETY: the handles `new`'s caller vouched for, still live.
        self.surface = unsafe { ash_window::create_surface(&s.entry, &s.instance, self.display, self.window, None) }
            .map_err(vk_err("vkCreate*SurfaceKHR"))?;
        self.lost = false;
        self.surfaces += 1;
        Ok(())
    }

    fn pick_format(&self, ctx: &Context) -> Result<vk::SurfaceFormatKHR> {
        // SAFETY: live surface and physical device of this instance.
        let formats = unsafe { self.surface_fn.get_physical_device_surface_formats(ctx.shared.physical, self.surface) }
            .map_err(vk_err("vkGetPhysicalDeviceSurfaceFormatsKHR"))?;
        let srgb = vk::ColorSpaceKHR::SRGB_NONLINEAR;
        [vk::Format::B8G8R8A8_UNORM, vk::Format::R8G8B8A8_UNORM]
            .iter()
            .find_map(|want| formats.iter().find(|f| f.format == *want && f.color_space == srgb))
            .copied()
            .ok_or_else(|| {
                Error::Unsupported(format!("the window offers no 8-bit UNORM swapchain format (offers {formats:?})"))
            })
    }

    fn pick_mode(&self, ctx: &Context) -> Result<vk::PresentModeKHR> {
        if self.vsync {
            return Ok(vk::PresentModeKHR::FIFO);
        }
        // SAFETY: live surface and physical device of this instance.
        let modes =
            unsafe { self.surface_fn.get_physical_device_surface_present_modes(ctx.shared.physical, self.surface) }
                .map_err(vk_err("vkGetPhysicalDeviceSurfacePresentModesKHR"))?;
        Ok([vk::PresentModeKHR::MAILBOX, vk::PresentModeKHR::IMMEDIATE]
            .into_iter()
            .find(|m| modes.contains(m))
            .unwrap_or(vk::PresentModeKHR::FIFO))
    }

    /// Acquires the next image, once the ring's next slot is free
    /// (`FrameRing::wait_next`). `None`: the swapchain is out of date, the
    /// surface lost or the window minimised; call [`Presenter::resize`] and
    /// skip the frame.
    pub fn acquire(&mut self) -> Result<Option<Acquired>> {
        if self.extent == [0, 0] {
            return Ok(None);
        }
        if self.shared.faults.acquire_loses_surface() {
            // Injected (FaultInjector): as vkAcquireNextImageKHR reports it.
            self.lost = true;
            return Ok(None);
        }
        let wait = self.acquired[self.next_acquire];
        // SAFETY: live swapchain; `wait` is unsignalled: the frame that last
        // waited on it completed (FrameRing::wait_next), and a failed
        // acquisition leaves it untouched.
        let got = unsafe { self.swapchain_fn.acquire_next_image(self.swapchain, u64::MAX, wait, vk::Fence::null()) };
        let index = match got {
            Ok((index, _suboptimal)) => index,
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => return Ok(None),
            Err(vk::Result::ERROR_SURFACE_LOST_KHR) => {
                self.lost = true;
                return Ok(None);
            }
            Err(e) => return Err(Error::vk("vkAcquireNextImageKHR", e)),
        };
        self.next_acquire = (self.next_acquire + 1) % self.acquired.len();
        let sync = BinarySync {
            wait,
            wait_stage: vk::PipelineStageFlags2::ALL_COMMANDS,
            signal: self.rendered[index as usize],
        };
        Ok(Some(Acquired { index, sync }))
    }

    /// Presents an image the submitted frame left in PRESENT_SRC_KHR.
    /// False: out of date or suboptimal; remake it before the next frame.
    pub fn present(&mut self, acquired: &Acquired) -> Result<bool> {
        let image = &self.images[acquired.index as usize];
        assert_eq!(
            image.layout(),
            vk::ImageLayout::PRESENT_SRC_KHR,
            "{} presented in {:?}",
            image.name,
            image.layout()
        );
        let waits = [acquired.sync.signal];
        let chains = [self.swapchain];
        let indices = [acquired.index];
        let info = vk::PresentInfoKHR::default().wait_semaphores(&waits).swapchains(&chains).image_indices(&indices);
        let _q = self.shared.queue_lock.lock().unwrap_or_else(|e| e.into_inner());
        // SAFETY: the image was acquired and the frame that signals `waits`
        // was submitted; the queue is externally synchronized by the lock.
        match unsafe { self.swapchain_fn.queue_present(self.shared.graphics.raw, &info) } {
            Ok(suboptimal) => Ok(!suboptimal),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(false),
            Err(vk::Result::ERROR_SURFACE_LOST_KHR) => {
                self.lost = true;
                Ok(false)
            }
            Err(e) => Err(Error::vk("vkQueuePresentKHR", e)),
        }
    }

    /// Drops the image wrappers and their semaphores; the device must be
    /// idle (`Shared::wait_idle`), so their views go now, before the
    /// swapchain that owns their images.
    fn release_images(&mut self) {
        self.images.clear();
        for sem in self.rendered.drain(..) {
            self.shared.retire(Garbage::Semaphore(sem));
        }
        self.shared.collect_garbage();
    }
}

impl Drop for Presenter {
    fn drop(&mut self) {
        let s = self.shared.clone();
        let _ = s.wait_idle();
        self.release_images();
        for sem in self.acquired.drain(..) {
            s.retire(Garbage::Semaphore(sem));
        }
        s.collect_garbage();
        // SAFETY: the device is idle; the images' views are destroyed; the
        // surface outlives its swapchain and nothing else uses it.
        unsafe {
            self.swapchain_fn.destroy_swapchain(self.swapchain, None);
            self.surface_fn.destroy_surface(self.surface, None);
        }
    }
}

fn semaphore(ctx: &Context, name: &str) -> Result<vk::Semaphore> {
    // SAFETY: valid device and create info.
    let sem = unsafe { ctx.shared.device.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }
        .map_err(vk_err("vkCreateSemaphore"))?;
    inc(&ctx.shared.live.sync_objects);
    ctx.set_name(sem, name);
    Ok(sem)
}

//! The engine's Vulkan objects made at start, in order: instance,
//! validation messenger, device, swapchain and the per-frame objects.
//! `Engine` keeps them and destroys them.

use crate::targets::EXTENT;
use ash::vk;
use std::ffi::c_void;
use std::sync::atomic::{AtomicU64, Ordering};
use winit::raw_window_handle::RawDisplayHandle;

/// The validation layer's messenger and its message counter.
pub type Messenger = (ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT, Box<AtomicU64>);

/// A `map_err` for a Vulkan call: its name and the error.
pub fn vk_err(what: &str) -> impl Fn(vk::Result) -> String {
    let what = what.to_string();
    move |r: vk::Result| format!("{what}: {r}")
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

/// The instance, with the window system's extensions (and the validation
/// layer and debug utils when asked).
pub fn instance(entry: &ash::Entry, display: RawDisplayHandle, validation: bool) -> Result<ash::Instance, String> {
    let e = vk_err;
    let mut exts = ash_window::enumerate_required_extensions(display).map_err(e("surface extensions"))?.to_vec();
    let layers = [c"VK_LAYER_KHRONOS_validation".as_ptr()];
    if validation {
        exts.push(ash::ext::debug_utils::NAME.as_ptr());
    }
    let app = vk::ApplicationInfo::default().application_name(c"embed").api_version(vk::API_VERSION_1_3);
    let mut info = vk::InstanceCreateInfo::default().application_info(&app).enabled_extension_names(&exts);
    if validation {
        info = info.enabled_layer_names(&layers);
    }
    // SAFETY: the create info points at locals that outlive the call.
    unsafe { entry.create_instance(&info, None) }.map_err(e("vkCreateInstance"))
}

/// # Safety
/// `instance` is live and was made by `entry` with debug utils when
/// `validation`.
pub unsafe fn messenger(
    entry: &ash::Entry,
    instance: &ash::Instance,
    validation: bool,
) -> Result<Option<Messenger>, String> {
    if !validation {
        return Ok(None);
    }
    let du = ash::ext::debug_utils::Instance::new(entry, instance);
    let count = Box::new(AtomicU64::new(0));
    let mi = vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR)
        .message_type(vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE)
        .pfn_user_callback(Some(on_message))
        .user_data(&*count as *const AtomicU64 as *mut c_void);
    // SAFETY: as the caller promises; `count` is boxed, so the pointer the
    // layer keeps stays valid while the engine holds it.
    let m = unsafe { du.create_debug_utils_messenger(&mi, None) }.map_err(vk_err("vkCreateDebugUtilsMessengerEXT"))?;
    Ok(Some((du, m, count)))
}

/// # Safety
/// `instance` and `surface` are live.
pub unsafe fn physical_and_family(
    instance: &ash::Instance,
    surface_fn: &ash::khr::surface::Instance,
    surface: vk::SurfaceKHR,
) -> Result<(vk::PhysicalDevice, u32), String> {
    let e = vk_err;
    // SAFETY: as the caller promises.
    unsafe {
        let physical = instance.enumerate_physical_devices().map_err(e("devices"))?[0];
        let family = instance
            .get_physical_device_queue_family_properties(physical)
            .iter()
            .position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE))
            .ok_or("no graphics queue")? as u32;
        if !surface_fn.get_physical_device_surface_support(physical, family, surface).map_err(e("support"))? {
            return Err("the graphics queue cannot present".into());
        }
        Ok((physical, family))
    }
}

/// vista's extensions and features, and the swapchain for ourselves.
///
/// # Safety
/// `instance` is live and `physical` one of its devices.
pub unsafe fn device(
    instance: &ash::Instance,
    physical: vk::PhysicalDevice,
    family: u32,
) -> Result<ash::Device, String> {
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
    // SAFETY: as the caller promises; the create info points at locals
    // that outlive the call.
    unsafe { instance.create_device(physical, &di, None) }.map_err(vk_err("vkCreateDevice"))
}

/// The swapchain (BGRA where offered), its images and whether they are BGRA.
///
/// # Safety
/// `surface` is live, on `physical`; `swapchain_fn` is the device's.
pub unsafe fn swapchain(
    surface_fn: &ash::khr::surface::Instance,
    swapchain_fn: &ash::khr::swapchain::Device,
    physical: vk::PhysicalDevice,
    surface: vk::SurfaceKHR,
) -> Result<(vk::SwapchainKHR, Vec<vk::Image>, bool), String> {
    let e = vk_err;
    // SAFETY: as the caller promises; the create info is a local.
    unsafe {
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
        Ok((swapchain, images, bgra))
    }
}

/// What each frame in flight records and waits with.
pub struct FrameObjects {
    pub pool: vk::CommandPool,
    pub cmds: Vec<vk::CommandBuffer>,
    pub fences: Vec<vk::Fence>,
    /// One per frame in flight.
    pub acquired: Vec<vk::Semaphore>,
    /// One per swapchain image.
    pub rendered: Vec<vk::Semaphore>,
}

/// # Safety
/// `device` is live and `family` one of its queue families.
pub unsafe fn frame_objects(
    device: &ash::Device,
    family: u32,
    frames: usize,
    images: usize,
) -> Result<FrameObjects, String> {
    let e = vk_err;
    // SAFETY: as the caller promises; the create infos are locals.
    unsafe {
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
                &vk::CommandBufferAllocateInfo::default().command_pool(pool).command_buffer_count(frames as u32),
            )
            .map_err(e("command buffers"))?;
        let signalled = vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED);
        let sem = || device.create_semaphore(&vk::SemaphoreCreateInfo::default(), None);
        let fences = (0..frames).map(|_| device.create_fence(&signalled, None)).collect::<Result<_, _>>();
        let acquired = (0..frames).map(|_| sem()).collect::<Result<_, _>>().map_err(e("semaphores"))?;
        let rendered = (0..images).map(|_| sem()).collect::<Result<_, _>>().map_err(e("semaphores"))?;
        Ok(FrameObjects { pool, cmds, fences: fences.map_err(e("fences"))?, acquired, rendered })
    }
}

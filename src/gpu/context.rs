//! The Vulkan context: instance, device, queues, allocator, deferred
//! destruction. Either created headless (tools, tests) or wrapped around an
//! engine's own handles without taking ownership.
//!
//! Destruction order (in `Shared::drop`): wait for the device to be idle, free
//! every deferred resource, drop the allocator, then the device and instance
//! (only if we created them), the debug messenger last but one, and the
//! validation log after the instance so messages at `vkDestroyInstance` land.

use super::device_info::{self, DeviceInfo, REQUIRED_DEVICE_EXTENSIONS};
use super::resources::{Garbage, LiveCounters, LiveObjects};
use super::validation::{self, ValidationLog};
use crate::error::{vk_err, Error, Result};
use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use std::ffi::{CStr, CString};
use std::mem::ManuallyDrop;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Options for [`Context::headless`].
#[derive(Debug, Clone, Default)]
pub struct ContextOptions {
    /// Enable the Khronos validation layer (fails if it is not installed).
    pub validation: bool,
    /// Also enable synchronization validation (implies `validation`).
    pub sync_validation: bool,
    /// Pick the first device whose name contains this; the env var
    /// `VISTA_DEVICE` does the same when this is `None`.
    pub device_name: Option<String>,
    /// The display a window will present on (feature `window`): the
    /// instance gets its surface extensions and the device
    /// VK_KHR_swapchain, for [`super::present::Presenter`].
    #[cfg(feature = "window")]
    pub display: Option<raw_window_handle::RawDisplayHandle>,
}

impl ContextOptions {
    /// The instance extensions a window needs.
    fn surface_extensions(&self) -> Result<&'static [*const std::ffi::c_char]> {
        #[cfg(feature = "window")]
        if let Some(display) = self.display {
            return ash_window::enumerate_required_extensions(display)
                .map_err(|e| Error::Unsupported(format!("no Vulkan surface for this display: {e}")));
        }
        Ok(&[])
    }

    fn presents(&self) -> bool {
        #[cfg(feature = "window")]
        return self.display.is_some();
        #[cfg(not(feature = "window"))]
        false
    }
}

/// An engine's Vulkan objects, shaped like Dear ImGui's
/// `ImGui_ImplVulkan_InitInfo`. The device must have been created with the
/// extensions in `REQUIRED_DEVICE_EXTENSIONS` and the features vista checks in
/// `device_info::required_features` enabled.
pub struct RawHandles {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    pub physical_device: vk::PhysicalDevice,
    pub device: ash::Device,
    pub graphics_queue_family: u32,
    pub graphics_queue: vk::Queue,
    /// Same as graphics when the engine has no separate compute queue.
    pub compute_queue_family: u32,
    pub compute_queue: vk::Queue,
    /// Whether the instance was created with VK_EXT_debug_utils (names and labels).
    pub debug_utils: bool,
    /// Where vista's submissions go: `None`, vista calls vkQueueSubmit2 on
    /// the queues above itself (behind a lock of its own, which an engine
    /// submitting from another thread does not take); `Some`, every one
    /// goes through the engine's function, which owns the queue.
    pub submit: Option<Submitter>,
}

/// Submits to `queue` (one of the context's) what vista recorded, signalling
/// `fence` on completion: the engine's queue, its lock, its thread.
pub type Submitter = Box<dyn Fn(vk::Queue, &vk::SubmitInfo2, vk::Fence) -> ash::prelude::VkResult<()> + Send + Sync>;

/// How many submissions vista made, and how.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Submissions {
    /// vkQueueSubmit2 called by vista itself.
    pub direct: u64,
    /// Handed to `RawHandles::submit`.
    pub through_engine: u64,
}

#[derive(Debug, Clone, Copy)]
pub struct Queue {
    pub family: u32,
    pub raw: vk::Queue,
}

pub(crate) struct Shared {
    /// Keeps the Vulkan loader library loaded for as long as any handle lives.
    #[allow(dead_code)]
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    pub physical: vk::PhysicalDevice,
    pub device: ash::Device,
    pub debug_instance: Option<ash::ext::debug_utils::Instance>,
    pub messenger: vk::DebugUtilsMessengerEXT,
    pub debug_device: Option<ash::ext::debug_utils::Device>,
    pub push_descriptor: ash::khr::push_descriptor::Device,
    pub allocator: ManuallyDrop<Mutex<Allocator>>,
    pub graphics: Queue,
    pub compute: Queue,
    /// vkQueueSubmit needs external synchronization of the queue.
    pub queue_lock: Mutex<()>,
    /// The engine's submit function ([`RawHandles::submit`]).
    pub submitter: Option<Submitter>,
    pub submissions_direct: AtomicU64,
    pub submissions_engine: AtomicU64,
    pub owns_handles: bool,
    pub live: LiveCounters,
    pub faults: super::fault::FaultInjector,
    pub garbage: Mutex<Vec<(u64, Garbage)>>,
    pub frames_submitted: AtomicU64,
    pub frames_completed: AtomicU64,
    /// Highest frame number whose recording has begun (`frame_recording`).
    pub frames_recording: AtomicU64,
    pub validation_log: Arc<ValidationLog>,
    pub info: DeviceInfo,
}

/// Cheap to clone: every resource keeps the context alive through it.
#[derive(Clone)]
pub struct Context {
    pub(crate) shared: Arc<Shared>,
}

fn create_instance(entry: &ash::Entry, options: &ContextOptions, log: &ValidationLog) -> Result<(ash::Instance, bool)> {
    let validation = options.validation || options.sync_validation;
    // SAFETY: plain enumeration through a loaded entry.
    let layers =
        unsafe { entry.enumerate_instance_layer_properties() }.map_err(vk_err("vkEnumerateInstanceLayerProperties"))?;
    if validation && !layers.iter().any(|l| l.layer_name_as_c_str().ok() == Some(VALIDATION_LAYER)) {
        return Err(Error::Unsupported(
            "the Khronos validation layer is not installed (run tools/install-deps as root)".into(),
        ));
    }
    // SAFETY: plain enumeration through a loaded entry.
    let exts = unsafe { entry.enumerate_instance_extension_properties(None) }
        .map_err(vk_err("vkEnumerateInstanceExtensionProperties"))?;
    let has = |name: &CStr| exts.iter().any(|e| e.extension_name_as_c_str().ok() == Some(name));
    let debug_utils = has(ash::ext::debug_utils::NAME);
    let mut ext_names = Vec::new();
    if debug_utils {
        ext_names.push(ash::ext::debug_utils::NAME.as_ptr());
    }
    if options.sync_validation {
        ext_names.push(ash::ext::validation_features::NAME.as_ptr());
    }
    ext_names.extend_from_slice(options.surface_extensions()?);
    let layer_names = if validation { vec![VALIDATION_LAYER.as_ptr()] } else { vec![] };
    let app = vk::ApplicationInfo::default()
        .application_name(c"vista")
        .engine_name(c"vista")
        .api_version(vk::API_VERSION_1_3);
    let enabled = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
    let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enabled);
    let mut chained = validation::messenger_info(log);
    let mut info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_layer_names(&layer_names)
        .enabled_extension_names(&ext_names);
    if debug_utils {
        info = info.push_next(&mut chained);
    }
    if options.sync_validation {
        info = info.push_next(&mut features);
    }
    // SAFETY: every pointer in `info` refers to locals that outlive the call.
    let instance = unsafe { entry.create_instance(&info, None) }.map_err(|e| match e {
        vk::Result::ERROR_INCOMPATIBLE_DRIVER => {
            Error::Unsupported("no Vulkan 1.3 driver (install mesa-vulkan-drivers: tools/install-deps)".into())
        }
        e => Error::vk("vkCreateInstance", e),
    })?;
    Ok((instance, debug_utils))
}

fn pick_device(instance: &ash::Instance, wanted: Option<&str>) -> Result<(vk::PhysicalDevice, DeviceInfo)> {
    // SAFETY: valid instance.
    let devices = unsafe { instance.enumerate_physical_devices() }.map_err(vk_err("vkEnumeratePhysicalDevices"))?;
    let mut rejected = Vec::new();
    let mut candidates = Vec::new();
    for pd in devices {
        match device_info::query(instance, pd) {
            Ok(info) => candidates.push((pd, info)),
            Err(why) => rejected.push(why),
        }
    }
    let usable: Vec<String> = candidates.iter().map(|(_, i)| i.name.clone()).collect();
    if let Some(w) = wanted {
        candidates.retain(|(_, i)| i.name.contains(w));
    }
    // SAFETY: valid instance and physical devices.
    candidates.sort_by_key(|(pd, _)| {
        device_info::type_rank(unsafe { instance.get_physical_device_properties(*pd) }.device_type)
    });
    candidates.into_iter().next().ok_or_else(|| {
        // Say what there is to choose from, and only lists that have entries.
        let mut msg = match wanted {
            Some(w) => format!("no usable Vulkan device named like {w:?}"),
            None => "no usable Vulkan device".to_string(),
        };
        if !usable.is_empty() {
            msg += &format!("; usable: {}", usable.join(", "));
        }
        if !rejected.is_empty() {
            msg += &format!("; not usable: {}", rejected.join("; "));
        }
        Error::Unsupported(msg)
    })
}

impl Context {
    /// Creates its own instance and device: for tools and tests.
    pub fn headless(options: &ContextOptions) -> Result<Context> {
        // SAFETY: loads the system Vulkan loader; no other precondition.
        let entry = unsafe { ash::Entry::load() }
            .map_err(|e| Error::Unsupported(format!("cannot load the Vulkan loader ({e}): run tools/install-deps")))?;
        let log = Arc::new(ValidationLog::default());
        let (instance, debug_utils) = create_instance(&entry, options, &log)?;
        let env = std::env::var("VISTA_DEVICE").ok();
        let wanted = options.device_name.as_deref().or(env.as_deref());
        let (pd, info) = match pick_device(&instance, wanted) {
            Ok(v) => v,
            Err(e) => {
                // SAFETY: nothing was created from the instance yet.
                unsafe { instance.destroy_instance(None) };
                return Err(e);
            }
        };
        let prio = [1.0f32];
        let mut queue_infos =
            vec![vk::DeviceQueueCreateInfo::default().queue_family_index(info.graphics_family).queue_priorities(&prio)];
        if info.async_compute {
            queue_infos.push(
                vk::DeviceQueueCreateInfo::default().queue_family_index(info.compute_family).queue_priorities(&prio),
            );
        }
        let mut feats = device_info::required_features();
        // Optional: the frame executor's per-pass counters where asked for.
        feats.core = feats.core.pipeline_statistics_query(info.limits.pipeline_statistics);
        let mut ext_names: Vec<_> = REQUIRED_DEVICE_EXTENSIONS.iter().map(|e| e.as_ptr()).collect();
        if options.presents() {
            ext_names.push(ash::khr::swapchain::NAME.as_ptr());
        }
        let dinfo = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queue_infos)
            .enabled_extension_names(&ext_names)
            .enabled_features(&feats.core)
            .push_next(&mut feats.v12)
            .push_next(&mut feats.v13);
        // SAFETY: pd belongs to instance; the create info only points at locals.
        let device = match unsafe { instance.create_device(pd, &dinfo, None) } {
            Ok(d) => d,
            Err(e) => {
                // SAFETY: no device was created; nothing else uses the instance.
                unsafe { instance.destroy_instance(None) };
                return Err(Error::vk("vkCreateDevice", e));
            }
        };
        // SAFETY: the families were requested with one queue each above.
        let (gq, cq) = unsafe {
            (device.get_device_queue(info.graphics_family, 0), device.get_device_queue(info.compute_family, 0))
        };
        let handles = RawHandles {
            entry,
            instance,
            physical_device: pd,
            device,
            graphics_queue_family: info.graphics_family,
            graphics_queue: gq,
            compute_queue_family: info.compute_family,
            compute_queue: cq,
            debug_utils,
            submit: None,
        };
        Self::build(handles, info, true, log)
    }

    /// Wraps an engine's handles; vista destroys only what it creates.
    ///
    /// # Safety
    /// The handles must be valid, created from each other, and outlive the
    /// returned context and everything made from it. The device must enable
    /// `REQUIRED_DEVICE_EXTENSIONS` and the features vista requires.
    pub unsafe fn from_raw(handles: RawHandles) -> Result<Context> {
        let mut info = device_info::query(&handles.instance, handles.physical_device).map_err(Error::Unsupported)?;
        info.graphics_family = handles.graphics_queue_family;
        info.compute_family = handles.compute_queue_family;
        info.async_compute = handles.compute_queue != handles.graphics_queue;
        // Whether the engine enabled pipelineStatisticsQuery is not
        // visible here: no per-pass counters on its device.
        info.limits.pipeline_statistics = false;
        Self::build(handles, info, false, Arc::new(ValidationLog::default()))
    }

    fn build(h: RawHandles, info: DeviceInfo, owns_handles: bool, log: Arc<ValidationLog>) -> Result<Context> {
        let (debug_instance, debug_device, messenger) = if h.debug_utils {
            let di = ash::ext::debug_utils::Instance::new(&h.entry, &h.instance);
            let dd = ash::ext::debug_utils::Device::new(&h.instance, &h.device);
            // A messenger of our own only when we own the instance: an engine
            // routes its validation output itself.
            let m = if owns_handles {
                // SAFETY: the log outlives the messenger (destroyed in Shared::drop first).
                unsafe { di.create_debug_utils_messenger(&validation::messenger_info(&log), None) }
                    .map_err(vk_err("vkCreateDebugUtilsMessengerEXT"))?
            } else {
                vk::DebugUtilsMessengerEXT::null()
            };
            (Some(di), Some(dd), m)
        } else {
            (None, None, vk::DebugUtilsMessengerEXT::null())
        };
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: h.instance.clone(),
            device: h.device.clone(),
            physical_device: h.physical_device,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        })
        .map_err(|source| Error::Allocation { name: "allocator".into(), source })?;
        let push_descriptor = ash::khr::push_descriptor::Device::new(&h.instance, &h.device);
        let shared = Shared {
            graphics: Queue { family: h.graphics_queue_family, raw: h.graphics_queue },
            compute: Queue { family: h.compute_queue_family, raw: h.compute_queue },
            entry: h.entry,
            instance: h.instance,
            physical: h.physical_device,
            device: h.device,
            debug_instance,
            messenger,
            debug_device,
            push_descriptor,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            queue_lock: Mutex::new(()),
            submitter: h.submit,
            submissions_direct: AtomicU64::new(0),
            submissions_engine: AtomicU64::new(0),
            owns_handles,
            live: LiveCounters::default(),
            faults: Default::default(),
            garbage: Mutex::new(Vec::new()),
            frames_submitted: AtomicU64::new(0),
            frames_completed: AtomicU64::new(0),
            frames_recording: AtomicU64::new(0),
            validation_log: log,
            info,
        };
        Ok(Context { shared: Arc::new(shared) })
    }

    pub fn info(&self) -> &DeviceInfo {
        &self.shared.info
    }

    pub fn instance(&self) -> &ash::Instance {
        &self.shared.instance
    }

    pub fn physical_device(&self) -> vk::PhysicalDevice {
        self.shared.physical
    }

    pub fn device(&self) -> &ash::Device {
        &self.shared.device
    }

    pub fn graphics_queue(&self) -> Queue {
        self.shared.graphics
    }

    /// The queue for traversal and culling: a dedicated compute queue when
    /// the device has one, else the graphics queue (single-queue fallback).
    pub fn compute_queue(&self) -> Queue {
        self.shared.compute
    }

    /// Messages from the validation layer (headless contexts only).
    pub fn validation_log(&self) -> Arc<ValidationLog> {
        self.shared.validation_log.clone()
    }

    /// Live Vulkan objects created through this context, not yet destroyed.
    /// Device memory the allocator holds: (bytes in live allocations,
    /// bytes of the memory blocks it reserved from the driver).
    pub fn allocator_bytes(&self) -> (u64, u64) {
        let report = self.shared.allocator.lock().unwrap_or_else(|e| e.into_inner()).generate_report();
        (report.total_allocated_bytes, report.total_capacity_bytes)
    }

    /// Tests and `vista stability` only (feature `test-hooks`): arm
    /// allocation failures and lost devices (see [`super::fault`]).
    #[cfg(feature = "test-hooks")]
    pub fn faults(&self) -> &super::fault::FaultInjector {
        &self.shared.faults
    }

    /// Submissions vista made so far, by itself and through the engine.
    pub fn submissions(&self) -> Submissions {
        Submissions {
            direct: self.shared.submissions_direct.load(Ordering::Acquire),
            through_engine: self.shared.submissions_engine.load(Ordering::Acquire),
        }
    }

    pub fn live_objects(&self) -> LiveObjects {
        self.shared.live.snapshot()
    }

    /// Marks the start of recording the next frame and returns the number
    /// `frame_submitted` will give it. Resources dropped from now on wait
    /// for that frame too: they may be in the commands being recorded.
    pub fn frame_recording(&self) -> u64 {
        let next = self.shared.frames_submitted.load(Ordering::Acquire) + 1;
        self.shared.frames_recording.fetch_max(next, Ordering::AcqRel);
        next
    }

    /// Call once per frame after its commands are submitted; returns its number.
    pub fn frame_submitted(&self) -> u64 {
        self.shared.frames_submitted.fetch_add(1, Ordering::AcqRel) + 1
    }

    /// The number of the last frame submitted (`frame_submitted`'s).
    pub fn frames_submitted(&self) -> u64 {
        self.shared.frames_submitted.load(Ordering::Acquire)
    }

    /// Call when the fence of frame `frame` (from `frame_submitted`) has
    /// signalled: resources dropped up to that frame are destroyed.
    pub fn frame_completed(&self, frame: u64) {
        self.shared.frames_completed.fetch_max(frame, Ordering::AcqRel);
        self.shared.collect_garbage();
    }

    /// The newest frame reported complete (`frame_completed`).
    pub fn frames_completed(&self) -> u64 {
        self.shared.frames_completed.load(Ordering::Acquire)
    }

    /// Waits for all GPU work, then destroys every deferred resource (but
    /// those dropped while a frame was being recorded and not submitted).
    pub fn wait_idle(&self) -> Result<()> {
        self.shared.wait_idle()
    }

    /// Gives a Vulkan object a name RenderDoc, Nsight and the layer show.
    pub fn set_name<H: vk::Handle>(&self, handle: H, name: &str) {
        if let Some(dd) = &self.shared.debug_device {
            let name = CString::new(name.replace('\0', " ")).unwrap_or_default();
            let info = vk::DebugUtilsObjectNameInfoEXT::default().object_handle(handle).object_name(&name);
            // SAFETY: the handle is a live object of this device.
            let _ = unsafe { dd.set_debug_utils_object_name(&info) };
        }
    }

    /// Makes one deliberate API misuse so a test can prove the validation
    /// layer is active (the harness canary). Creates and leaks nothing.
    #[cfg(feature = "test-hooks")]
    pub fn provoke_validation_error(&self) {
        // A buffer of size 0 violates VUID-VkBufferCreateInfo-size-00912.
        let info = vk::BufferCreateInfo::default().size(0).usage(vk::BufferUsageFlags::STORAGE_BUFFER);
        // SAFETY: invalid on purpose but harmless: drivers accept or reject it,
        // and any created handle is destroyed at once.
        unsafe {
            if let Ok(b) = self.shared.device.create_buffer(&info, None) {
                self.shared.device.destroy_buffer(b, None);
            }
        }
    }
}

impl Shared {
    /// Buffers and images shared by the graphics and compute families when
    /// terrain compute can run on its own queue family (see `gpu` docs).
    pub(crate) fn concurrent_families(&self) -> Option<[u32; 2]> {
        let (g, c) = (self.info.graphics_family, self.info.compute_family);
        (g != c).then_some([g, c])
    }

    /// Tags `g` with the newest frame that may use it: the last submitted,
    /// or the one being recorded (a resource dropped mid-recording may be
    /// in its commands), and destroys it once that frame completed.
    pub(crate) fn retire(&self, g: Garbage) {
        let submitted = self.frames_submitted.load(Ordering::Acquire);
        let frame = submitted.max(self.frames_recording.load(Ordering::Acquire));
        let mut list = self.garbage.lock().unwrap_or_else(|e| e.into_inner());
        list.push((frame, g));
        drop(list);
        if frame <= self.frames_completed.load(Ordering::Acquire) {
            self.collect_garbage();
        }
    }

    /// The frame being recorded will not be submitted (its recording or
    /// submission failed): what was dropped meanwhile was never in submitted
    /// commands, so it waits for the frames before it only.
    pub(crate) fn abandon_recording(&self) {
        let submitted = self.frames_submitted.load(Ordering::Acquire);
        self.frames_recording.fetch_min(submitted, Ordering::AcqRel);
        let mut list = self.garbage.lock().unwrap_or_else(|e| e.into_inner());
        for (frame, _) in list.iter_mut() {
            *frame = (*frame).min(submitted);
        }
        drop(list);
        self.collect_garbage();
    }

    /// Waits for the device; every submitted frame has completed then, and
    /// what they held is destroyed.
    pub(crate) fn wait_idle(&self) -> Result<()> {
        {
            let _q = self.queue_lock.lock().unwrap_or_else(|e| e.into_inner());
            // SAFETY: valid device; the queue lock keeps vista's submissions out.
            unsafe { self.device.device_wait_idle() }.map_err(vk_err("vkDeviceWaitIdle"))?;
        }
        let submitted = self.frames_submitted.load(Ordering::Acquire);
        self.frames_completed.fetch_max(submitted, Ordering::AcqRel);
        self.collect_garbage();
        Ok(())
    }

    pub(crate) fn collect_garbage(&self) {
        let done = self.frames_completed.load(Ordering::Acquire);
        let ready: Vec<Garbage> = {
            let mut list = self.garbage.lock().unwrap_or_else(|e| e.into_inner());
            let (ready, keep): (Vec<_>, Vec<_>) = list.drain(..).partition(|(f, _)| *f <= done);
            *list = keep;
            ready.into_iter().map(|(_, g)| g).collect()
        };
        for g in ready {
            g.destroy(self);
        }
    }
}

impl Drop for Shared {
    fn drop(&mut self) {
        // SAFETY: last reference: nothing else can record or submit; the order
        // follows the module documentation.
        unsafe {
            let _ = self.device.device_wait_idle();
            let all: Vec<_> = self.garbage.get_mut().unwrap_or_else(|e| e.into_inner()).drain(..).collect();
            for (_, g) in all {
                g.destroy(self);
            }
            ManuallyDrop::drop(&mut self.allocator);
            if self.owns_handles {
                self.device.destroy_device(None);
            }
            if let Some(di) = &self.debug_instance {
                if self.messenger != vk::DebugUtilsMessengerEXT::null() {
                    di.destroy_debug_utils_messenger(self.messenger, None);
                }
            }
            if self.owns_handles {
                self.instance.destroy_instance(None);
            }
        }
    }
}

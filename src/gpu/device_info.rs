//! What the renderer needs to know about a physical device: identity, queue
//! families, limits, and which required features are missing.

use ash::vk;
use serde::Serialize;
use std::ffi::CStr;

/// Device extensions vista cannot run without.
pub const REQUIRED_DEVICE_EXTENSIONS: &[&CStr] = &[ash::khr::push_descriptor::NAME];

#[derive(Debug, Clone, Serialize)]
pub struct QueueFamilyInfo {
    pub index: u32,
    pub graphics: bool,
    pub compute: bool,
    pub transfer: bool,
    pub queue_count: u32,
    pub timestamp_valid_bits: u32,
}

/// Limits the renderer sizes its passes by.
#[derive(Debug, Clone, Serialize)]
pub struct Limits {
    pub max_compute_shared_memory_bytes: u32,
    pub max_compute_workgroup_invocations: u32,
    pub max_compute_workgroup_size: [u32; 3],
    pub max_compute_workgroup_count: [u32; 3],
    pub subgroup_size: u32,
    pub max_push_constants_bytes: u32,
    pub max_image_dimension_2d: u32,
    pub max_image_array_layers: u32,
    /// Largest storage buffer range a descriptor binds (the per-triangle
    /// rule's index lists grow to it at most).
    pub max_storage_buffer_range: u32,
    /// Size of the largest device-local memory heap.
    pub device_local_bytes: u64,
    pub timestamps_supported: bool,
    pub timestamp_period_ns: f32,
    /// Pipeline statistics queries are enabled (the per-pass counters of
    /// `FrameExecutor`): on a device vista created, where it supports
    /// them; never on an engine's (`Context::from_raw`: vista cannot tell
    /// what the engine enabled).
    pub pipeline_statistics: bool,
}

#[derive(Debug, Clone, Serialize)]
pub struct DeviceInfo {
    pub name: String,
    pub device_type: String,
    pub driver_name: String,
    pub driver_info: String,
    pub api_version: String,
    pub queue_families: Vec<QueueFamilyInfo>,
    pub graphics_family: u32,
    /// A compute-only family for async compute, if the device has one.
    pub compute_family: u32,
    /// True when culling/traversal run on a separate compute queue; false
    /// means the single-queue fallback (same queue, same semaphores).
    pub async_compute: bool,
    pub limits: Limits,
}

fn cstr(bytes: &[std::ffi::c_char]) -> String {
    // SAFETY: Vulkan fixed-size string arrays are NUL-terminated.
    unsafe { CStr::from_ptr(bytes.as_ptr()) }.to_string_lossy().into_owned()
}

pub(crate) fn type_rank(t: vk::PhysicalDeviceType) -> u32 {
    match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    }
}

/// Size of `pd`'s largest device-local heap.
fn device_local_bytes(instance: &ash::Instance, pd: vk::PhysicalDevice) -> u64 {
    // SAFETY: valid physical device of this instance.
    let memory = unsafe { instance.get_physical_device_memory_properties(pd) };
    let local = memory.memory_heaps_as_slice().iter().filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL));
    local.map(|h| h.size).max().unwrap_or(0)
}

/// Queries everything about `pd`; `Err(reason)` names what is missing.
pub(crate) fn query(instance: &ash::Instance, pd: vk::PhysicalDevice) -> Result<DeviceInfo, String> {
    let mut v11 = vk::PhysicalDeviceVulkan11Properties::default();
    let mut v12 = vk::PhysicalDeviceVulkan12Properties::default();
    let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut v11).push_next(&mut v12);
    // SAFETY: pd comes from this instance; the chained structs outlive the call.
    unsafe { instance.get_physical_device_properties2(pd, &mut props2) };
    let p = props2.properties;
    let name = cstr(&p.device_name);
    let api = p.api_version;
    if vk::api_version_major(api) < 1 || (vk::api_version_major(api) == 1 && vk::api_version_minor(api) < 3) {
        return Err(format!(
            "{name}: Vulkan 1.3 required, device has {}.{}",
            vk::api_version_major(api),
            vk::api_version_minor(api)
        ));
    }
    missing_features(instance, pd).map_err(|m| format!("{name}: missing {m}"))?;
    // SAFETY: valid physical device of this instance.
    let exts = unsafe { instance.enumerate_device_extension_properties(pd) }.map_err(|e| format!("{name}: {e:?}"))?;
    for req in REQUIRED_DEVICE_EXTENSIONS {
        if !exts.iter().any(|e| e.extension_name_as_c_str().ok() == Some(*req)) {
            return Err(format!("{name}: missing device extension {}", req.to_string_lossy()));
        }
    }
    // SAFETY: valid physical device of this instance.
    let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    let queue_families: Vec<QueueFamilyInfo> = families
        .iter()
        .enumerate()
        .map(|(i, f)| QueueFamilyInfo {
            index: i as u32,
            graphics: f.queue_flags.contains(vk::QueueFlags::GRAPHICS),
            compute: f.queue_flags.contains(vk::QueueFlags::COMPUTE),
            transfer: f.queue_flags.contains(vk::QueueFlags::TRANSFER),
            queue_count: f.queue_count,
            timestamp_valid_bits: f.timestamp_valid_bits,
        })
        .collect();
    let graphics = queue_families
        .iter()
        .find(|f| f.graphics && f.compute)
        .ok_or_else(|| format!("{name}: no queue family with graphics and compute"))?;
    let compute = queue_families.iter().find(|f| f.compute && !f.graphics);
    let l = &p.limits;
    let device_local_bytes = device_local_bytes(instance, pd);
    Ok(DeviceInfo {
        device_type: format!("{:?}", p.device_type),
        driver_name: cstr(&v12.driver_name),
        driver_info: cstr(&v12.driver_info),
        api_version: format!(
            "{}.{}.{}",
            vk::api_version_major(api),
            vk::api_version_minor(api),
            vk::api_version_patch(api)
        ),
        graphics_family: graphics.index,
        compute_family: compute.map_or(graphics.index, |c| c.index),
        async_compute: compute.is_some(),
        limits: Limits {
            max_compute_shared_memory_bytes: l.max_compute_shared_memory_size,
            max_compute_workgroup_invocations: l.max_compute_work_group_invocations,
            max_compute_workgroup_size: l.max_compute_work_group_size,
            max_compute_workgroup_count: l.max_compute_work_group_count,
            subgroup_size: v11.subgroup_size,
            max_push_constants_bytes: l.max_push_constants_size,
            max_image_dimension_2d: l.max_image_dimension2_d,
            max_image_array_layers: l.max_image_array_layers,
            max_storage_buffer_range: l.max_storage_buffer_range,
            device_local_bytes,
            timestamps_supported: l.timestamp_compute_and_graphics == vk::TRUE && graphics.timestamp_valid_bits > 0,
            timestamp_period_ns: l.timestamp_period,
            // SAFETY: valid physical device of this instance.
            pipeline_statistics: unsafe { instance.get_physical_device_features(pd) }.pipeline_statistics_query
                == vk::TRUE,
        },
        queue_families,
        name,
    })
}

/// The features vista enables (an engine enables at least these on the
/// device it hands to `Context::from_raw`); `missing_features` checks the
/// same list. Chain `v12` and `v13` into `VkDeviceCreateInfo`.
pub struct FeatureChain {
    pub core: vk::PhysicalDeviceFeatures,
    pub v12: vk::PhysicalDeviceVulkan12Features<'static>,
    pub v13: vk::PhysicalDeviceVulkan13Features<'static>,
}

pub fn required_features() -> FeatureChain {
    FeatureChain {
        core: vk::PhysicalDeviceFeatures::default()
            .multi_draw_indirect(true)
            .draw_indirect_first_instance(true)
            .shader_storage_image_extended_formats(true)
            .texture_compression_bc(true)
            .full_draw_index_uint32(true),
        v12: vk::PhysicalDeviceVulkan12Features::default()
            .timeline_semaphore(true)
            .draw_indirect_count(true)
            .host_query_reset(true)
            // DEPTH_ATTACHMENT_OPTIMAL for a depth-only target (DepthOptions).
            .separate_depth_stencil_layouts(true),
        v13: vk::PhysicalDeviceVulkan13Features::default().synchronization2(true).dynamic_rendering(true),
    }
}

fn missing_features(instance: &ash::Instance, pd: vk::PhysicalDevice) -> Result<(), String> {
    let mut v12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut v13 = vk::PhysicalDeviceVulkan13Features::default();
    let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut v12).push_next(&mut v13);
    // SAFETY: pd comes from this instance; the chained structs outlive the call.
    unsafe { instance.get_physical_device_features2(pd, &mut f2) };
    let core = f2.features;
    let checks = [
        ("multiDrawIndirect", core.multi_draw_indirect),
        ("drawIndirectFirstInstance", core.draw_indirect_first_instance),
        // R16_UINT storage writes to the quadtree node texture.
        ("shaderStorageImageExtendedFormats", core.shader_storage_image_extended_formats),
        // The normal (BC3) and albedo (BC1) payload atlases.
        ("textureCompressionBC", core.texture_compression_bc),
        // The per-triangle rule's index list: a vertex code is 27 bits
        // (slot and grid point, triangle_list.glsl).
        ("fullDrawIndexUint32", core.full_draw_index_uint32),
        ("timelineSemaphore", v12.timeline_semaphore),
        ("drawIndirectCount", v12.draw_indirect_count),
        ("hostQueryReset", v12.host_query_reset),
        ("separateDepthStencilLayouts", v12.separate_depth_stencil_layouts),
        ("synchronization2", v13.synchronization2),
        ("dynamicRendering", v13.dynamic_rendering),
    ];
    let missing: Vec<&str> = checks.iter().filter(|(_, v)| *v != vk::TRUE).map(|(n, _)| *n).collect();
    if missing.is_empty() {
        Ok(())
    } else {
        Err(format!("feature(s) {}", missing.join(", ")))
    }
}

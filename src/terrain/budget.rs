//! How many node slots a GPU budget buys: every slot is a layer of each
//! node atlas, so the device's array layers and the slot fields' width cap
//! it whatever the budget.

use super::quadtree;

/// Most resident slots a device holds: every slot (and the reload spares
/// beside them, and the reserved slot 0) is a layer of each node atlas,
/// and the slot fields are `SLOT_BITS` wide.
pub fn max_slots(device: &crate::gpu::Limits) -> u32 {
    let layers = device.max_image_array_layers.saturating_sub(1 + crate::world::RELOAD_SLOTS);
    quadtree::MAX_SLOTS.min(layers)
}

/// The GPU budget a renderer is given when its user names none: a quarter
/// of the device's local memory, and no more than the most slots the
/// device holds need (on any device with 2 GiB or more, the most slots).
pub fn default_gpu_budget(device: &crate::gpu::Limits, slot_bytes: u64) -> u64 {
    (device.device_local_bytes / 4).min(u64::from(max_slots(device)) * slot_bytes)
}

/// Resident slots a GPU budget of `budget_bytes` holds at `slot_bytes`
/// each (see [`crate::render::slot_bytes`]), at most [`max_slots`].
pub fn slots_for_budget(budget_bytes: u64, slot_bytes: u64, device: &crate::gpu::Limits) -> u32 {
    assert!(slot_bytes > 0, "a slot costs something");
    let fit = (budget_bytes / slot_bytes).min(u64::from(u32::MAX)) as u32;
    fit.min(max_slots(device))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn device(layers: u32, local_mib: u64) -> crate::gpu::Limits {
        crate::gpu::Limits {
            max_compute_shared_memory_bytes: 32768,
            max_compute_workgroup_invocations: 1024,
            max_compute_workgroup_size: [1024; 3],
            max_compute_workgroup_count: [65535; 3],
            subgroup_size: 8,
            max_push_constants_bytes: 128,
            max_image_dimension_2d: 16384,
            max_image_array_layers: layers,
            max_storage_buffer_range: 1 << 27,
            device_local_bytes: local_mib << 20,
            timestamps_supported: true,
            timestamp_period_ns: 1.0,
            pipeline_statistics: false,
        }
    }

    #[test]
    fn a_budget_buys_whole_slots_up_to_the_atlas_layers() {
        // 2048 layers: slot 0 and 8 reload spares leave 2039 for the budget.
        let d = device(2048, 8192);
        assert_eq!(max_slots(&d), 2039);
        assert_eq!(slots_for_budget(10 << 20, 64 << 10, &d), 160);
        assert_eq!(slots_for_budget((10 << 20) - 1, 64 << 10, &d), 159);
        assert_eq!(slots_for_budget(1 << 40, 64 << 10, &d), 2039);
        // The slot fields cap a device with more layers.
        assert_eq!(max_slots(&device(1 << 16, 8192)), quadtree::MAX_SLOTS);
    }

    #[test]
    fn the_default_budget_is_a_quarter_of_local_memory_at_most_what_the_slots_need() {
        let d = device(2048, 8192);
        assert_eq!(default_gpu_budget(&d, 64 << 10), 2039 * (64 << 10));
        // 256 MiB of local memory: 64 MiB, 1024 slots of 64 KiB.
        let small = device(2048, 256);
        assert_eq!(default_gpu_budget(&small, 64 << 10), 64 << 20);
        assert_eq!(slots_for_budget(default_gpu_budget(&small, 64 << 10), 64 << 10, &small), 1024);
    }
}

//! Fault injection for `vista stability` case 8 and its test: make the Nth
//! device-memory allocation fail with `OutOfDeviceMemory`, or the Nth queue
//! submission or fence wait report `DeviceLost`, or the Nth swapchain
//! acquisition report `SurfaceLost`, counting from when it was armed, so
//! every error path can be walked on a device (and a window) that never
//! fails.
//! Disarmed (the default) each hook is one relaxed atomic load.

use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

const OFF: u64 = u64::MAX;

pub struct FaultInjector {
    allocations: AtomicU64,
    submits: AtomicU64,
    waits: AtomicU64,
    acquires: AtomicU64,
    fail_allocation: AtomicU64,
    lose_at_submit: AtomicU64,
    lose_at_wait: AtomicU64,
    lose_surface_at_acquire: AtomicU64,
}

impl Default for FaultInjector {
    fn default() -> Self {
        FaultInjector {
            allocations: AtomicU64::new(0),
            submits: AtomicU64::new(0),
            waits: AtomicU64::new(0),
            acquires: AtomicU64::new(0),
            fail_allocation: AtomicU64::new(OFF),
            lose_at_submit: AtomicU64::new(OFF),
            lose_at_wait: AtomicU64::new(OFF),
            lose_surface_at_acquire: AtomicU64::new(OFF),
        }
    }
}

impl FaultInjector {
    /// Device-memory allocations, submissions and fence waits so far.
    pub fn counts(&self) -> [u64; 3] {
        [self.allocations.load(Relaxed), self.submits.load(Relaxed), self.waits.load(Relaxed)]
    }

    /// The allocation `n` allocations from now (0: the next) fails.
    pub fn fail_allocation_in(&self, n: u64) {
        self.fail_allocation.store(self.allocations.load(Relaxed) + n, Relaxed);
    }

    /// The submission `n` submissions from now reports a lost device.
    pub fn lose_device_at_submit_in(&self, n: u64) {
        self.lose_at_submit.store(self.submits.load(Relaxed) + n, Relaxed);
    }

    /// The fence wait `n` waits from now reports a lost device.
    pub fn lose_device_at_wait_in(&self, n: u64) {
        self.lose_at_wait.store(self.waits.load(Relaxed) + n, Relaxed);
    }

    /// The swapchain acquisition `n` acquisitions from now reports a lost
    /// surface (`Presenter::acquire`), as a window system may at any time.
    pub fn lose_surface_at_acquire_in(&self, n: u64) {
        self.lose_surface_at_acquire.store(self.acquires.load(Relaxed) + n, Relaxed);
    }

    pub fn disarm(&self) {
        for a in [&self.fail_allocation, &self.lose_at_submit, &self.lose_at_wait, &self.lose_surface_at_acquire] {
            a.store(OFF, Relaxed);
        }
    }

    /// Counts one event; true when it is the armed one (which then disarms).
    fn hit(count: &AtomicU64, armed: &AtomicU64) -> bool {
        let n = count.fetch_add(1, Relaxed);
        armed.compare_exchange(n, OFF, Relaxed, Relaxed).is_ok()
    }

    pub(crate) fn allocation_fails(&self) -> bool {
        Self::hit(&self.allocations, &self.fail_allocation)
    }

    pub(crate) fn submit_loses_device(&self) -> bool {
        Self::hit(&self.submits, &self.lose_at_submit)
    }

    pub(crate) fn wait_loses_device(&self) -> bool {
        Self::hit(&self.waits, &self.lose_at_wait)
    }

    #[cfg_attr(not(feature = "window"), allow(dead_code))]
    pub(crate) fn acquire_loses_surface(&self) -> bool {
        Self::hit(&self.acquires, &self.lose_surface_at_acquire)
    }
}

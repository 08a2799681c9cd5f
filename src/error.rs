//! The library's error type: what a caller cannot prevent. Programmer errors
//! (a wrong binding kind, a pass recorded outside a frame) are asserts.

use ash::vk;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("out of host memory")]
    OutOfHostMemory,
    #[error("out of device memory")]
    OutOfDeviceMemory,
    #[error("the Vulkan device was lost")]
    DeviceLost,
    #[error("unsupported device or system: {0}")]
    Unsupported(String),
    #[error("bad input: {0}")]
    BadInput(String),
    /// A scene's `[effects]` table names an unknown effect, a wrong type or
    /// a missing file; the message names the key.
    #[error("{0}")]
    Scene(String),
    #[error(transparent)]
    World(#[from] crate::world::WorldError),
    #[error("Vulkan call {call} failed: {result:?}")]
    Vulkan { call: &'static str, result: vk::Result },
    #[error("GPU memory allocation for {name:?} failed: {source}")]
    Allocation {
        name: String,
        #[source]
        source: gpu_allocator::AllocationError,
    },
}

pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// Maps a Vulkan result to the error a caller can act on.
    pub(crate) fn vk(call: &'static str, result: vk::Result) -> Self {
        match result {
            vk::Result::ERROR_OUT_OF_HOST_MEMORY => Error::OutOfHostMemory,
            vk::Result::ERROR_OUT_OF_DEVICE_MEMORY => Error::OutOfDeviceMemory,
            vk::Result::ERROR_DEVICE_LOST => Error::DeviceLost,
            result => Error::Vulkan { call, result },
        }
    }
}

/// `result.map_err(vk_err("vkFoo"))`
pub(crate) fn vk_err(call: &'static str) -> impl Fn(vk::Result) -> Error {
    move |r| Error::vk(call, r)
}

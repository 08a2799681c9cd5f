//! The only place with unsafe Vulkan calls. Everything above it is safe Rust.
//!
//! Queues: where the device has a compute-only family (async compute),
//! every buffer and image is created with CONCURRENT sharing between it and
//! the graphics family, so terrain compute and graphics command buffers use
//! the same resources without queue-family ownership transfers; ordering
//! comes from the timeline semaphores the submitter signals and waits on
//! ([`FrameRing`], [`COMPUTE_LAG`]). With one family, sharing is EXCLUSIVE.

pub mod access_log;
pub mod commands;
pub mod context;
pub mod device_info;
pub mod fault;
pub mod pipeline;
#[cfg(feature = "window")]
pub mod present;
pub mod query;
pub mod queue_mode;
pub mod resources;
pub mod shader;
pub mod submit;
mod transfer;
pub mod validation;

pub use ash::vk;
pub use commands::{ColorTarget, DepthTarget, Recorder, Resource};
pub use context::{Context, ContextOptions, Queue, RawHandles, Submissions, Submitter};
pub use device_info::{
    required_features, DeviceInfo, FeatureChain, Limits, QueueFamilyInfo, REQUIRED_DEVICE_EXTENSIONS,
};
pub use pipeline::{ComputePipelineDesc, GraphicsPipelineDesc, Pipeline, StencilDesc};
pub use query::{StatisticsPool, TimestampPool, STATISTICS};
pub use queue_mode::{QueueMode, COMPUTE_LAG, FRAME_COPIES};
pub use resources::{
    depth_layout, has_stencil, Buffer, BufferDesc, Image, ImageDesc, LiveObjects, MemoryLocation, Sampler, SamplerDesc,
};
pub use shader::{Binding, BindingKind, ShaderInfo, ShaderStage};
pub use submit::{BinarySync, CommandPool, FrameCommands, FrameRing};
pub use validation::{Severity, ValidationLog, ValidationMessage};

//! The only place with unsafe Vulkan calls. Everything above it is safe Rust.

pub mod commands;
pub mod context;
pub mod device_info;
pub mod pipeline;
pub mod query;
pub mod resources;
pub mod shader;
pub mod submit;
mod transfer;
pub mod validation;

pub use ash::vk;
pub use commands::{ColorTarget, DepthTarget, Recorder, Resource};
pub use context::{Context, ContextOptions, Queue, RawHandles};
pub use device_info::{DeviceInfo, Limits, QueueFamilyInfo};
pub use pipeline::{ComputePipelineDesc, GraphicsPipelineDesc, Pipeline};
pub use query::TimestampPool;
pub use resources::{Buffer, BufferDesc, Image, ImageDesc, LiveObjects, MemoryLocation, Sampler, SamplerDesc};
pub use shader::{Binding, BindingKind, ShaderInfo, ShaderStage};
pub use submit::FrameRing;
pub use validation::{Severity, ValidationLog, ValidationMessage};

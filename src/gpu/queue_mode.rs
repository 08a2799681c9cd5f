//! How a frame's terrain work reaches the GPU: one command buffer, or a
//! compute and a graphics one on one queue or two, and how far apart the
//! frames' halves may run.

use super::device_info::DeviceInfo;
use crate::error::{Error, Result};
use serde::Serialize;

/// Copies of each resource a frame's compute work rewrites while an older
/// frame's graphics work may still read it (`frame::per_frame`).
pub const FRAME_COPIES: usize = 2;

/// How many frames back the graphics work a frame's compute submission
/// must wait for: the last frame whose graphics read the copies it
/// rewrites. A split frame's compute thus runs beside the previous
/// frame's graphics on a compute-only queue.
pub const COMPUTE_LAG: u64 = FRAME_COPIES as u64;

/// How a frame's terrain work reaches the GPU.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum QueueMode {
    /// One command buffer on the graphics queue.
    Single,
    /// The compute passes in a command buffer of their own, submitted first
    /// to the graphics queue; the graphics command buffer waits for it on a
    /// timeline semaphore. The async scheme on a device with one queue.
    SplitOneQueue,
    /// As `SplitOneQueue`, with the compute command buffer submitted to
    /// the queue of a compute-only family, running beside graphics work.
    AsyncCompute,
}

impl QueueMode {
    /// Async compute where the device has a compute-only family, else one
    /// command buffer.
    pub fn auto(info: &DeviceInfo) -> QueueMode {
        if info.async_compute {
            QueueMode::AsyncCompute
        } else {
            QueueMode::Single
        }
    }

    /// Two command buffers per frame.
    pub fn is_split(self) -> bool {
        self != QueueMode::Single
    }

    /// Whether the device can run this mode.
    pub fn check(self, info: &DeviceInfo) -> Result<()> {
        if self == QueueMode::AsyncCompute && !info.async_compute {
            return Err(Error::Unsupported(format!(
                "{} has no compute-only queue family: async compute cannot run (use single or split)",
                info.name
            )));
        }
        Ok(())
    }

    pub fn name(self) -> &'static str {
        match self {
            QueueMode::Single => "single",
            QueueMode::SplitOneQueue => "split",
            QueueMode::AsyncCompute => "async",
        }
    }

    /// What ran, in words, for tools' output.
    pub fn describe(self, info: &DeviceInfo) -> String {
        match self {
            QueueMode::Single => {
                format!(
                    "single: every pass in one command buffer on the graphics queue (family {})",
                    info.graphics_family
                )
            }
            QueueMode::SplitOneQueue => format!(
                "split: compute passes in their own command buffer on the graphics queue (family {}); \
                 graphics waits for them, they for the graphics {COMPUTE_LAG} frames back (timeline \
                 semaphores)",
                info.graphics_family
            ),
            QueueMode::AsyncCompute => format!(
                "async: compute passes on the compute queue (family {}) beside the last frame's \
                 graphics (family {}); graphics waits for them, they for the graphics {COMPUTE_LAG} \
                 frames back (timeline semaphores)",
                info.compute_family, info.graphics_family
            ),
        }
    }
}

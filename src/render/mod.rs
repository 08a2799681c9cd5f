//! The renderer an engine records into: [`TerrainRenderer`] owns the
//! terrain passes and records one frame into the caller's command buffer
//! from a [`View`]; [`offscreen`] is the headless frame loop of the tools
//! and tests.

pub mod offscreen;
pub mod renderer;
pub mod stats;
pub mod view;

pub use crate::passes::terrain_geometry::RenderTargets;
pub use renderer::{RendererOptions, TerrainRenderer};
pub use view::{linear_depth, overview_camera, Camera, Lighting, TerrainViewGpu, View, DEFAULT_NEAR_M};

//! The renderer an engine records into: [`TerrainRenderer`] owns the
//! terrain passes and the effects a scene calls for, built into a pass
//! graph (`scene::graph`), and records one frame into the caller's command
//! buffer from a [`View`]; [`report`] says what was built and what ran;
//! [`offscreen`] is the headless frame loop of the tools and tests.

mod frame_passes;
pub mod offscreen;
pub mod renderer;
pub mod report;
/// What `vista render` prints and `stats.json` holds (with the reference
/// traversal's wanted-finer counts).
#[cfg(feature = "reference")]
pub mod stats;
pub mod telemetry;

pub use crate::effects::{Effect, EffectDecision, Effects, FrameSwitches, MaterialsMode};
pub use crate::passes::terrain_geometry::RenderTargets;
pub use crate::scene::shading::Shading;
pub use crate::scene::tonemap::Tonemap;
pub use crate::scene::view::{linear_depth, overview_camera, Camera, Lighting, TerrainViewGpu, View, DEFAULT_NEAR_M};
pub use renderer::{
    memory_for, slot_bytes, vertex_bounds_slot_bytes, LodOptions, LodRule, RendererOptions, TerrainRenderer,
};
pub use report::{frame_report, FrameReport, PassState};

//! The renderer an engine records into: [`TerrainRenderer`] owns the
//! terrain passes, built from the scene's [`effects`] into a pass
//! [`graph`], and records one frame into the caller's command buffer from a
//! [`View`]; [`report`] says what was built and what ran; [`offscreen`] is
//! the headless frame loop of the tools and tests.

pub mod assets;
pub mod atmosphere;
pub mod cliff_meshes;
pub mod detail_textures;
pub mod effects;
mod frame_passes;
pub mod gbuffer;
pub mod graph;
pub mod grass;
pub mod materials;
pub mod materials_gpu;
pub mod near_geometry;
pub mod offscreen;
pub mod renderer;
pub mod report;
pub mod shading;
/// What `vista render` prints and `stats.json` holds (with the reference
/// traversal's wanted-finer counts).
#[cfg(feature = "reference")]
pub mod stats;
pub mod sun_shadows;
pub mod telemetry;
pub mod tonemap;
pub mod view;
pub mod virtual_texture;

pub use crate::passes::terrain_geometry::RenderTargets;
pub use effects::{Effect, EffectDecision, Effects, FrameSwitches, MaterialsMode};
pub use renderer::{memory_for, LodOptions, RendererOptions, TerrainRenderer};
pub use report::{frame_report, FrameReport, PassState};
pub use shading::Shading;
pub use tonemap::Tonemap;
pub use view::{linear_depth, overview_camera, Camera, Lighting, TerrainViewGpu, View, DEFAULT_NEAR_M};

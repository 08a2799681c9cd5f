//! vista: a GPU-driven terrain renderer for Vulkan (Far Cry 5 style) on ash.
//!
//! Layers, each using only those above it:
//! - [`output`]: every file vista writes, whole or not at all;
//! - [`shaders`]: generated at build time from `shaders_glsl/` (SPIR-V,
//!   reflection, struct layouts, the constants shared with shaders);
//! - [`gpu`]: every unsafe Vulkan call; [`frame`]: the frame executor
//!   (labels, timestamps) and profiler output;
//! - [`world`]: the CPU side of the terrain (height sources, bake, cache,
//!   streaming), no Vulkan; [`terrain`]: streaming feeding the GPU quadtree;
//! - [`targets`]: what a frame renders into (outputs, depth, G-buffer layout);
//! - [`passes`]: one pass per file; `reference` (feature `reference`): a
//!   CPU twin per pass and the reference ray-caster;
//! - [`render`]: the renderer an engine records into
//!   ([`render::TerrainRenderer`]) and the frame order; `bench` (feature
//!   `bench`): the `vista bench` kinds; `stability` (feature `stability`):
//!   the hard cases. The default features build the renderer alone: the
//!   command line is the `vista-cli` package (tools/vista), and the twins,
//!   benches, hard cases and test switches (`test-hooks`) are features.

#[cfg(feature = "bench")]
pub mod bench;
pub mod effects;
pub mod error;
pub mod frame;
pub mod gpu;
pub mod output;
pub mod passes;
#[cfg(feature = "reference")]
pub mod reference;
pub mod render;
pub mod scene;
pub mod shaders;
#[cfg(feature = "stability")]
pub mod stability;
pub mod targets;
pub mod terrain;
pub mod world;

pub use error::{Error, Result};

//! vista: a GPU-driven terrain renderer for Vulkan (Far Cry 5 style) on ash.
//!
//! Layers: [`gpu`] owns every unsafe Vulkan call; [`frame`] wraps passes in
//! labels and timestamps; [`render`] is the renderer an engine records into
//! ([`render::TerrainRenderer`]); [`passes`] holds one pass per file; [`shaders`] is
//! generated at build time from `shaders_glsl/`; [`world`] is the CPU side of
//! the terrain (height sources, node bake, cache, streaming), with no Vulkan.

pub mod bench;
pub mod error;
pub mod frame;
pub mod gpu;
pub mod gpu_quadtree;
pub mod passes;
pub mod patch_grid;
pub mod profiler;
pub mod quadtree;
pub mod render;
pub mod shaders;
pub mod terrain;
pub mod traverse_cpu;
pub mod world;

pub use error::{Error, Result};

//! vista: a GPU-driven terrain renderer for Vulkan (Far Cry 5 style) on ash.
//!
//! Floors, each importing only its own and those below it (the house's
//! plan with the frame's phases and the effect traits:
//! `docs/architecture.md`; `tests/layout.rs` holds the rules):
//! - [`output`], [`shaders`]: every file vista writes, whole or not at all;
//!   the shader bank generated from `shaders_glsl/` (SPIR-V, reflection,
//!   struct layouts, the constants shared with shaders);
//! - [`world`]: the CPU side of the terrain (height sources, bake, cache,
//!   streaming), no Vulkan; [`error`]; [`gpu`]: every unsafe Vulkan call;
//!   [`frame`]: the frame executor (labels, timestamps) and profiler;
//!   [`terrain`]: streaming feeding the GPU quadtree;
//! - [`targets`] and [`scene`]: what passes and effects share (outputs,
//!   G-buffer and depth; view, lighting, shading rules, effect names, the
//!   pass graph);
//! - [`passes`]: the core terrain passes, one per file;
//! - [`effects`]: one folder per optional effect behind two small traits,
//!   and their registry;
//! - `reference` (feature `reference`): a CPU twin per pass and the
//!   reference ray-caster;
//! - [`render`]: the renderer an engine records into
//!   ([`render::TerrainRenderer`]), which drives the passes and effects;
//!   `bench` (feature `bench`) and `stability` (feature `stability`) on top.
//!
//! The default features build the renderer alone: the command line is the
//! `vista-cli` package (tools/vista), and the twins, benches, hard cases and
//! test switches (`test-hooks`) are features.

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

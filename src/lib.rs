//! vista: a GPU-driven terrain renderer for Vulkan (Far Cry 5 style) on ash.
//!
//! # Embedding, in short
//!
//! vista records into an engine's command buffers; the engine submits them
//! (`docs/embedding.md` has the whole contract: outputs lit, HDR or into the
//! engine's G-buffer, its depth kept, queues, frames in flight). A renderer
//! is made once and recorded each frame:
//!
//! ```no_run
//! use std::sync::Arc;
//! use vista::gpu::{vk, Context, Image, Recorder};
//! use vista::render::{RenderTargets, RendererOptions, TerrainRenderer, View};
//! use vista::world::{ProceduralSource, WorldDesc};
//!
//! /// Once, beside the engine's own passes (`ctx`: `Context::from_raw` over its device).
//! fn make(ctx: &Context) -> vista::error::Result<TerrainRenderer> {
//!     let world = WorldDesc::default(); // 10 240 m, 0.5 m spacing
//!     let source = Arc::new(ProceduralSource::new(1, world.extent_m, world.height_range_m)?);
//!     TerrainRenderer::new(ctx, &world, source, vec![], &RendererOptions::default())
//! }
//!
//! /// Each frame, into the engine's recording command buffer, before it submits.
//! fn draw(ctx: &Context, r: &mut TerrainRenderer, cmd: vk::CommandBuffer, view: &View, color: &Image, depth: &Image)
//!     -> vista::error::Result<()> {
//!     // SAFETY: `cmd` is recording, from `ctx`'s device, and the engine submits it.
//!     let mut rec = unsafe { Recorder::from_raw(ctx, cmd) };
//!     r.record(&mut rec, view, &RenderTargets::color(color, depth, [0.0; 4]))
//! }
//! ```
//!
//! # The house
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

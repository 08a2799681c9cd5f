//! [`TerrainRenderer`]: owns the terrain (streaming, GPU quadtree) and the
//! passes that turn it into pixels, and records one frame into a command
//! buffer the caller provides. Per frame, each pass wrapped by the frame
//! executor in a debug label and a timestamp pair:
//! quadtree_update -> traverse -> lod_map -> sector_data (terrain.rs), then
//! cull_patches -> terrain_geometry (one instanced indirect draw).
//!
//! Teardown: fields drop in declaration order; every Vulkan object is
//! retired to the context and destroyed once the frames using it completed.

use crate::error::{Error, Result};
use crate::frame::{FrameExecutor, FrameTimings, QueueKind};
use crate::gpu::{vk, Buffer, BufferDesc, Context, MemoryLocation, Recorder};
use crate::passes::cull_patches::{CullPatches, CullStages};
use crate::passes::terrain_geometry::{RenderTargets, TerrainGeometry, COLOR_FORMAT, DEPTH_FORMAT};
use crate::quadtree::texture_extent;
use crate::render::view::{Lighting, TerrainViewGpu, View};
use crate::shaders::structs;
use crate::terrain::{Terrain, TerrainOptions};
use crate::world::{HeightSource, Hole, WorldDesc};
use std::sync::Arc;

/// Passes of one frame (the executor's timestamp pool is sized from it).
const PASSES_PER_FRAME: u32 = 6;

#[derive(Debug, Clone, Default)]
pub struct RendererOptions {
    pub terrain: TerrainOptions,
    pub stages: CullStages,
    pub lighting: Lighting,
}

pub struct TerrainRenderer {
    pub terrain: Terrain,
    pub cull: CullPatches,
    pub geometry: TerrainGeometry,
    view_buffer: Buffer,
    exec: FrameExecutor,
    /// Culling stages of the next recorded frame.
    pub stages: CullStages,
    pub lighting: Lighting,
}

impl TerrainRenderer {
    pub fn new(
        ctx: &Context,
        world: &WorldDesc,
        source: Arc<dyn HeightSource>,
        holes: Vec<Hole>,
        options: &RendererOptions,
    ) -> Result<Self> {
        // Samples past the extent are holes whenever a root node reaches
        // beyond it; otherwise only hole regions need the vertex test.
        let root = world.node_size_m(world.root_lod());
        let ragged_edge = world.extent_m.iter().any(|e| e % root != 0.0);
        let geometry = TerrainGeometry::new(ctx, !holes.is_empty() || ragged_edge)?;
        let terrain = Terrain::new(ctx, world, source, holes, &options.terrain)?;
        let cull = CullPatches::new(ctx, &terrain.traverse, geometry.index_count())?;
        let view_buffer = Buffer::new(
            ctx,
            &BufferDesc {
                name: "terrain_view",
                size: structs::TERRAIN_VIEW as u64,
                usage: vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                location: MemoryLocation::GpuOnly,
            },
        )?;
        let exec = FrameExecutor::new(ctx, options.terrain.frames_in_flight, PASSES_PER_FRAME)?;
        Ok(TerrainRenderer {
            terrain,
            cull,
            geometry,
            view_buffer,
            exec,
            stages: options.stages,
            lighting: options.lighting,
        })
    }

    pub fn world(&self) -> &WorldDesc {
        &self.terrain.world
    }

    /// Records one frame of `view` into `rec` (the caller submits it, at most
    /// `frames_in_flight` frames ahead of the GPU). `targets` must match the
    /// view's size and the formats of [`COLOR_FORMAT`] / [`DEPTH_FORMAT`].
    pub fn record(&mut self, rec: &mut Recorder, view: &View, targets: &RenderTargets) -> Result<()> {
        view.validate()?;
        for (what, image, format) in [("colour", targets.color, COLOR_FORMAT), ("depth", targets.depth, DEPTH_FORMAT)] {
            if image.extent != view.size || image.format != format {
                return Err(Error::BadInput(format!(
                    "{what} target {} is {:?} {}x{}, the view needs {format:?} {}x{}",
                    image.name, image.format, image.extent[0], image.extent[1], view.size[0], view.size[1]
                )));
            }
        }
        let world = self.terrain.world;
        let gpu: TerrainViewGpu = view.gpu(&world, texture_extent(&world), &self.lighting);
        let mut frame = self.exec.begin(rec);
        self.terrain.record(&mut frame, &view.traverse_params())?;
        let (terrain, cull, stages, view_buffer) = (&self.terrain, &self.cull, self.stages, &self.view_buffer);
        frame.pass(CullPatches::NAME, QueueKind::Compute, |r| {
            let view_bytes = bytemuck::bytes_of(&gpu);
            cull.record(r, &terrain.traverse, &terrain.tree, &terrain.lod_map, view_buffer, view_bytes, stages);
        });
        let geometry = &self.geometry;
        frame.pass(TerrainGeometry::NAME, QueueKind::Graphics, |r| {
            geometry.record(r, targets, view_buffer, cull, &terrain.tree)
        });
        Ok(())
    }

    /// Pass timings of the newest frame the GPU has finished (one or more
    /// frames late; never waits).
    pub fn latest_timings(&self) -> Option<&FrameTimings> {
        self.exec.latest()
    }
}

//! [`TerrainRenderer`]: owns the terrain (streaming, GPU quadtree) and the
//! passes that turn it into pixels, and records one frame into a command
//! buffer the caller provides. The frame, in order, each pass wrapped by the
//! frame executor in a debug label and a timestamp pair (see `record`):
//! quadtree_update -> traverse (one dispatch) -> lod_map -> sector_data ->
//! cull_patches -> terrain_geometry (one instanced indirect draw).
//!
//! Teardown: fields drop in declaration order; every Vulkan object is
//! retired to the context and destroyed once the frames using it completed.

use crate::error::{Error, Result};
use crate::frame::{FrameExecutor, FrameTimings, QueueKind};
use crate::gpu::{vk, Buffer, BufferDesc, Context, MemoryLocation, Recorder};
use crate::passes::cull_patches::{CullPatches, CullStages};
use crate::passes::lod_map::LodMap;
use crate::passes::quadtree_update::QuadtreeUpdatePass;
use crate::passes::sector_data::SectorData;
use crate::passes::terrain_geometry::{RenderTargets, TerrainGeometry, COLOR_FORMAT, DEPTH_FORMAT};
use crate::passes::traverse::{Traverse, TraverseMode};
use crate::render::view::{Lighting, TerrainViewGpu, View};
use crate::shaders::structs;
use crate::terrain::quadtree::texture_extent;
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
    update: QuadtreeUpdatePass,
    pub traverse: Traverse,
    pub lod_map: LodMap,
    pub sector_data: SectorData,
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
        let traverse = Traverse::new(ctx, world, options.terrain.slots)?;
        let cull = CullPatches::new(ctx, &traverse, geometry.index_count())?;
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
            update: QuadtreeUpdatePass::new(ctx)?,
            lod_map: LodMap::new(ctx, world)?,
            sector_data: SectorData::new(ctx, world)?,
            terrain,
            traverse,
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
        let params = view.traverse_params();
        self.terrain.stream(&params);
        let mut frame = self.exec.begin(rec);
        let (tree, update) = (&mut self.terrain.tree, &self.update);
        frame.pass(QuadtreeUpdatePass::NAME, QueueKind::Compute, |r| update.record(r, tree))?;
        let tree = &self.terrain.tree;
        let (traverse, lod_map, sector_data) = (&self.traverse, &self.lod_map, &self.sector_data);
        frame.pass(Traverse::NAME, QueueKind::Compute, |r| {
            traverse.record(r, tree, &params, TraverseMode::SingleDispatch)
        });
        frame.pass(LodMap::NAME, QueueKind::Compute, |r| lod_map.record(r, traverse));
        frame.pass(SectorData::NAME, QueueKind::Compute, |r| sector_data.record(r, tree));
        let (cull, stages, view_buffer) = (&self.cull, self.stages, &self.view_buffer);
        frame.pass(CullPatches::NAME, QueueKind::Compute, |r| {
            let view_bytes = bytemuck::bytes_of(&gpu);
            cull.record(r, traverse, tree, lod_map, view_buffer, view_bytes, stages);
        });
        let geometry = &self.geometry;
        frame
            .pass(TerrainGeometry::NAME, QueueKind::Graphics, |r| geometry.record(r, targets, view_buffer, cull, tree));
        Ok(())
    }

    /// Pass timings of the newest frame the GPU has finished (one or more
    /// frames late; never waits).
    pub fn latest_timings(&self) -> Option<&FrameTimings> {
        self.exec.latest()
    }
}

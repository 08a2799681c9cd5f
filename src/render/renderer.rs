//! [`TerrainRenderer`]: owns the terrain (streaming, GPU quadtree) and the
//! passes that turn it into pixels, built from the scene's effects, and
//! records one frame into a command buffer the caller provides. The frame
//! is the pass graph of [`graph`](super::graph) (in order: quadtree_update,
//! traverse, lod_map, sector_data, cull_patches, terrain_geometry,
//! terrain_holes); a pass whose effect is off is not built (no pipeline, no
//! resource) and never recorded, and one with nothing to do this frame is
//! skipped (known on the CPU) or runs with zero indirect work (known only
//! on the GPU). Each recorded pass is wrapped by the frame executor in a
//! debug label and a timestamp pair.
//!
//! Teardown: fields drop in declaration order; every Vulkan object is
//! retired to the context and destroyed once the frames using it completed.

use crate::error::{Error, Result};
use crate::frame::{FrameExecutor, FrameTimings, QueueKind};
use crate::gpu::{vk, Buffer, BufferDesc, Context, MemoryLocation, Recorder};
use crate::passes::cull_patches::{CullBuild, CullPatches, CullStages};
use crate::passes::lod_map::LodMap;
use crate::passes::quadtree_update::QuadtreeUpdatePass;
use crate::passes::sector_data::SectorData;
use crate::passes::terrain_geometry::{RenderTargets, TerrainGeometry, COLOR_FORMAT, DEPTH_FORMAT};
use crate::passes::terrain_holes::TerrainHoles;
use crate::passes::traverse::{Traverse, TraverseMode};
use crate::render::effects::{decide, Effect, EffectDecision, Effects, WorldContent};
use crate::render::graph::{FramePass, PassGraph, Skip};
use crate::render::view::{TerrainViewGpu, View};
use crate::shaders::structs;
use crate::terrain::gpu_quadtree::{AtlasSet, ATLAS_NORMAL, ATLAS_PATCH_CONES, ATLAS_PATCH_HOLES, ATLAS_SPLAT};
use crate::terrain::quadtree::texture_extent;
use crate::terrain::{Terrain, TerrainOptions};
use crate::world::{HeightSource, Hole, WorldDesc};
use std::sync::Arc;

#[derive(Debug, Clone, Default)]
pub struct RendererOptions {
    /// `atlases` is replaced by what the effects need.
    pub terrain: TerrainOptions,
    /// Per-frame switches of the culling stages that are built (benchmarks
    /// and tests turn them off to show what each removes and costs).
    pub stages: CullStages,
    pub effects: Effects,
    /// Tests only: keep an effect on although the world lacks its data, to
    /// show that its path changes nothing there.
    #[doc(hidden)]
    pub force_content_gated: bool,
}

pub struct TerrainRenderer {
    pub terrain: Terrain,
    update: QuadtreeUpdatePass,
    pub traverse: Traverse,
    pub lod_map: LodMap,
    /// Effect `queries` (sector data for `TerrainQuery`).
    pub sector_data: Option<SectorData>,
    pub cull: CullPatches,
    pub geometry: TerrainGeometry,
    /// Effect `holes`.
    pub holes: Option<TerrainHoles>,
    view_buffer: Buffer,
    exec: FrameExecutor,
    pub(crate) graph: PassGraph,
    /// Culling stages of the next recorded frame (of those built).
    pub stages: CullStages,
    pub effects: Effects,
    decisions: Vec<EffectDecision>,
}

/// The payload atlases each effect reads (the normal atlas serves two).
const EFFECT_ATLASES: [(Effect, usize); 5] = [
    (Effect::Lighting, ATLAS_NORMAL),
    (Effect::ConeCull, ATLAS_PATCH_CONES),
    (Effect::Holes, ATLAS_PATCH_HOLES),
    (Effect::Queries, ATLAS_NORMAL),
    (Effect::Queries, ATLAS_SPLAT),
];

/// Whether the world has anything for the hole path to cut.
fn world_content(world: &WorldDesc, holes: &[Hole]) -> WorldContent {
    let root = world.node_size_m(world.root_lod());
    let ragged = world.extent_m.iter().any(|e| e % root != 0.0);
    let [ex, ey] = world.extent_m;
    let inside = holes
        .iter()
        .filter(|h| {
            let [x0, y0, x1, y1] = h.bounds();
            x1 > 0.0 && y1 > 0.0 && x0 < ex && y0 < ey
        })
        .count();
    let mut present = Vec::new();
    if inside > 0 {
        present.push(format!("{inside} hole region(s) in the world"));
    }
    if ragged {
        present.push(format!("the {ex} x {ey} m extent is not a whole number of {root} m root nodes: the edge is cut"));
    }
    let missing = present.is_empty().then(|| {
        let outside = if holes.is_empty() { String::new() } else { format!(" ({} lie outside it)", holes.len()) };
        format!("the world has no hole regions{outside} and its extent is a whole number of root nodes")
    });
    WorldContent { holes_missing: missing, holes_present: present.join("; ") }
}

impl TerrainRenderer {
    pub fn new(
        ctx: &Context,
        world: &WorldDesc,
        source: Arc<dyn HeightSource>,
        holes: Vec<Hole>,
        options: &RendererOptions,
    ) -> Result<Self> {
        let decisions = decide(&options.effects, &world_content(world, &holes), options.force_content_gated);
        let on = |e: Effect| decisions.iter().any(|d| d.effect == e && d.on);
        let mut atlases = AtlasSet::CORE;
        for (effect, atlas) in EFFECT_ATLASES {
            if on(effect) {
                atlases = atlases.with(atlas);
            }
        }
        let terrain_options = TerrainOptions { atlases, ..options.terrain.clone() };
        let lighting = on(Effect::Lighting);
        let geometry = TerrainGeometry::new(ctx, lighting)?;
        let terrain = Terrain::new(ctx, world, source, holes, &terrain_options)?;
        let traverse = Traverse::new(ctx, world, options.terrain.slots)?;
        let build = CullBuild { cone: on(Effect::ConeCull), holes: on(Effect::Holes) };
        let cull = CullPatches::new(ctx, &traverse, geometry.index_count(), build)?;
        let holes_pass = if build.holes { Some(TerrainHoles::new(ctx, lighting)?) } else { None };
        let sector_data = if on(Effect::Queries) { Some(SectorData::new(ctx, world)?) } else { None };
        let view_buffer = Buffer::new(
            ctx,
            &BufferDesc {
                name: "terrain_view",
                size: structs::TERRAIN_VIEW as u64,
                usage: vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                location: MemoryLocation::GpuOnly,
            },
        )?;
        let graph = PassGraph::new(&decisions);
        let exec = FrameExecutor::new(ctx, options.terrain.frames_in_flight, graph.max_recorded())?;
        Ok(TerrainRenderer {
            update: QuadtreeUpdatePass::new(ctx)?,
            lod_map: LodMap::new(ctx, world)?,
            sector_data,
            terrain,
            traverse,
            cull,
            geometry,
            holes: holes_pass,
            view_buffer,
            exec,
            graph,
            stages: options.stages,
            effects: options.effects.clone(),
            decisions,
        })
    }

    pub fn world(&self) -> &WorldDesc {
        &self.terrain.world
    }

    /// What became of each effect, and why.
    pub fn effects(&self) -> &[EffectDecision] {
        &self.decisions
    }

    /// Whether `effect` is built.
    pub fn effect_on(&self, effect: Effect) -> bool {
        self.decisions.iter().any(|d| d.effect == effect && d.on)
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
        let gpu: TerrainViewGpu = view.gpu(&world, texture_extent(&world), &self.effects.lighting);
        let params = view.traverse_params();
        self.terrain.stream(&params);
        let mut frame = self.exec.begin(rec);
        let mut log = self.graph.begin_frame(frame.number());

        if self.terrain.tree.has_work() {
            let (tree, update) = (&mut self.terrain.tree, &self.update);
            let writes = frame.pass(QuadtreeUpdatePass::NAME, QueueKind::Compute, |r| update.record(r, tree))?;
            log.ran(FramePass::QuadtreeUpdate, Some(u64::from(writes)));
        } else {
            log.skipped(FramePass::QuadtreeUpdate, Skip::NothingToUpload);
        }
        let tree = &self.terrain.tree;
        let (traverse, lod_map) = (&self.traverse, &self.lod_map);
        frame.pass(Traverse::NAME, QueueKind::Compute, |r| {
            traverse.record(r, tree, &params, TraverseMode::SingleDispatch)
        });
        log.ran(FramePass::Traverse, None);
        frame.pass(LodMap::NAME, QueueKind::Compute, |r| lod_map.record(r, traverse));
        log.ran(FramePass::LodMap, None);
        if let Some(sector_data) = &self.sector_data {
            frame.pass(SectorData::NAME, QueueKind::Compute, |r| sector_data.record(r, tree));
            log.ran(FramePass::SectorData, None);
        }
        let (cull, stages, view_buffer) = (&self.cull, self.stages, &self.view_buffer);
        frame.pass(CullPatches::NAME, QueueKind::Compute, |r| {
            let view_bytes = bytemuck::bytes_of(&gpu);
            cull.record(r, traverse, tree, lod_map, view_buffer, view_bytes, stages);
        });
        log.ran(FramePass::CullPatches, None);
        let geometry = &self.geometry;
        frame
            .pass(TerrainGeometry::NAME, QueueKind::Graphics, |r| geometry.record(r, targets, view_buffer, cull, tree));
        log.ran(FramePass::TerrainGeometry, None);
        if let Some(holes) = &self.holes {
            frame.pass(TerrainHoles::NAME, QueueKind::Graphics, |r| {
                holes.record(r, targets, view_buffer, cull, geometry, tree)
            });
            log.ran(FramePass::TerrainHoles, None);
        }
        self.graph.end_frame(log);
        Ok(())
    }

    /// Pass timings of the newest frame the GPU has finished (one or more
    /// frames late; never waits).
    pub fn latest_timings(&self) -> Option<&FrameTimings> {
        self.exec.latest()
    }

    /// Collects timings of frames that finished since the last `record`
    /// (never waits) and returns the newest.
    pub fn poll_timings(&mut self) -> Option<&FrameTimings> {
        self.exec.poll();
        self.exec.latest()
    }

    /// Frames recorded so far (the number of the last one).
    pub fn frames_recorded(&self) -> u64 {
        self.graph.last_frame().map_or(0, |l| l.frame)
    }

    /// Labels of every pipeline built (variant switches included).
    pub fn pipelines(&self) -> Vec<String> {
        let mut out = vec![
            self.update.pipeline_label().to_string(),
            self.traverse.pipeline_label().to_string(),
            self.lod_map.pipeline_label().to_string(),
        ];
        if let Some(s) = &self.sector_data {
            out.push(s.pipeline_label().to_string());
        }
        out.push(self.cull.pipeline_label().to_string());
        out.push(self.geometry.pipeline_label().to_string());
        if let Some(h) = &self.holes {
            out.push(h.pipeline_label().to_string());
        }
        out
    }

    /// Device memory of every resource the renderer owns, with the effects
    /// it exists for (empty: needed by any scene).
    pub fn memory(&self) -> Vec<(String, u64, Vec<Effect>)> {
        let atlas_users = |i: usize| -> Vec<Effect> {
            EFFECT_ATLASES.iter().filter(|(e, a)| *a == i && self.effect_on(*e)).map(|(e, _)| *e).collect()
        };
        let mut out: Vec<(String, u64, Vec<Effect>)> = self
            .terrain
            .tree
            .memory()
            .into_iter()
            .map(|(name, bytes, atlas)| (name, bytes, atlas.map(atlas_users).unwrap_or_default()))
            .collect();
        for (name, bytes) in self.traverse.memory() {
            out.push((name, bytes, Vec::new()));
        }
        let core = [
            (&self.lod_map.image.name, self.lod_map.image.memory_bytes()),
            (&self.cull.list.name, self.cull.list.memory_bytes()),
            (&self.view_buffer.name, self.view_buffer.memory_bytes()),
            (&self.geometry.indices().name, self.geometry.indices().memory_bytes()),
        ];
        out.extend(core.into_iter().map(|(n, b)| (n.clone(), b, Vec::new())));
        if let Some(h) = &self.cull.hole_list {
            out.push((h.name.clone(), h.memory_bytes(), vec![Effect::Holes]));
        }
        if let Some(s) = &self.sector_data {
            out.push((s.buffer.name.clone(), s.buffer.memory_bytes(), vec![Effect::Queries]));
        }
        out
    }
}

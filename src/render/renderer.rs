//! [`TerrainRenderer`]: owns the terrain (streaming, GPU quadtree) and the
//! passes that turn it into pixels, built from the scene's effects, and
//! records one frame into a command buffer the caller provides. The frame
//! is the pass graph of [`graph`](super::graph) (in order: quadtree_update,
//! traverse, lod_map, sector_data, select_patches, cull_patches, terrain_geometry,
//! terrain_holes, the occlusion passes, classify_tiles, gbuffer_tiles,
//! lighting_resolve); a pass whose effect is off is not built (no pipeline, no
//! resource) and never recorded, and one with nothing to do this frame is
//! skipped (known on the CPU) or runs with zero indirect work (known only
//! on the GPU). Each recorded pass is wrapped by the frame executor in a
//! debug label and a timestamp pair.
//!
//! Teardown: fields drop in declaration order; every Vulkan object is
//! retired to the context and destroyed once the frames using it completed.

use crate::effects::assets::Asset;
use crate::effects::grass::gpu::{Grass, GrassFrameInputs};
use crate::effects::materials::gpu::MaterialResources;
use crate::effects::shadows::sun_shadows::{SunShadowJob, SunShadows};
use crate::effects::shadows::{MarchSun, NodeExtent, ShadowSchedule};
use crate::effects::virtual_texture::decals::{Decal, DecalSet};
use crate::effects::virtual_texture::{VirtualTexture, VtCamera, VtFrame};
use crate::effects::{decide, Effect, EffectDecision, Effects, FrameSwitches, MaterialsMode, WorldContent};
use crate::error::{Error, Result};
use crate::frame::per_frame::{copy_name, PerFrame};
use crate::frame::{FrameExecutor, FrameTimings, QueueKind};
use crate::gpu::{vk, Buffer, BufferDesc, Context, FrameCommands, MemoryLocation, QueueMode, Recorder};
use crate::passes::classify_tiles::ClassifyTiles;
use crate::passes::cull_occluded::CullOccluded;
use crate::passes::cull_patches::{CullBuild, CullPatches, CullStages};
use crate::passes::debug_view::{DebugView, DebugViewPass};
use crate::passes::gbuffer_tiles::{GbufferTiles, TileMaterials};
use crate::passes::hiz_build::HizBuild;
use crate::passes::lighting_resolve::{LightingResolve, ResolveTarget};
use crate::passes::lod_map::LodMap;
use crate::passes::quadtree_update::QuadtreeUpdatePass;
use crate::passes::sector_data::SectorData;
use crate::passes::select_patches::SelectPatches;
use crate::passes::terrain_geometry::{DepthOptions, RenderTargets, TerrainGeometry};
use crate::passes::terrain_holes::TerrainHoles;
use crate::passes::terrain_query::VistaTerrain;
use crate::passes::traverse::Traverse;
use crate::render::frame_passes::FramePasses;
use crate::render::near_geometry::{NearBuild, NearGeometry};
use crate::render::telemetry::TRIANGLES_PER_PATCH;
use crate::render::telemetry::{CounterLayout, CounterSources, FrameCounters, Telemetry};
use crate::scene::graph::{FramePass, PassGraph, Skip};
use crate::scene::shading::{ShadeRules, Shading};
use crate::scene::view::{TerrainViewGpu, View};
use crate::shaders::structs;
use crate::targets::gbuffer::GBuffer;
use crate::targets::Output;
use crate::terrain::gpu_quadtree::{
    AtlasSet, ATLAS_CONTROL, ATLAS_NORMAL, ATLAS_PATCH_CONES, ATLAS_PATCH_HOLES, ATLAS_SPLAT,
};
use crate::terrain::quadtree::texture_extent;
use crate::terrain::{Terrain, TerrainOptions};
use crate::world::{HeightSource, Hole, NodeId, WorldDesc};
use std::sync::Arc;

#[derive(Debug, Clone, Default)]
pub struct RendererOptions {
    /// `atlases` is replaced by what the effects need.
    pub terrain: TerrainOptions,
    /// Per-frame switches of the culling stages that are built (benchmarks
    /// and tests turn them off to show what each removes and costs).
    pub stages: CullStages,
    pub effects: Effects,
    /// Tiled (default), or one pipeline for every tile: the references the
    /// tiled shading is compared with in tests and `vista bench shade`.
    pub shading: Shading,
    /// Where the world's south-west corner lies in the caller's coordinates
    /// (e.g. UTM metres east, north): views are given in those coordinates
    /// and made world-relative in f64 before anything is rounded to f32.
    pub origin_m: [f64; 2],
    /// Tests only (feature `test-hooks`): keep an effect on although the
    /// world lacks its data, to show that its path changes nothing there.
    #[cfg(feature = "test-hooks")]
    pub force_content_gated: bool,
    /// What the per-patch LOD selection may do.
    pub lod: LodOptions,
    /// The engine's depth target: format and terrain stencil bit.
    pub depth: DepthOptions,
    /// Effect `decals`: the decals (world metres, like holes) and their
    /// textures; [`TerrainRenderer::set_decals`] edits them later.
    pub decals: DecalSet,
    /// Effect `assets`: the example assets (world metres, like holes).
    pub assets: Vec<Asset>,
    /// What a frame writes for the engine: vista's lit picture (`lit`,
    /// the default), linear radiance (`hdr`) or the engine's G-buffer.
    pub output: Output,
}

/// Per-patch LOD selection settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LodOptions {
    /// Levels of refinement below LOD 0 allowed (0: none; 1: 2x; 2: 4x, the
    /// finest surface the error tree measures against). Below the finest,
    /// the error bound reported is the refused level's.
    pub refine_levels: u32,
    /// Tests only (feature `test-hooks`): off, edges are not snapped to
    /// coarser neighbours (seams open), to show that the watertightness
    /// tests can fail.
    #[cfg(feature = "test-hooks")]
    pub stitching: bool,
}

impl LodOptions {
    /// Edges snap to coarser neighbours (always, but in a test that opens
    /// the seams).
    fn stitched(&self) -> bool {
        #[cfg(feature = "test-hooks")]
        return self.stitching;
        #[cfg(not(feature = "test-hooks"))]
        true
    }
}

impl RendererOptions {
    /// Effects stay on without their data (a test's override).
    fn forced(&self) -> bool {
        #[cfg(feature = "test-hooks")]
        return self.force_content_gated;
        #[cfg(not(feature = "test-hooks"))]
        false
    }
}

impl Default for LodOptions {
    fn default() -> Self {
        LodOptions {
            refine_levels: crate::shaders::consts::REFINE_LEVELS,
            #[cfg(feature = "test-hooks")]
            stitching: true,
        }
    }
}

pub struct TerrainRenderer {
    pub terrain: Terrain,
    update: QuadtreeUpdatePass,
    pub traverse: Traverse,
    pub lod_map: LodMap,
    /// Where any shader finds the terrain: the tile shading and `TerrainQuery`.
    pub sector_data: SectorData,
    /// Per-patch LOD selection (always built).
    pub select: SelectPatches,
    pub cull: CullPatches,
    /// Effect `occlusion`: the depth pyramid and phase 2's culling.
    pub occlusion: Option<Occlusion>,
    pub geometry: TerrainGeometry,
    /// Effect `holes`.
    pub holes: Option<TerrainHoles>,
    pub classify: ClassifyTiles,
    pub gbuffer_tiles: GbufferTiles,
    /// Outputs `lit` and `hdr` (None with output `gbuffer`: the engine lights).
    pub resolve: Option<LightingResolve>,
    /// Effect `shadows`: the pass, its atlas, and which nodes it redoes when.
    pub sun_shadows: Option<SunShadows>,
    pub shadow_schedule: ShadowSchedule,
    /// Effects `splat` or `cliffs`: the material table and detail textures.
    pub materials: Option<MaterialResources>,
    /// Effect `virtual_texture`: its cache, indirection and passes.
    pub virtual_texture: Option<VirtualTexture>,
    /// Effects `grass`, `assets`, `cliff_meshes` and the displacement
    /// decals' meshes: geometry beside the height field near the camera.
    pub near: NearGeometry,
    /// Made for the view size on the first frame (remade when it changes).
    pub gbuffer: Option<GBuffer>,
    pub shade: ShadeRules,
    shading: Shading,
    /// Per-patch LOD settings of the next recorded frame.
    pub lod: LodOptions,
    /// One per frame parity (`frame::per_frame`), like what the LOD phase
    /// writes: the compute submission writes it.
    view_buffer: PerFrame<Buffer>,
    telemetry: Telemetry,
    exec: FrameExecutor,
    pub(crate) graph: PassGraph,
    /// Culling stages of the next recorded frame (of those built).
    pub stages: CullStages,
    /// Effects of the next recorded frame that a built renderer can switch
    /// off without rebuilding (of those built).
    pub switches: FrameSwitches,
    /// Shadows were switched off in an earlier frame and not back on yet.
    shadows_were_off: bool,
    /// What the next frame shows over its picture (`vista view`'s selector).
    pub debug_view: Option<DebugView>,
    /// Its pass, made the first time a view is asked for.
    debug_pass: Option<DebugViewPass>,
    pub effects: Effects,
    output: Output,
    /// See [`RendererOptions::origin_m`]; may change between frames.
    pub origin_m: [f64; 2],
    decisions: Vec<EffectDecision>,
    /// How the last frame was recorded.
    mode: Option<QueueMode>,
}

/// The passes of effect `occlusion` (phase 2).
pub struct Occlusion {
    pub hiz: HizBuild,
    pub cull: CullOccluded,
}

/// The stage a graphics submission must wait at for the compute
/// submission's timeline value (see [`TerrainRenderer::record_split`]).
pub const GRAPHICS_WAIT_STAGE: vk::PipelineStageFlags2 = vk::PipelineStageFlags2::ALL_COMMANDS;

/// The payload atlases each effect reads beyond the core ones (the splat
/// map serves three; in control-map mode `splat` reads the control words).
fn effect_atlases(mode: MaterialsMode) -> [(Effect, usize); 5] {
    let near = match mode {
        MaterialsMode::Splat => ATLAS_SPLAT,
        MaterialsMode::ControlMap => ATLAS_CONTROL,
    };
    [
        (Effect::ConeCull, ATLAS_PATCH_CONES),
        (Effect::Holes, ATLAS_PATCH_HOLES),
        (Effect::Queries, ATLAS_SPLAT),
        (Effect::Splat, near),
        (Effect::Cliffs, ATLAS_SPLAT),
    ]
}

/// The patch lists whose headers hold a frame's counters, in telemetry
/// order: phase 1 solid, holes; phase 2 solid, holes.
fn counter_lists<'a>(cull: &'a CullPatches, occlusion: &'a Option<Occlusion>) -> [Option<&'a Buffer>; 4] {
    let late = occlusion.as_ref().map(|o| &o.cull.lists);
    [
        Some(&cull.lists().list),
        cull.lists().hole_list.as_ref(),
        late.map(|l| &l.list),
        late.and_then(|l| l.hole_list.as_ref()),
    ]
}

/// Whether the world has anything for the hole path to cut.
/// The payload atlases a renderer keeps on the GPU for these decisions:
/// the core ones, the normal (the geometry pass classifies by it), and
/// each atlas an effect that is on reads.
fn atlases_for(decisions: &[EffectDecision], mode: MaterialsMode) -> AtlasSet {
    let on = |e: Effect| decisions.iter().any(|d| d.effect == e && d.on);
    effect_atlases(mode)
        .iter()
        .filter(|(effect, _)| on(*effect))
        .fold(AtlasSet::CORE.with(ATLAS_NORMAL), |set, (_, atlas)| set.with(*atlas))
}

/// Memory of `slots` resident nodes as a renderer of `effects` over this
/// world keeps them (what `vista memory` prints): payload kinds no effect
/// reads are baked, not kept on the GPU.
pub fn memory_for(
    slots: usize,
    format: crate::world::PayloadFormat,
    effects: &Effects,
    world: &WorldDesc,
    holes: &[Hole],
    source_holes: bool,
) -> crate::world::MemoryReport {
    let decisions = decide(effects, &world_content(world, holes, source_holes, 0, 0), false);
    // (The output does not change what the atlases hold.)
    let mut report = crate::world::MemoryReport::for_format(slots, format);
    if effects.materials == MaterialsMode::ControlMap {
        report = report.with_control();
    }
    crate::terrain::mask_memory(report, atlases_for(&decisions, effects.materials))
}

/// Effect `virtual_texture`: plans the frame's pages and writes (`frame`:
/// the renderer's and the context's numbers of it).
fn begin_virtual_texture(
    vt: &mut VirtualTexture,
    terrain: &Terrain,
    ctx: &Context,
    frame: [u64; 2],
    view: &View,
    shade: &ShadeRules,
) -> VtFrame {
    let camera = VtCamera {
        xy: [view.camera.position_m[0], view.camera.position_m[1]],
        pixel_rad: 2.0 * (view.fov_y_deg.to_radians() * 0.5).tan() / f64::from(view.size[1]),
        // A pixel at the near flavour's far end can lie this far away.
        range_m: f64::from(shade.far_end_m) * view.corner_secant(),
        size: view.size,
    };
    vt.begin_frame(ctx, frame[0], frame[1], camera, terrain)
}

/// `source_holes`: the height source has holes of its own (a DEM's no-data
/// samples).
fn world_content(world: &WorldDesc, holes: &[Hole], source_holes: bool, decals: usize, assets: usize) -> WorldContent {
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
    if source_holes {
        present.push("the height map's no-data samples".to_string());
    }
    if ragged {
        present.push(format!("the {ex} x {ey} m extent is not a whole number of {root} m root nodes: the edge is cut"));
    }
    let missing = present.is_empty().then(|| {
        let outside = if holes.is_empty() { String::new() } else { format!(" ({} lie outside it)", holes.len()) };
        format!("the world has no hole regions{outside} and its extent is a whole number of root nodes")
    });
    WorldContent { holes_missing: missing, holes_present: present.join("; "), decals, assets, engine_lights: false }
}

impl TerrainRenderer {
    pub fn new(
        ctx: &Context,
        world: &WorldDesc,
        source: Arc<dyn HeightSource>,
        holes: Vec<Hole>,
        options: &RendererOptions,
    ) -> Result<Self> {
        // Before any pass allocates: a world over its limits fails alone.
        crate::terrain::check_plan(ctx, world, &options.terrain)?;
        options.depth.check().map_err(Error::BadInput)?;
        options.output.check().map_err(Error::BadInput)?;
        let depth = options.depth;
        let mut content =
            world_content(world, &holes, source.has_holes(), options.decals.decals.len(), options.assets.len());
        content.engine_lights = !options.output.lights();
        let decisions = decide(&options.effects, &content, options.forced());
        let on = |e: Effect| decisions.iter().any(|d| d.effect == e && d.on);
        let atlases = atlases_for(&decisions, options.effects.materials);
        let mut terrain_options = TerrainOptions { atlases, ..options.terrain.clone() };
        if atlases.contains(ATLAS_CONTROL) && terrain_options.bake.control.is_none() {
            // The control-map flavour reads control words: bake them (from
            // the scene's map or the material rules) unless the caller did.
            let rules = terrain_options.bake.materials;
            terrain_options.bake.control = crate::effects::materials::control_bake(&options.effects, world, rules)?;
        }
        let geometry = TerrainGeometry::new(ctx, depth)?;
        let mut shade =
            options.effects.shade.allowing(options.effects.materials, on(Effect::Splat), on(Effect::Cliffs));
        if on(Effect::VirtualTexture) {
            shade = shade.with_virtual_texture();
        }
        let materials = if on(Effect::Splat) || on(Effect::Cliffs) {
            Some(MaterialResources::new(ctx, &options.effects)?)
        } else {
            None
        };
        let variants = options.shading.pipelines(&shade);
        let every = options.shading == Shading::OneShaderEveryFlavour;
        let tile_materials = match (&materials, options.effects.materials) {
            (None, _) => TileMaterials::None,
            (Some(_), MaterialsMode::Splat) if on(Effect::VirtualTexture) => TileMaterials::SplatVirtualTexture,
            (Some(_), MaterialsMode::Splat) => TileMaterials::Splat,
            (Some(_), MaterialsMode::ControlMap) => TileMaterials::ControlMap,
        };
        let layout = options.output.gbuffer();
        let gbuffer_tiles = GbufferTiles::new(ctx, &variants, tile_materials, every, depth.format, layout)?;
        let terrain = Terrain::new(ctx, world, source, holes, &terrain_options)?;
        let traverse = Traverse::new(ctx, world, options.terrain.slots)?;
        // Per-slot resources cover the reload slots too (gpu_quadtree::RELOAD_SLOTS).
        let slot_capacity = terrain.tree.slot_capacity();
        let build =
            CullBuild { cone: on(Effect::ConeCull), holes: on(Effect::Holes), occlusion: on(Effect::Occlusion) };
        let cull = CullPatches::new(ctx, &traverse, geometry.index_count(), build)?;
        let occlusion = if build.occlusion {
            let occluded = CullOccluded::new(ctx, &traverse, geometry.index_count(), build, slot_capacity)?;
            Some(Occlusion { hiz: HizBuild::new(ctx)?, cull: occluded })
        } else {
            None
        };
        let holes_pass = if build.holes { Some(TerrainHoles::new(ctx, depth)?) } else { None };
        let sector_data = SectorData::new(ctx, world)?;
        let view_buffer = PerFrame::new(|i| {
            Buffer::new(
                ctx,
                &BufferDesc {
                    name: &copy_name("terrain_view", i),
                    size: structs::TERRAIN_VIEW as u64,
                    usage: vk::BufferUsageFlags::STORAGE_BUFFER
                        | vk::BufferUsageFlags::TRANSFER_DST
                        | vk::BufferUsageFlags::TRANSFER_SRC,
                    location: MemoryLocation::GpuOnly,
                },
            )
        })?;
        let mut graph = PassGraph::new(&decisions);
        if layout.is_some() {
            graph.not_built(FramePass::LightingResolve, "output gbuffer: the engine lights the G-buffer".into());
            graph.not_built(FramePass::DebugView, "output gbuffer: no colour target to draw a debug view over".into());
        }
        let near_build =
            NearBuild { options, on: &on, occlusion: build.occlusion, materials: materials.is_some(), depth, layout };
        let near = NearGeometry::new(ctx, &near_build, &mut graph)?;
        // gbuffer_tiles records one timed draw per variant.
        let max_passes = graph.max_recorded() + variants.len() as u32;
        let exec = FrameExecutor::new(ctx, options.terrain.frames_in_flight, max_passes)?;
        let layout = CounterLayout {
            holes: build.holes,
            occlusion: build.occlusion,
            lod_count: world.lod_count,
            list_capacity: cull.lists().capacity,
            triangles_per_patch: TRIANGLES_PER_PATCH,
            grass: on(Effect::Grass),
        };
        Ok(TerrainRenderer {
            update: QuadtreeUpdatePass::new(ctx, build.occlusion)?,
            lod_map: LodMap::new(ctx, world)?,
            sector_data,
            terrain,
            select: SelectPatches::new(ctx, world, slot_capacity)?,
            traverse,
            cull,
            occlusion,
            geometry,
            holes: holes_pass,
            classify: ClassifyTiles::new(ctx)?,
            gbuffer_tiles,
            resolve: match ResolveTarget::of(&options.output) {
                Some(target) => Some(LightingResolve::new(
                    ctx,
                    (on(Effect::Lighting), on(Effect::Shadows), on(Effect::Atmosphere)),
                    depth.format,
                    target,
                )?),
                None => None,
            },
            sun_shadows: if on(Effect::Shadows) {
                Some(SunShadows::new(ctx, options.effects.shadows, slot_capacity)?)
            } else {
                None
            },
            shadow_schedule: ShadowSchedule::default(),
            virtual_texture: if on(Effect::VirtualTexture) {
                let extent = world.extent_m;
                Some(VirtualTexture::new(
                    ctx,
                    extent,
                    options.effects.virtual_texture,
                    options.terrain.frames_in_flight,
                    on(Effect::Decals).then_some(&options.decals),
                )?)
            } else {
                None
            },
            near,
            materials,
            gbuffer: None,
            shade,
            shading: options.shading,
            lod: options.lod,
            view_buffer,
            telemetry: Telemetry::new(ctx, options.terrain.frames_in_flight, layout)?,
            exec,
            graph,
            stages: options.stages,
            switches: FrameSwitches::default(),
            shadows_were_off: false,
            debug_view: None,
            debug_pass: None,
            effects: options.effects.clone(),
            output: options.output.clone(),
            origin_m: options.origin_m,
            decisions,
            mode: None,
        })
    }

    pub fn world(&self) -> &WorldDesc {
        &self.terrain.world
    }

    /// What became of each effect, and why.
    pub fn effects(&self) -> &[EffectDecision] {
        &self.decisions
    }

    /// The depth target it was built for.
    pub fn depth(&self) -> DepthOptions {
        self.geometry.depth()
    }

    /// The GPU's copy of the newest frame's `TerrainViewGpu` (tests read
    /// it back).
    pub fn view_buffer(&self) -> &Buffer {
        self.view_buffer.current()
    }

    /// Whether `effect` is built.
    pub fn effect_on(&self, effect: Effect) -> bool {
        self.decisions.iter().any(|d| d.effect == effect && d.on)
    }

    /// Records one frame of `view` into `rec` (the caller submits it, at most
    /// `frames_in_flight` frames ahead of the GPU, and reports its completion
    /// with `Context::frame_completed`). `targets` must match the view's
    /// size, the output's colour format or G-buffer layout
    /// (`RendererOptions::output`) and the depth format of
    /// `RendererOptions::depth` (by default
    /// [`crate::passes::terrain_geometry::DEPTH_FORMAT`]); the depth target
    /// needs SAMPLED usage.
    pub fn record(&mut self, rec: &mut Recorder, view: &View, targets: &RenderTargets) -> Result<()> {
        self.record_frame(FrameCommands::One(rec), QueueMode::Single, view, targets)
    }

    /// Records one frame split in two command buffers: `compute` (streaming
    /// uploads, traversal, LOD map, sector data, phase 1 culling) and
    /// `graphics` (the draws, the depth pyramid and phase 2). The caller
    /// submits `compute` first, to a queue of the compute family
    /// (`async_queue`) or the graphics queue, signalling a timeline
    /// semaphore value that the `graphics` submission waits for at
    /// [`GRAPHICS_WAIT_STAGE`]; `compute` must also wait for the `graphics`
    /// submission of the frame [`crate::gpu::COMPUTE_LAG`] (2) frames back,
    /// the last to read the per-frame copies it rewrites
    /// (`frame::per_frame`), and need not wait for the previous frame's: on
    /// a compute-only queue it runs beside it (see `FrameRing` for the
    /// scheme on two timeline semaphores). Resources that cross the queues
    /// are created with concurrent sharing (`gpu` docs).
    pub fn record_split<'c>(
        &mut self,
        compute: &mut Recorder<'c>,
        graphics: &mut Recorder<'c>,
        async_queue: bool,
        view: &View,
        targets: &RenderTargets,
    ) -> Result<()> {
        let mode = if async_queue { QueueMode::AsyncCompute } else { QueueMode::SplitOneQueue };
        mode.check(compute.context().info())?;
        self.record_frame(FrameCommands::Split { compute, graphics }, mode, view, targets)
    }

    /// Records one frame into the command buffers of `mode`.
    pub fn record_frame(
        &mut self,
        mut cmds: FrameCommands,
        mode: QueueMode,
        view: &View,
        targets: &RenderTargets,
    ) -> Result<()> {
        let view = &self.check_frame(view, targets)?;
        let ctx = match &mut cmds {
            FrameCommands::One(r) => r.context(),
            FrameCommands::Split { graphics, .. } => graphics.context(),
        };
        self.prepare_frame(ctx, view, targets)?;
        let ctx_frame = ctx.frame_recording();
        self.telemetry.harvest(ctx);
        let world = self.terrain.world;
        let shade = self.frame_shade();
        let mut gpu: TerrainViewGpu = view.gpu(&world, texture_extent(&world), &self.effects.lighting, &shade);
        gpu.lod_params[2] = self.lod.refine_levels as f32;
        gpu.lod_params[3] = if self.lod.stitched() { 0.0 } else { 1.0 };
        let params = view.traverse_params();
        self.terrain.stream(&params)?;
        let fog = (self.effect_on(Effect::Atmosphere) && self.switches.on(Effect::Atmosphere))
            .then(|| self.effects.atmosphere.gpu(world.height_range_m[0]));
        let switched_off = self.switched_off();
        self.select_copies(self.exec.next_frame());
        let mut frame = self.exec.begin(cmds, mode);
        let number = frame.number();
        let mut log = self.graph.begin_frame(number);
        log.switched_off = switched_off;
        let visibility = self.occlusion.as_ref().map(|o| o.cull.visibility());
        let near_inputs = GrassFrameInputs {
            camera_world: [gpu.camera_world[0], gpu.camera_world[1], gpu.camera_world[2]],
            terrain: VistaTerrain::new(&world, &self.sector_data),
            depth_size: targets.depth.extent,
            holes: self.holes.is_some() && self.switches.holes,
            hiz: self.occlusion.is_some() && self.stages.occlusion,
            terrain_changed: self.terrain.tree.has_work(),
        };
        let uploaded = self.virtual_texture.as_ref().and_then(VirtualTexture::uploaded_decals);
        let near = self.near.plan(&near_inputs, uploaded);
        // The last frame's changes reach this frame's node texture copy too.
        if self.terrain.tree.has_work() || self.terrain.tree.previous_updates().is_some() {
            let (tree, update) = (&mut self.terrain.tree, &self.update);
            let writes = frame
                .pass(QuadtreeUpdatePass::NAME, false, QueueKind::Compute, |r| update.record(r, tree, visibility))?;
            log.ran(FramePass::QuadtreeUpdate, Some(u64::from(writes)));
        } else {
            log.skipped(FramePass::QuadtreeUpdate, Skip::NothingToUpload);
        }
        let sun = self.effects.lighting.sun_dir();
        let shadows = ShadowState {
            pass: self.sun_shadows.as_ref(),
            on: self.switches.on(Effect::Shadows),
            schedule: &mut self.shadow_schedule,
            were_off: &mut self.shadows_were_off,
        };
        let jobs = shadows.jobs(&self.terrain, sun);
        // Switched back on, the shadows show once every slot holds its own
        // node's texture again; until then the lighting goes without them.
        let shadows_on = self.switches.on(Effect::Shadows);
        let shadows_shown = shadows_on && self.shadow_schedule.ready();
        if self.sun_shadows.is_some() && shadows_on && !shadows_shown {
            log.switched_off.insert(0, Effect::Shadows);
        }
        let vt = self.virtual_texture.as_mut();
        let vt_frame = vt.map(|vt| begin_virtual_texture(vt, &self.terrain, ctx, [number, ctx_frame], view, &shade));
        let sw = self.switches;
        if let Some(resolve) = &mut self.resolve {
            resolve.prepare(ctx, sw.lighting, shadows_shown, sw.on(Effect::Atmosphere))?;
        }
        let tree = &self.terrain.tree;
        let passes = FramePasses {
            traverse: &self.traverse,
            lod_map: &self.lod_map,
            sector_data: &self.sector_data,
            select: &self.select,
            cull: &self.cull,
            occlusion: self.occlusion.as_ref(),
            geometry: &self.geometry,
            holes: self.holes.as_ref(),
            classify: &self.classify,
            gbuffer_tiles: &self.gbuffer_tiles,
            resolve: self.resolve.as_ref(),
            shadows: self
                .sun_shadows
                .as_ref()
                .filter(|_| shadows_on)
                .map(|s| (s, jobs.as_slice(), sun, self.effects.lighting.sun_elevation_deg)),
            shadows_off: self.sun_shadows.is_some() && !shadows_on,
            debug: self.debug_pass.as_ref().zip(self.debug_view),
            fog,
            materials: self.materials.as_ref(),
            virtual_texture: self.virtual_texture.as_ref().zip(vt_frame.as_ref()),
            view_buffer: self.view_buffer.current(),
            stages: self.stages,
            holes_off: !sw.holes,
            force_flavours: if self.shading == Shading::Tiled { 0 } else { shade.allowed },
            grass: self.near.grass.as_ref().zip(near.grass.as_ref()),
            assets: self.near.assets.as_ref(),
            decal_meshes: self.near.decal_meshes.as_ref(),
            cliff_meshes: self.near.cliff_meshes.as_ref().map(|c| (c, near.cliff_build.as_ref())),
        };
        let gb = self.gbuffer.as_ref().expect("made above");
        passes.record_lod(&mut frame, &mut log, tree, &params, &gpu, visibility);
        passes.record_draws(&mut frame, &mut log, tree, targets, gb);
        passes.record_cliff_meshes(&mut frame, &mut log, tree, targets, gb);
        passes.record_decal_meshes(&mut frame, &mut log, tree, &world, targets, gb);
        passes.record_shading(&mut frame, &mut log, tree, &world, targets, gb);
        let sources = CounterSources {
            traverse: self.traverse.output(),
            lists: counter_lists(&self.cull, &self.occlusion),
            tiles: self.classify.lists.as_ref().map(|l| &l.buffer),
            select: self.select.levels(),
            grass: self.near.grass.as_ref().map(Grass::header),
        };
        let telemetry = &mut self.telemetry;
        frame.untimed(QueueKind::Graphics, |r| telemetry.record(r, number, ctx_frame, &sources));
        drop(frame);
        self.graph.end_frame(log);
        self.mode = Some(mode);
        Ok(())
    }

    /// Frame `frame` writes its parity's copy of what the compute work
    /// rewrites each frame (`frame::per_frame`).
    fn select_copies(&mut self, frame: u64) {
        self.terrain.tree.begin_frame(frame);
        self.traverse.select_frame(frame);
        self.lod_map.select_frame(frame);
        self.sector_data.select_frame(frame);
        self.select.select_frame(frame);
        self.cull.select_frame(frame);
        if let Some(o) = &mut self.occlusion {
            o.cull.select_frame(frame);
        }
        self.view_buffer.select(frame);
    }

    /// Built effects switched off for the next frame.
    pub fn switched_off(&self) -> Vec<Effect> {
        FrameSwitches::SWITCHABLE.into_iter().filter(|&e| self.effect_on(e) && !self.switches.on(e)).collect()
    }

    /// The shading rules of the next frame: the built ones less the
    /// flavours switched off.
    fn frame_shade(&self) -> ShadeRules {
        let off = [Effect::Splat, Effect::Cliffs].into_iter().filter(|&e| !self.switches.on(e));
        off.fold(self.shade, ShadeRules::without)
    }

    /// GPU counters of the newest frame that came back (frames late; never
    /// waits). Call after `record` or `poll_timings`.
    pub fn latest_counters(&self) -> Option<&FrameCounters> {
        self.telemetry.latest()
    }

    /// Reads the last recorded frame's counters back, waiting for the GPU
    /// (tests and tools; the frame path uses `latest_counters`).
    pub fn read_counters(&self, ctx: &Context) -> Result<FrameCounters> {
        let mut bytes = ctx.read_buffer(self.traverse.output())?;
        bytes.truncate(std::mem::size_of::<crate::passes::traverse::TraverseHeader>());
        for list in counter_lists(&self.cull, &self.occlusion) {
            let header = match list {
                Some(b) => ctx.read_buffer(b)?[..structs::PATCH_LIST_HEADER].to_vec(),
                None => vec![0; structs::PATCH_LIST_HEADER],
            };
            bytes.extend(header);
        }
        match self.classify.lists.as_ref() {
            Some(l) => bytes.extend(&ctx.read_buffer(&l.buffer)?[..crate::passes::classify_tiles::HEAD_BYTES as usize]),
            None => bytes.extend(vec![0; crate::passes::classify_tiles::HEAD_BYTES as usize]),
        }
        bytes.extend(&ctx.read_buffer(self.select.levels())?[..structs::SELECT_HEADER]);
        match &self.near.grass {
            Some(g) => bytes.extend(&ctx.read_buffer(g.header())?[..structs::GRASS_HEADER]),
            None => bytes.extend(vec![0; structs::GRASS_HEADER]),
        }
        let frame = self.graph.last_frame().map_or(0, |l| l.frame);
        Ok(self.telemetry.layout().parse(frame, &bytes))
    }

    /// Visible patches of every list of the last frame, both phases,
    /// sorted (tests): waits.
    pub fn read_patches(&self, ctx: &Context) -> Result<Vec<crate::passes::cull_patches::PatchRecord>> {
        let mut out = self.cull.lists().read_patches(ctx)?;
        if let Some(o) = &self.occlusion {
            out.extend(o.cull.lists.read_patches(ctx)?);
        }
        out.sort();
        Ok(out)
    }

    /// Streaming rests, every resident node's sun shadow is current and
    /// every virtual-texture page a view asks for is resident: a frame now
    /// shows what more frames would.
    pub fn settled(&self) -> bool {
        self.terrain.settled()
            && self.shadow_schedule.stale() == 0
            && self.virtual_texture.as_ref().is_none_or(VirtualTexture::settled)
    }

    /// Effect `decals`: replaces the decal list (world metres; the textures
    /// stay those given at creation). The resident virtual-texture pages
    /// an added, removed or changed decal touches, before or after, are
    /// dropped and rendered again over the next frames; returns how many.
    /// Errors: the effect is off, or a decal is bad (one line).
    /// Displacement decals' meshes are made again; a renderer made
    /// without any cannot take one (its pass was not built).
    pub fn set_decals(&mut self, ctx: &Context, decals: Vec<Decal>) -> Result<u32> {
        let next = self.frames_recorded() + 1;
        let Some(vt) = &mut self.virtual_texture else {
            return Err(Error::BadInput("effect decals is off in this renderer".into()));
        };
        let meshes = self.near.check_decals(&decals, vt.decal_textures())?;
        let dropped = vt.set_decals(decals, next)?;
        self.near.replace_decal_meshes(ctx, &meshes)?;
        Ok(dropped)
    }

    /// Effect `decals`: the decals drawn (empty when off).
    pub fn decals(&self) -> &[Decal] {
        self.virtual_texture.as_ref().map_or(&[], VirtualTexture::decals)
    }

    /// The world's height source was edited over `region` (a stamp added,
    /// moved or removed): see [`Terrain::replace_source`]. The resident
    /// nodes it touches reload while the old ones stay drawn (their sun
    /// shadows are marched again as for arrivals); returns how many.
    /// `bake`: new bake settings too (see [`Terrain::replace_source`]).
    pub fn replace_source(
        &mut self,
        source: Arc<dyn HeightSource>,
        bake: Option<crate::world::BakeSettings>,
        region: [f64; 4],
    ) -> Result<usize> {
        self.terrain.replace_source(source, bake, region)
    }

    /// How the last frame was submitted (None before the first).
    pub fn queue_mode(&self) -> Option<QueueMode> {
        self.mode
    }

    /// Pass timings of the newest frame the GPU has finished (one or more
    /// frames late; never waits).
    pub fn latest_timings(&self) -> Option<&FrameTimings> {
        self.exec.latest()
    }

    /// Collects timings and counters of frames that finished since the
    /// last `record` (never waits) and returns the newest timings.
    pub fn poll_timings(&mut self, ctx: &Context) -> Option<&FrameTimings> {
        self.telemetry.harvest(ctx);
        self.exec.poll();
        self.exec.latest()
    }

    /// Every pass of the frame, built or not (and why not).
    pub fn pass_graph(&self) -> &[crate::scene::graph::PassNode] {
        self.graph.nodes()
    }

    /// What became of each built pass in the last recorded frame.
    pub fn last_frame_log(&self) -> Option<&crate::scene::graph::FrameLog> {
        self.graph.last_frame()
    }

    /// Frames recorded so far (the number of the last one).
    pub fn frames_recorded(&self) -> u64 {
        self.graph.last_frame().map_or(0, |l| l.frame)
    }
}

mod frame_checks;
mod inventory;

/// The renderer's shadow state for one frame's planning.
struct ShadowState<'a> {
    pass: Option<&'a SunShadows>,
    on: bool,
    schedule: &'a mut ShadowSchedule,
    were_off: &'a mut bool,
}

impl ShadowState<'_> {
    /// This frame's sun shadow jobs. Switched off, none; switched back on,
    /// every resident node's shadow is stale (nodes arrived meanwhile were
    /// not marched) and they are redone as fast as the job list allows.
    fn jobs(self, terrain: &Terrain, sun: glam::DVec3) -> Vec<SunShadowJob> {
        let Some(s) = self.pass else { return Vec::new() };
        let tree = &terrain.tree;
        if !self.on {
            *self.were_off = true;
            return Vec::new();
        }
        let mut budget = s.params.update_budget;
        if std::mem::take(self.were_off) {
            let resident: Vec<_> =
                terrain.resident_nodes().into_iter().filter_map(|n| Some((n, tree.shadow.slot_of(n)?))).collect();
            self.schedule.restart(&resident);
        }
        if !self.schedule.ready() {
            budget = crate::effects::shadows::sun_shadows::MAX_UPDATE_BUDGET;
        }
        let world = terrain.world;
        let march = MarchSun { dir: sun.as_vec3().to_array(), reach_m: f64::from(s.params.reach_m) };
        let extent = |n: NodeId| {
            let slot = tree.shadow.slot_of(n)?;
            let [lo, hi] = tree.shadow.height_range(slot);
            let [x0, y0, x1, y1] = world.bounds_m(n);
            Some((slot, NodeExtent { bounds_m: [x0, y0, x1, y1], min_m: lo, max_m: hi }))
        };
        self.schedule.plan(march, budget, tree.arrived(), extent)
    }
}

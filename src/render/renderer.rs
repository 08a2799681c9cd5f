//! [`TerrainRenderer`]: owns the terrain (streaming, GPU quadtree) and the
//! passes that turn it into pixels, built from the scene's effects, and
//! records one frame into a command buffer the caller provides. The frame
//! is the pass graph of `scene::graph` (in order: quadtree_update,
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
use crate::effects::frame_effect::{find, find_mut, FrameEffect};
use crate::effects::virtual_texture::decals::{Decal, DecalSet};
use crate::effects::virtual_texture::VirtualTexture;
use crate::effects::{decide, Effect, EffectDecision, Effects, FrameSwitches, MaterialsMode, WorldContent};
use crate::error::{Error, Result};
use crate::frame::per_frame::PerFrame;
use crate::frame::{FrameExecutor, FrameTimings};
use crate::gpu::{vk, Buffer, Context, FrameCommands, QueueMode, Recorder};
use crate::passes::classify_tiles::ClassifyTiles;
use crate::passes::cull_occluded::CullOccluded;
use crate::passes::cull_patches::{CullPatches, CullStages};
use crate::passes::debug_view::{DebugView, DebugViewPass};
use crate::passes::emit_fine::EmitFine;
use crate::passes::emit_triangles::EmitTriangles;
use crate::passes::gbuffer_tiles::GbufferTiles;
use crate::passes::hiz_build::HizBuild;
use crate::passes::lighting_resolve::LightingResolve;
use crate::passes::lod_map::LodMap;
use crate::passes::quadtree_update::QuadtreeUpdatePass;
use crate::passes::sector_data::SectorData;
use crate::passes::select_patches::SelectPatches;
use crate::passes::terrain_geometry::{DepthOptions, RenderTargets, TerrainGeometry};
use crate::passes::terrain_holes::TerrainHoles;
use crate::passes::terrain_triangles::TerrainTriangles;
use crate::passes::traverse::Traverse;
use crate::render::telemetry::{head_bytes, FrameCounters, Telemetry};
use crate::scene::graph::PassGraph;
use crate::scene::shading::{ShadeRules, Shading};
use crate::scene::view::{Camera, View};
use crate::shaders::structs;
use crate::targets::gbuffer::GBuffer;
use crate::targets::Output;
use crate::terrain::gpu_quadtree::{
    AtlasSet, ATLAS_CONTROL, ATLAS_NORMAL, ATLAS_PATCH_CONES, ATLAS_PATCH_HOLES, ATLAS_SPLAT,
};
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
    /// Count each graphics-queue pass's pipeline statistics (vertices,
    /// primitives, fragments, compute invocations) into its
    /// [`PassTiming::counters`](crate::frame::PassTiming::counters), where
    /// the device enabled them (`Limits::pipeline_statistics`).
    pub counters: bool,
}

/// Which LOD selection draws the terrain.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub enum LodRule {
    /// Far Cry 5's: per patch of 8x8 quads, coarsened from ancestors,
    /// refined below the samples, seams stitched (`select_patches`,
    /// `cull_patches`, `terrain_geometry`).
    #[default]
    Patch,
    /// A restricted bintree with saturated per-vertex errors (Lindstrom &
    /// Pascucci): per triangle inside each drawn node, a conforming cut
    /// with a strict bound (`emit_triangles`, `terrain_triangles`). Its
    /// bounds are computed for the whole world when the renderer is made.
    /// With effect `occlusion` it culls its subtrees in two phases against
    /// the depth pyramid. A LOD-0 node continues the bisection below its
    /// samples, on the Catmull-Rom surface, to the finest lattice. With
    /// effect `cone_cull` (stage `cone`) each triangle it leaves whole on a
    /// node's grid is dropped when it faces away from the camera, and with
    /// stage `frustum` when it lies outside the frustum on its own.
    Triangle,
}

/// LOD selection settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LodOptions {
    /// Per patch (the default) or per triangle.
    pub rule: LodRule,
    /// Levels of refinement below LOD 0 allowed (0: none; 1: 2x; 2: 4x, the
    /// finest surface the error tree measures against). Below the finest,
    /// the error bound reported is the refused level's.
    pub refine_levels: u32,
    /// LOD-0 patches refined per frame at most (1 to `MAX_REFINED_PATCHES`,
    /// the default, which sizes the patch lists). Beyond it the patches
    /// whose projected error exceeds the target most are refined, whole
    /// priority buckets at a time, so the choice is the same on every run
    /// and device; the rest are drawn at LOD 0 and counted.
    pub refine_budget: u32,
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
            rule: LodRule::Patch,
            refine_levels: crate::shaders::consts::REFINE_LEVELS,
            refine_budget: crate::shaders::consts::MAX_REFINED_PATCHES,
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
    /// The per-triangle rule's passes, which draw instead of `select`,
    /// `cull`, `geometry` and `holes` ([`LodRule::Triangle`]).
    pub triangles: Option<TrianglePath>,
    pub classify: ClassifyTiles,
    pub gbuffer_tiles: GbufferTiles,
    /// Outputs `lit` and `hdr` (None with output `gbuffer`: the engine lights).
    pub resolve: Option<LightingResolve>,
    /// The effect folders that are on, built, in registry order
    /// (`effects::registry`); [`Self::effect`] finds one by type.
    built: Vec<Box<dyn FrameEffect>>,
    /// Made for the view size on the first frame (remade when it changes).
    pub gbuffer: Option<GBuffer>,
    pub shade: ShadeRules,
    shading: Shading,
    /// Per-patch LOD settings of the next recorded frame.
    pub lod: LodOptions,
    /// One per frame parity (`frame::per_frame`), like what the LOD phase
    /// writes: the compute submission writes it.
    view_buffer: PerFrame<Buffer>,
    /// The LOD phase's view when [`Self::lod_camera`] is set.
    lod_view_buffer: PerFrame<Buffer>,
    /// Chooses the LOD (streaming, traversal, selection, culling) of the
    /// next frames for this camera instead of the view's, which still draws
    /// and shades: the surface one camera's LOD gives, seen from another
    /// (`vista bench accuracy --fly` measures popping with it). `None`: the
    /// view's.
    pub lod_camera: Option<Camera>,
    telemetry: Telemetry,
    /// Taken while a frame records (the frame borrows it; see `record.rs`).
    exec: Option<FrameExecutor>,
    pub(crate) graph: PassGraph,
    /// Culling stages of the next recorded frame (of those built).
    pub stages: CullStages,
    /// Effects of the next recorded frame that a built renderer can switch
    /// off without rebuilding (of those built).
    pub switches: FrameSwitches,
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

/// The per-triangle rule's passes ([`LodRule::Triangle`]).
pub struct TrianglePath {
    pub emit: EmitTriangles,
    pub fine: EmitFine,
    pub draw: TerrainTriangles,
    /// Effect `occlusion`: the depth pyramid of phase 1's draw, which the
    /// cut's phase 2 tests its subtrees against.
    pub hiz: Option<HizBuild>,
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

/// GPU bytes one resident node slot costs a renderer of `effects` over this
/// world: its payload atlases ([`memory_for`]) and the layer each effect
/// keeps per slot. What a GPU budget in MiB is divided by.
pub fn slot_bytes(
    format: crate::world::PayloadFormat,
    effects: &Effects,
    world: &WorldDesc,
    holes: &[Hole],
    source_holes: bool,
) -> u64 {
    let decisions = decide(effects, &world_content(world, holes, source_holes, 0, 0), false);
    let effect_layers: u64 = decisions
        .iter()
        .filter(|d| d.on)
        .map(|d| crate::effects::registry::kind_of(d.effect).slot_bytes(effects))
        .sum();
    memory_for(1, format, effects, world, holes, source_holes).gpu_total() as u64 + effect_layers
}

/// GPU bytes a slot's vertex numbers add for the per-triangle rule
/// ([`LodRule::Triangle`]: an atlas layer of [`slot_bytes`]' kinds too).
pub fn vertex_bounds_slot_bytes() -> u64 {
    let plain = crate::world::MemoryReport::new(1);
    (plain.clone().with_vertex_bounds().gpu_total() - plain.gpu_total()) as u64
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

    /// The built effect of type `T` (e.g. `VirtualTexture`, `Grass`,
    /// `Shadows`), if it is on.
    pub fn effect<T: FrameEffect>(&self) -> Option<&T> {
        find(&self.built)
    }

    /// The built effect of type `T`, to change (tests, tools).
    pub fn effect_mut<T: FrameEffect>(&mut self) -> Option<&mut T> {
        find_mut(&mut self.built)
    }

    /// Every built effect, in registry order.
    pub fn built_effects(&self) -> &[Box<dyn FrameEffect>] {
        &self.built
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
            bytes.extend(head_bytes(ctx, list, structs::PATCH_LIST_HEADER)?);
        }
        let tiles = self.classify.lists.as_ref().map(|l| &l.buffer);
        bytes.extend(head_bytes(ctx, tiles, crate::passes::classify_tiles::HEAD_BYTES as usize)?);
        bytes.extend(head_bytes(ctx, Some(self.select.levels()), structs::SELECT_HEADER)?);
        for list in self.triangles.as_ref().map(|t| [Some(t.emit.list()), t.emit.late_list()]).into_iter().flatten() {
            bytes.extend(head_bytes(ctx, list, structs::TRIANGLE_LIST_HEADER)?);
        }
        for (buffer, n) in self.built.iter().filter_map(|e| e.counters()) {
            bytes.extend(&ctx.read_buffer(buffer)?[..n as usize]);
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
        self.terrain.settled() && self.built.iter().all(|e| e.settled())
    }

    /// Only the terrain's loads are under way ([`Terrain::only_loading`])
    /// and every effect has settled: the next frame would draw this one.
    pub fn only_loading(&self) -> bool {
        self.terrain.only_loading() && self.built.iter().all(|e| e.settled())
    }

    /// A render that waits for [`Self::settled`] (`on`; an offline render)
    /// lets the effects spend more a frame to settle in fewer frames (the
    /// virtual texture's feedback samples every pixel, shadows take their
    /// largest budget); off, every frame
    /// costs what it costs at its own pace.
    pub fn set_catch_up(&mut self, on: bool) {
        for e in &mut self.built {
            e.catch_up(on);
        }
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
        let Some(vt) = self.effect_mut::<VirtualTexture>() else {
            return Err(Error::BadInput("effect decals is off in this renderer".into()));
        };
        vt.edit_decals(ctx, decals, next)
    }

    /// Effect `decals`: the decals drawn (empty when off).
    pub fn decals(&self) -> &[Decal] {
        self.effect::<VirtualTexture>().map_or(&[], VirtualTexture::decals)
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
        self.exec.as_ref().and_then(FrameExecutor::latest)
    }

    /// Collects timings and counters of frames that finished since the
    /// last `record` (never waits) and returns the newest timings.
    pub fn poll_timings(&mut self, ctx: &Context) -> Option<&FrameTimings> {
        self.telemetry.harvest(ctx);
        let exec = self.exec.as_mut().expect("not recording");
        exec.poll();
        exec.latest()
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

mod build;
mod frame_checks;
mod inventory;
mod record;

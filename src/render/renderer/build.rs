//! Building a renderer: the effect decisions first (nothing allocates for
//! an effect that is off), then the terrain and the core passes, then
//! each effect's built side through the registry.

use super::{atlases_for, world_content, LodRule, Occlusion, RendererOptions, TerrainRenderer, TrianglePath};
use crate::effects::frame_effect::{BuildInputs, FrameEffect};
use crate::effects::registry::kinds;
use crate::effects::{decide, Effect, EffectDecision, FrameSwitches, MaterialsMode};
use crate::error::{Error, Result};
use crate::frame::per_frame::{copy_name, PerFrame};
use crate::frame::FrameExecutor;
use crate::gpu::{vk, Buffer, BufferDesc, Context, MemoryLocation};
use crate::passes::classify_tiles::ClassifyTiles;
use crate::passes::cull_occluded::CullOccluded;
use crate::passes::cull_patches::{CullBuild, CullPatches};
use crate::passes::emit_fine::EmitFine;
use crate::passes::emit_triangles::{EmitBuild, EmitTriangles};
use crate::passes::gbuffer_tiles::{GbufferTiles, TileMaterials};
use crate::passes::hiz_build::HizBuild;
use crate::passes::lighting_resolve::{LightingResolve, ResolveTarget};
use crate::passes::lod_map::LodMap;
use crate::passes::quadtree_update::QuadtreeUpdatePass;
use crate::passes::sector_data::SectorData;
use crate::passes::select_patches::SelectPatches;
use crate::passes::terrain_geometry::{TerrainGeometry, PATCH_INDEX_COUNT};
use crate::passes::terrain_holes::TerrainHoles;
use crate::passes::terrain_triangles::TerrainTriangles;
use crate::passes::traverse::Traverse;
use crate::render::telemetry::{CounterLayout, Telemetry, TRIANGLES_PER_PATCH};
use crate::scene::graph::{FramePass, PassGraph};
use crate::scene::shading::{ShadeRules, Shading};
use crate::shaders::structs;
use crate::terrain::gpu_quadtree::{ATLAS_CONTROL, ATLAS_VERTEX_BOUNDS};
use crate::terrain::{Terrain, TerrainOptions};
use crate::world::{HeightSource, Hole, WorldDesc};
use std::sync::Arc;

/// Checks what would fail alone (a world over its limits, bad targets)
/// and decides every effect, before anything allocates.
fn decisions(
    ctx: &Context,
    world: &WorldDesc,
    source: &dyn HeightSource,
    holes: &[Hole],
    options: &RendererOptions,
) -> Result<Vec<EffectDecision>> {
    crate::terrain::check_plan(ctx, world, &options.terrain)?;
    options.depth.check().map_err(Error::BadInput)?;
    options.output.check().map_err(Error::BadInput)?;
    let budget = options.lod.refine_budget;
    if !(1..=crate::shaders::consts::MAX_REFINED_PATCHES).contains(&budget) {
        return Err(Error::BadInput(format!(
            "refine_budget {budget}: 1 to {} LOD-0 patches refined a frame",
            crate::shaders::consts::MAX_REFINED_PATCHES
        )));
    }
    let (decals, assets) = (options.decals.decals.len(), options.assets.len());
    let mut content = world_content(world, holes, source.has_holes(), decals, assets);
    content.engine_lights = !options.output.lights();
    Ok(decide(&options.effects, &content, options.forced()))
}

/// The decisions' answer for one effect.
fn is_on(decisions: &[EffectDecision], e: Effect) -> bool {
    decisions.iter().any(|d| d.effect == e && d.on)
}

/// The terrain's options for these decisions: the atlases the effects
/// that are on read, and the control words when a flavour reads them.
fn terrain_options(
    options: &RendererOptions,
    world: &WorldDesc,
    decisions: &[EffectDecision],
) -> Result<TerrainOptions> {
    let mut atlases = atlases_for(decisions, options.effects.materials);
    let triangle = options.lod.rule == LodRule::Triangle;
    if triangle {
        atlases = atlases.with(ATLAS_VERTEX_BOUNDS);
    }
    let mut terrain_options = TerrainOptions { atlases, vertex_bounds: triangle, ..options.terrain.clone() };
    if atlases.contains(ATLAS_CONTROL) && terrain_options.bake.control.is_none() {
        // The control-map flavour reads control words: bake them (from
        // the scene's map or the material rules) unless the caller did.
        let rules = terrain_options.bake.materials;
        terrain_options.bake.control = crate::effects::materials::control_bake(&options.effects, world, rules)?;
    }
    Ok(terrain_options)
}

/// The tile shading's rules and its pass, for the material effects on.
fn tile_shading(
    ctx: &Context,
    o: &RendererOptions,
    decisions: &[EffectDecision],
) -> Result<(ShadeRules, GbufferTiles, usize)> {
    let on = |e| is_on(decisions, e);
    let fx = &o.effects;
    let mut shade = fx.shade.allowing(fx.materials, on(Effect::Splat), on(Effect::Cliffs));
    if on(Effect::VirtualTexture) {
        shade = shade.with_virtual_texture();
    }
    let variants = o.shading.pipelines(&shade);
    let every = o.shading == Shading::OneShaderEveryFlavour;
    let tile_materials = match (on(Effect::Splat) || on(Effect::Cliffs), fx.materials) {
        (false, _) => TileMaterials::None,
        (true, MaterialsMode::Splat) if on(Effect::VirtualTexture) => TileMaterials::SplatVirtualTexture,
        (true, MaterialsMode::Splat) => TileMaterials::Splat,
        (true, MaterialsMode::ControlMap) => TileMaterials::ControlMap,
    };
    let layout = o.output.gbuffer();
    let tiles = GbufferTiles::new(ctx, &variants, tile_materials, every, o.depth.format, layout)?;
    Ok((shade, tiles, variants.len()))
}

fn view_buffers(ctx: &Context, name: &str) -> Result<PerFrame<Buffer>> {
    PerFrame::new(|i| {
        Buffer::new(
            ctx,
            &BufferDesc {
                name: &copy_name(name, i),
                size: structs::TERRAIN_VIEW as u64,
                usage: vk::BufferUsageFlags::STORAGE_BUFFER
                    | vk::BufferUsageFlags::TRANSFER_DST
                    | vk::BufferUsageFlags::TRANSFER_SRC,
                location: MemoryLocation::GpuOnly,
            },
        )
    })
}

/// The pass graph of these decisions and output.
fn graph(decisions: &[EffectDecision], options: &RendererOptions) -> PassGraph {
    let effect_passes: Vec<_> = kinds().iter().flat_map(|k| k.passes().iter().copied()).collect();
    let mut graph = PassGraph::new(decisions, &effect_passes);
    if options.output.gbuffer().is_some() {
        graph.not_built(FramePass::LIGHTING_RESOLVE, "output gbuffer: the engine lights the G-buffer".into());
        graph.not_built(FramePass::DEBUG_VIEW, "output gbuffer: no colour target to draw a debug view over".into());
    }
    let per_patch = [
        FramePass::SELECT_PATCHES,
        FramePass::CULL_PATCHES,
        FramePass::TERRAIN_GEOMETRY,
        FramePass::TERRAIN_HOLES,
        FramePass::CULL_OCCLUDED,
        FramePass::TERRAIN_GEOMETRY_LATE,
        FramePass::TERRAIN_HOLES_LATE,
    ];
    let per_triangle = [
        FramePass::EMIT_TRIANGLES,
        FramePass::EMIT_FINE,
        FramePass::TERRAIN_TRIANGLES,
        FramePass::EMIT_TRIANGLES_LATE,
        FramePass::EMIT_FINE_LATE,
        FramePass::TERRAIN_TRIANGLES_LATE,
    ];
    let (off, why) = match options.lod.rule {
        LodRule::Patch => (&per_triangle[..], "LOD rule patch: the per-patch selection draws"),
        LodRule::Triangle => (
            &per_patch[..],
            "LOD rule triangle: the per-triangle rule draws (its vertices test holes; its subtrees are culled by \
             the frustum, patches of holes only and, with effect occlusion, the depth pyramid; with effect \
             cone_cull, each triangle it leaves whole by its facing)",
        ),
    };
    for p in off {
        graph.not_built(*p, why.into());
    }
    graph
}

impl Occlusion {
    fn new(ctx: &Context, traverse: &Traverse, indices: u32, build: CullBuild, slots: u32) -> Result<Self> {
        Ok(Occlusion { hiz: HizBuild::new(ctx)?, cull: CullOccluded::new(ctx, traverse, indices, build, slots)? })
    }

    /// Phase 2 and its depth pyramid when `build` asks for occlusion.
    fn when_built(ctx: &Context, traverse: &Traverse, build: CullBuild, slots: u32) -> Result<Option<Self>> {
        build.occlusion.then(|| Self::new(ctx, traverse, PATCH_INDEX_COUNT, build, slots)).transpose()
    }
}

/// The lighting resolve of outputs `lit` and `hdr` (None: the engine lights).
fn resolve(ctx: &Context, o: &RendererOptions, decisions: &[EffectDecision]) -> Result<Option<LightingResolve>> {
    let Some(target) = ResolveTarget::of(&o.output) else { return Ok(None) };
    let on = |e| is_on(decisions, e);
    let variants = (on(Effect::Lighting), on(Effect::Shadows), on(Effect::Atmosphere));
    Ok(Some(LightingResolve::new(ctx, variants, o.depth.format, target)?))
}

/// Where the telemetry finds each counter: the lists built, and each
/// built effect's counters.
fn counter_layout(
    world: &WorldDesc,
    cull: &CullPatches,
    build: CullBuild,
    built: &[Box<dyn FrameEffect>],
    triangle: bool,
) -> CounterLayout {
    CounterLayout {
        triangle_lists: triangle,
        holes: build.holes,
        occlusion: build.occlusion,
        lod_count: world.lod_count,
        list_capacity: cull.lists().capacity,
        triangles_per_patch: TRIANGLES_PER_PATCH,
        effects: built.iter().filter_map(|e| e.counters().map(|(_, n)| (e.effect(), n))).collect(),
    }
}

/// Every effect's built side, in registry order.
fn build_effects(b: &mut BuildInputs) -> Result<Vec<Box<dyn FrameEffect>>> {
    let mut built = Vec::new();
    for kind in kinds() {
        built.extend(kind.build(b)?);
    }
    Ok(built)
}

/// The traversal, its boxes padded for the per-triangle rule (a vertex's
/// box reaches less than a cell past its node: world/vertex_bounds.rs).
fn traversal(ctx: &Context, world: &WorldDesc, options: &RendererOptions) -> Result<Traverse> {
    let mut traverse = Traverse::new(ctx, world, options.terrain.slots)?;
    if options.lod.rule == LodRule::Triangle {
        traverse.set_box_pad(1.0 / crate::world::NODE_QUADS as f32);
    }
    Ok(traverse)
}

/// The terrain's draws: the patch draw, the hole draw where built and the
/// per-triangle rule's passes where it draws (`triangle`: its slots, and
/// whether effect `occlusion` gives it two phases), each
/// pushing an effect's sunk cells behind where one has a sink (terrain_sink.rs).
fn terrain_draws(
    ctx: &Context,
    depth: crate::passes::terrain_geometry::DepthOptions,
    effects: &[Box<dyn FrameEffect>],
    holes: bool,
    triangle: Option<(u32, EmitBuild)>,
) -> Result<(TerrainGeometry, Option<TerrainHoles>, Option<TrianglePath>)> {
    let sinks = effects.iter().filter(|e| e.terrain_sink().is_some()).count();
    assert!(sinks <= 1, "{sinks} effects sink the height field; the terrain's draws read one sink");
    let sink = sinks == 1;
    let holes = if holes { Some(TerrainHoles::new(ctx, depth, sink)?) } else { None };
    let triangles = match triangle {
        Some((slots, build)) => Some(TrianglePath {
            emit: EmitTriangles::new(ctx, slots, build)?,
            fine: EmitFine::new(ctx)?,
            draw: TerrainTriangles::new(ctx, depth, sink)?,
            hiz: build.occlusion.then(|| HizBuild::new(ctx)).transpose()?,
        }),
        None => None,
    };
    Ok((TerrainGeometry::new(ctx, depth, sink)?, holes, triangles))
}

impl TerrainRenderer {
    pub fn new(
        ctx: &Context,
        world: &WorldDesc,
        source: Arc<dyn HeightSource>,
        holes: Vec<Hole>,
        options: &RendererOptions,
    ) -> Result<Self> {
        let decisions = decisions(ctx, world, source.as_ref(), &holes, options)?;
        let on = |e: Effect| is_on(&decisions, e);
        let triangle = options.lod.rule == LodRule::Triangle;
        let terrain_options = terrain_options(options, world, &decisions)?;
        let (shade, gbuffer_tiles, variants) = tile_shading(ctx, options, &decisions)?;
        let terrain = Terrain::new(ctx, world, source, holes, &terrain_options)?;
        let traverse = traversal(ctx, world, options)?;
        // Per-slot resources cover the reload slots too (gpu_quadtree::RELOAD_SLOTS).
        let slot_capacity = terrain.tree.slot_capacity();
        // The per-triangle rule's own two phases are its passes'.
        let occlusion = on(Effect::Occlusion) && !triangle;
        let build = CullBuild { cone: on(Effect::ConeCull), holes: on(Effect::Holes), occlusion };
        let cull = CullPatches::new(ctx, &traverse, PATCH_INDEX_COUNT, build)?;
        let occlusion = Occlusion::when_built(ctx, &traverse, build, slot_capacity)?;
        let mut graph = graph(&decisions, options);
        let built = build_effects(&mut BuildInputs {
            ctx,
            world,
            effects: &options.effects,
            decisions: &decisions,
            depth: options.depth,
            layout: options.output.gbuffer(),
            occlusion: build.occlusion,
            frames_in_flight: options.terrain.frames_in_flight,
            slot_capacity,
            decals: &options.decals,
            assets: &options.assets,
            graph: &mut graph,
        })?;
        // gbuffer_tiles records one timed draw per variant.
        let max_passes = graph.max_recorded() + variants as u32;
        let counters = counter_layout(world, &cull, build, &built, triangle);
        let emit = EmitBuild { occlusion: on(Effect::Occlusion), facing: on(Effect::ConeCull) };
        let tri = triangle.then_some((slot_capacity, emit));
        let (geometry, holes, triangles) = terrain_draws(ctx, options.depth, &built, build.holes, tri)?;
        let resolve = resolve(ctx, options, &decisions)?;
        Ok(TerrainRenderer {
            update: QuadtreeUpdatePass::new(ctx, build.occlusion)?,
            lod_map: LodMap::new(ctx, world)?,
            sector_data: SectorData::new(ctx, world)?,
            terrain,
            select: SelectPatches::new(ctx, world, slot_capacity, options.lod.refine_budget)?,
            traverse,
            cull,
            occlusion,
            geometry,
            holes,
            triangles,
            classify: ClassifyTiles::new(ctx)?,
            gbuffer_tiles,
            resolve,
            built,
            gbuffer: None,
            shade,
            shading: options.shading,
            lod: options.lod,
            view_buffer: view_buffers(ctx, "terrain_view")?,
            lod_view_buffer: view_buffers(ctx, "lod_view")?,
            lod_camera: None,
            telemetry: Telemetry::new(ctx, options.terrain.frames_in_flight, counters)?,
            exec: Some(FrameExecutor::new(ctx, options.terrain.frames_in_flight, max_passes, options.counters)?),
            graph,
            stages: options.stages,
            switches: FrameSwitches::default(),
            debug_view: None,
            debug_pass: None,
            effects: options.effects.clone(),
            output: options.output.clone(),
            origin_m: options.origin_m,
            decisions,
            mode: None,
        })
    }
}

//! One frame's passes after streaming, recorded phase by phase: the LOD
//! phase (traverse, lod_map, sector_data, select_patches, cull_patches),
//! the draws (terrain_geometry, terrain_holes and occlusion's phase 2),
//! grass placement, and the shading (classify_tiles, gbuffer_tiles,
//! asset_draw, grass_draw, sun_shadows, lighting_resolve). The
//! renderer lends its passes apart from the frame executor and the
//! streaming state ([`FramePasses`]); each pass is logged in the frame's
//! [`FrameLog`] as the graph expects.

use crate::effects::assets::asset_draw::AssetDraw;
use crate::effects::assets::AssetResources;
use crate::effects::cliff_meshes::cliff_mesh_build::CliffBuildPush;
use crate::effects::cliff_meshes::CliffMeshes;
use crate::effects::grass::gpu::{Grass, GrassFrame};
use crate::effects::materials::gpu::MaterialResources;
use crate::effects::shadows::sun_shadows::{SunShadowJob, SunShadows};
use crate::effects::virtual_texture::decal_meshes::DecalMeshPass;
use crate::effects::virtual_texture::{VirtualTexture, VtFrame};
use crate::frame::{Frame, QueueKind};
use crate::gpu::{depth_layout, vk, Buffer, Recorder};
use crate::passes::classify_tiles::ClassifyTiles;
use crate::passes::cull_patches::{CullFrame, CullPatches, CullStages};
use crate::passes::debug_view::{DebugView, DebugViewPass};
use crate::passes::gbuffer_tiles::{variant_label, GbufferTiles, MaterialBindings};
use crate::passes::lighting_resolve::{LightingResolve, ResolveInputs, ShadowInput};
use crate::passes::lod_map::LodMap;
use crate::passes::sector_data::SectorData;
use crate::passes::select_patches::SelectPatches;
use crate::passes::terrain_geometry::{RenderTargets, TerrainGeometry};
use crate::passes::terrain_holes::TerrainHoles;
use crate::passes::terrain_query::VistaTerrain;
use crate::passes::traverse::{Traverse, TraverseMode};
use crate::render::renderer::Occlusion;
use crate::scene::graph::{FrameLog, FramePass, Skip};
use crate::scene::view::TerrainViewGpu;
use crate::targets::gbuffer::GBuffer;
use crate::terrain::gpu_quadtree::GpuQuadtree;
use crate::terrain::selection::TraverseParams;
use crate::world::WorldDesc;

/// The renderer's passes and per-frame inputs, borrowed for one frame.
pub(crate) struct FramePasses<'a> {
    pub traverse: &'a Traverse,
    pub lod_map: &'a LodMap,
    pub sector_data: &'a SectorData,
    pub select: &'a SelectPatches,
    pub cull: &'a CullPatches,
    pub occlusion: Option<&'a Occlusion>,
    pub geometry: &'a TerrainGeometry,
    pub holes: Option<&'a TerrainHoles>,
    pub classify: &'a ClassifyTiles,
    pub gbuffer_tiles: &'a GbufferTiles,
    /// Outputs `lit` and `hdr` (output `gbuffer`: not built).
    pub resolve: Option<&'a LightingResolve>,
    /// Effect `shadows`, with this frame's jobs (empty: skipped), the unit
    /// vector towards the sun and its elevation (degrees).
    pub shadows: Option<(&'a SunShadows, &'a [SunShadowJob], glam::DVec3, f64)>,
    /// Effect `shadows` is built but switched off this frame.
    pub shadows_off: bool,
    /// The debug view asked for, and its pass (made when first asked).
    pub debug: Option<(&'a DebugViewPass, DebugView)>,
    /// Effect `atmosphere`: the fog's push vectors.
    pub fog: Option<[[f32; 4]; 3]>,
    pub materials: Option<&'a MaterialResources>,
    /// Effect `virtual_texture`, with this frame's planned work.
    pub virtual_texture: Option<(&'a VirtualTexture, &'a VtFrame)>,
    pub view_buffer: &'a Buffer,
    pub stages: CullStages,
    /// Effect `holes` is built but switched off this frame: every patch is
    /// solid and the hole draws are skipped.
    pub holes_off: bool,
    /// Shading flavours forced on every tile (the reference shadings), else 0.
    pub force_flavours: u32,
    /// Effect `grass`, with this frame's plan.
    pub grass: Option<(&'a Grass, &'a GrassFrame)>,
    /// Effect `assets`: the pass and its meshes.
    pub assets: Option<&'a (AssetDraw, AssetResources)>,
    /// Effect `decals` with displacement decals: their meshes.
    pub decal_meshes: Option<&'a DecalMeshPass>,
    /// Effect `cliff_meshes`, with this frame's build (None: current).
    pub cliff_meshes: Option<(&'a CliffMeshes, Option<&'a CliffBuildPush>)>,
}

/// Records `p` in `frame` and logs it.
fn pass<'r>(frame: &mut Frame<'_, 'r>, log: &mut FrameLog, p: FramePass, f: impl FnOnce(&mut Recorder<'r>)) {
    frame.pass(p.name(), p.late(), p.queue(), f);
    log.ran(p, None);
}

impl FramePasses<'_> {
    fn cull_frame(&self) -> CullFrame {
        CullFrame { stages: self.stages, holes: !self.holes_off }
    }

    /// The hole draw, unless switched off this frame (then logged skipped).
    fn holes_drawn(&self, log: &mut FrameLog, p: FramePass) -> Option<&TerrainHoles> {
        if self.holes.is_some() && self.holes_off {
            log.skipped(p, Skip::HolesOff);
            return None;
        }
        self.holes
    }

    /// The node list, the maps the patches read, each patch's level and
    /// the phase-1 patch lists.
    pub fn record_lod(
        &self,
        frame: &mut Frame<'_, '_>,
        log: &mut FrameLog,
        tree: &GpuQuadtree,
        params: &TraverseParams,
        view: &TerrainViewGpu,
        visibility: Option<&Buffer>,
    ) {
        let (traverse, lod_map, select) = (self.traverse, self.lod_map, self.select);
        pass(frame, log, FramePass::Traverse, |r| traverse.record(r, tree, params, TraverseMode::SingleDispatch));
        pass(frame, log, FramePass::LodMap, |r| lod_map.record(r, traverse));
        pass(frame, log, FramePass::SectorData, |r| self.sector_data.record(r, tree));
        pass(frame, log, FramePass::SelectPatches, |r| {
            select.record(r, traverse, tree, lod_map, self.view_buffer, bytemuck::bytes_of(view))
        });
        let cull = self.cull_frame();
        pass(frame, log, FramePass::CullPatches, |r| {
            self.cull.record(r, traverse, tree, lod_map, select, self.view_buffer, cull, visibility)
        });
    }

    /// The terrain draws, and with occlusion the pyramid, phase 2's culling
    /// and its draws (or, switched off this frame, their empty lists).
    pub fn record_draws(
        &self,
        frame: &mut Frame<'_, '_>,
        log: &mut FrameLog,
        tree: &GpuQuadtree,
        targets: &RenderTargets,
        gb: &GBuffer,
    ) {
        let (geometry, view) = (self.geometry, self.view_buffer);
        pass(frame, log, FramePass::TerrainGeometry, |r| {
            geometry.record(r, targets, gb, view, &self.cull.lists().list, tree, true)
        });
        if let Some(holes) = self.holes_drawn(log, FramePass::TerrainHoles) {
            pass(frame, log, FramePass::TerrainHoles, |r| {
                holes.record(r, targets, gb, view, self.cull.lists(), geometry, tree, false)
            });
        }
        let Some(o) = self.occlusion else { return };
        if !self.stages.occlusion {
            // Built but off this frame: nothing drawn in phase 2.
            let passes = [FramePass::HizBuild, FramePass::CullOccluded, FramePass::TerrainGeometryLate];
            for p in passes.into_iter().chain(self.holes.map(|_| FramePass::TerrainHolesLate)) {
                log.skipped(p, Skip::OcclusionOff);
            }
            frame.untimed(QueueKind::Graphics, |r| {
                o.cull.lists.reset(r);
                r.barrier(vk::PipelineStageFlags2::ALL_TRANSFER, vk::PipelineStageFlags2::ALL_COMMANDS);
            });
            return;
        }
        let (traverse, lod_map, select, cull) = (self.traverse, self.lod_map, self.select, self.cull_frame());
        pass(frame, log, FramePass::HizBuild, |r| o.hiz.record(r, targets.depth));
        pass(frame, log, FramePass::CullOccluded, |r| {
            o.cull.record(r, traverse, tree, lod_map, select, view, cull, &o.hiz, targets.depth)
        });
        let late = &o.cull.lists;
        pass(frame, log, FramePass::TerrainGeometryLate, |r| {
            geometry.record(r, targets, gb, view, &late.list, tree, false)
        });
        if let Some(holes) = self.holes_drawn(log, FramePass::TerrainHolesLate) {
            pass(frame, log, FramePass::TerrainHolesLate, |r| {
                holes.record(r, targets, gb, view, late, geometry, tree, true)
            });
        }
    }

    /// The virtual texture's writes, pages and feedback (each skipped
    /// where the CPU knows it has nothing to do).
    #[allow(clippy::too_many_arguments)]
    fn record_virtual_texture(
        &self,
        frame: &mut Frame<'_, '_>,
        log: &mut FrameLog,
        vt: &VirtualTexture,
        f: &VtFrame,
        terrain: VistaTerrain,
        tree: &GpuQuadtree,
        targets: &RenderTargets,
        gb: &GBuffer,
        m: &MaterialBindings,
    ) {
        if f.init {
            frame.untimed(QueueKind::Graphics, |r| vt.record_init(r));
        }
        if f.writes.is_empty() {
            log.skipped(FramePass::VtUpdate, Skip::NoVtWrites);
        } else {
            frame.pass(FramePass::VtUpdate.name(), false, QueueKind::Graphics, |r| vt.record_update(r, &f.writes));
            log.ran(FramePass::VtUpdate, Some(f.writes.len() as u64));
        }
        if f.jobs.is_empty() {
            log.skipped(FramePass::VtPages, Skip::NoVtPages);
        } else {
            let sector = self.sector_data.buffer();
            frame.pass(FramePass::VtPages.name(), false, QueueKind::Graphics, |r| {
                vt.record_pages(r, f, terrain, sector, tree, m)
            });
            log.ran(FramePass::VtPages, Some(f.jobs.len() as u64));
        }
        pass(frame, log, FramePass::VtFeedback, |r| vt.record_feedback(r, f, self.view_buffer, targets, gb));
    }

    /// Effect `cliff_meshes`: their build (when due) and draw, over the
    /// terrain's geometry pass.
    pub fn record_cliff_meshes(
        &self,
        frame: &mut Frame<'_, '_>,
        log: &mut FrameLog,
        tree: &GpuQuadtree,
        targets: &RenderTargets,
        gb: &GBuffer,
    ) {
        let Some((c, build)) = self.cliff_meshes else { return };
        let (view, sector) = (self.view_buffer, self.sector_data.buffer());
        match build {
            Some(push) => pass(frame, log, FramePass::CliffMeshBuild, |r| c.record_build(r, push, sector, tree)),
            None => log.skipped(FramePass::CliffMeshBuild, Skip::CliffMeshesCurrent),
        }
        pass(frame, log, FramePass::CliffMeshes, |r| c.record_draw(r, targets, gb, view));
    }

    /// The displacement decals' meshes, over the terrain's geometry pass.
    pub fn record_decal_meshes(
        &self,
        frame: &mut Frame<'_, '_>,
        log: &mut FrameLog,
        tree: &GpuQuadtree,
        world: &WorldDesc,
        targets: &RenderTargets,
        gb: &GBuffer,
    ) {
        let Some(m) = self.decal_meshes else { return };
        if m.is_empty() {
            log.skipped(FramePass::DecalMeshes, Skip::NoDisplacement);
            return;
        }
        let terrain = VistaTerrain::new(world, self.sector_data);
        let (view, sector) = (self.view_buffer, self.sector_data.buffer());
        pass(frame, log, FramePass::DecalMeshes, |r| m.record(r, targets, gb, view, terrain, sector, tree));
    }

    /// Effect `grass`: the pigment map (when due) and the placement, culled
    /// by the pyramid this frame built, if it built one.
    fn record_grass_place(&self, frame: &mut Frame<'_, '_>, log: &mut FrameLog, tree: &GpuQuadtree) {
        let Some((grass, f)) = self.grass else { return };
        let sector = self.sector_data.buffer();
        let decals = self.virtual_texture.and_then(|(vt, _)| vt.decal_resources());
        if f.pigment_due {
            let m = self.materials.expect("grass needs splat's materials").bindings();
            pass(frame, log, FramePass::GrassPigment, |r| grass.record_pigment(r, f, sector, tree, &m, decals));
        } else {
            log.skipped(FramePass::GrassPigment, Skip::PigmentCurrent);
        }
        let hiz = self.occlusion.filter(|_| self.stages.occlusion).and_then(|o| o.hiz.pyramid());
        pass(frame, log, FramePass::GrassPlace, |r| {
            grass.record_place(r, f, self.view_buffer, hiz, sector, tree, decals)
        });
    }

    /// The G-buffer tile shading and the lit output.
    pub fn record_shading(
        &self,
        frame: &mut Frame<'_, '_>,
        log: &mut FrameLog,
        tree: &GpuQuadtree,
        world: &WorldDesc,
        targets: &RenderTargets,
        gb: &GBuffer,
    ) {
        self.record_grass_place(frame, log, tree);
        let classify = self.classify;
        pass(frame, log, FramePass::ClassifyTiles, |r| classify.record(r, gb, self.force_flavours));
        let lists = classify.lists.as_ref().expect("prepared before the frame");
        let terrain = VistaTerrain::new(world, self.sector_data);
        let mut materials = self.materials.map(|m| m.bindings());
        if let (Some(m), Some((vt, f))) = (materials.as_mut(), self.virtual_texture) {
            self.record_virtual_texture(frame, log, vt, f, terrain, tree, targets, gb, m);
            m.virtual_texture = Some(vt.bindings());
        }
        frame.untimed(QueueKind::Graphics, |r| GbufferTiles::begin(r, targets, gb));
        for (i, bits) in self.gbuffer_tiles.variants().into_iter().enumerate() {
            let tiles = self.gbuffer_tiles;
            frame.pass(variant_label(bits), false, QueueKind::Graphics, |r| {
                let sector = self.sector_data.buffer();
                let m = materials.as_ref();
                tiles.record_variant(r, bits, i == 0, targets, gb, self.view_buffer, lists, sector, terrain, tree, m)
            });
        }
        log.ran(FramePass::GbufferTiles, None);
        if let Some((pass_, assets)) = self.assets {
            let (view, sector) = (self.view_buffer, self.sector_data.buffer());
            // The splat colours where the pass was built with them.
            let m = materials.as_ref().filter(|_| pass_.materials());
            pass(frame, log, FramePass::AssetDraw, |r| {
                pass_.record(r, targets, gb, view, assets, terrain, sector, tree, m)
            });
        }
        if let Some((grass, f)) = self.grass {
            pass(frame, log, FramePass::GrassDraw, |r| grass.record_draw(r, f, self.view_buffer, targets, gb));
        }
        match self.shadows {
            Some((_, [], _, _)) => log.skipped(FramePass::SunShadows, Skip::ShadowsCurrent),
            Some((s, jobs, sun, _)) => {
                frame.pass(FramePass::SunShadows.name(), false, QueueKind::Graphics, |r| {
                    s.record(r, jobs, sun, terrain, self.sector_data, tree)
                });
                log.ran(FramePass::SunShadows, Some(jobs.len() as u64));
            }
            None if self.shadows_off => log.skipped(FramePass::SunShadows, Skip::ShadowsOff),
            None => {}
        }
        let Some(resolve) = self.resolve else {
            // Output `gbuffer`: the engine lights; neither pass is built.
            // The depth goes back to its frame layout (the tile passes left
            // it read-only).
            let layout = depth_layout(targets.depth.format, false);
            frame.untimed(QueueKind::Graphics, |r| r.transition(targets.depth, layout));
            return;
        };
        let inputs = ResolveInputs {
            terrain,
            sector_data: self.sector_data,
            tree,
            shadows: self.shadows.map(|(s, _, _, elevation)| ShadowInput {
                atlas: &s.atlas,
                penumbra: s.params.penumbra(elevation),
                resolution: s.params.resolution,
            }),
            fog: self.fog,
        };
        pass(frame, log, FramePass::LightingResolve, |r| resolve.record(r, targets, gb, self.view_buffer, &inputs));
        match self.debug {
            Some((p, view)) => pass(frame, log, FramePass::DebugView, |r| p.record(r, targets, gb, view)),
            None => log.skipped(FramePass::DebugView, Skip::NoDebugView),
        }
    }
}

//! One frame's passes after streaming, recorded phase by phase: the LOD
//! phase (traverse, lod_map, sector_data, select_patches, cull_patches),
//! the draws (terrain_geometry, terrain_holes and occlusion's phase 2),
//! then the shading (classify_tiles, gbuffer_tiles, lighting_resolve,
//! debug_view), with the built effects recording at their points between
//! them ([`FramePoint`]). The renderer lends its passes apart from the
//! frame executor and the streaming state ([`FramePasses`]); each pass is
//! logged in the frame's [`FrameLog`] as the graph expects.

use crate::effects::frame_effect::{FrameEffect, FramePoint, RecordInputs};
use crate::frame::{Frame, QueueKind};
use crate::gpu::{depth_layout, vk, Buffer, Image, Recorder};
use crate::passes::classify_tiles::ClassifyTiles;
use crate::passes::cull_patches::{CullFrame, CullPatches, CullStages};
use crate::passes::debug_view::{DebugView, DebugViewPass};
use crate::passes::emit_triangles::{EmitInputs, EmitPhase};
use crate::passes::gbuffer_tiles::{variant_label, GbufferTiles, MaterialBindings};
use crate::passes::lighting_resolve::{LightingResolve, ResolveInputs};
use crate::passes::lod_map::LodMap;
use crate::passes::sector_data::SectorData;
use crate::passes::select_patches::SelectPatches;
use crate::passes::terrain_geometry::{RenderTargets, TerrainGeometry};
use crate::passes::terrain_holes::TerrainHoles;
use crate::passes::terrain_query::VistaTerrain;
use crate::passes::traverse::{Traverse, TraverseMode};
use crate::render::renderer::{Occlusion, TrianglePath};
use crate::scene::graph::{FrameLog, FramePass, Skip};
use crate::scene::view::TerrainViewGpu;
use crate::targets::gbuffer::GBuffer;
use crate::terrain::gpu_quadtree::GpuQuadtree;
use crate::terrain::selection::TraverseParams;
use crate::world::WorldDesc;

pub(crate) struct FramePasses<'a> {
    pub traverse: &'a Traverse,
    pub lod_map: &'a LodMap,
    pub sector_data: &'a SectorData,
    pub select: &'a SelectPatches,
    pub cull: &'a CullPatches,
    pub occlusion: Option<&'a Occlusion>,
    /// The per-triangle rule: it cuts and draws instead of select, cull,
    /// geometry and holes.
    pub triangles: Option<&'a TrianglePath>,
    pub geometry: &'a TerrainGeometry,
    pub holes: Option<&'a TerrainHoles>,
    pub classify: &'a ClassifyTiles,
    pub gbuffer_tiles: &'a GbufferTiles,
    pub resolve: Option<&'a LightingResolve>,
    pub debug: Option<(&'a DebugViewPass, DebugView)>,
    pub view_buffer: &'a Buffer,
    /// The LOD phase's view when it is not the frame's
    /// ([`crate::render::TerrainRenderer::lod_camera`]).
    pub lod_view_buffer: &'a Buffer,
    pub stages: CullStages,
    /// The per-triangle rule's cut runs in occlusion's two phases this
    /// frame, where built (off: one phase emits every triangle).
    pub triangle_phases: bool,
    pub holes_off: bool,
    pub force_flavours: u32,
    /// The built effects, in registry order.
    pub effects: &'a [Box<dyn FrameEffect>],
}

/// What the draws and the shading record into.
pub(crate) struct FrameTargets<'a> {
    pub tree: &'a GpuQuadtree,
    pub world: &'a WorldDesc,
    pub targets: &'a RenderTargets<'a>,
    pub gbuffer: &'a GBuffer,
}

fn pass<'r>(frame: &mut Frame<'_, 'r>, log: &mut FrameLog, p: FramePass, f: impl FnOnce(&mut Recorder<'r>)) {
    frame.pass(p.name(), p.late(), p.queue(), f);
    log.ran(p, None);
}

/// The material bindings the effects make (`shading`: with what the tile
/// shading adds).
fn materials<'a>(effects: &'a [Box<dyn FrameEffect>], shading: bool) -> Option<MaterialBindings<'a>> {
    let mut m = None;
    for e in effects {
        e.bind_materials(&mut m, shading);
    }
    m
}

impl FramePasses<'_> {
    fn cull_frame(&self) -> CullFrame {
        CullFrame { stages: self.stages, holes: !self.holes_off }
    }

    fn holes_drawn(&self, log: &mut FrameLog, p: FramePass) -> Option<&TerrainHoles> {
        if self.holes.is_some() && self.holes_off {
            log.skipped(p, Skip::HolesOff);
            return None;
        }
        self.holes
    }

    /// The depth pyramid, when occlusion is built and on this frame.
    fn hiz(&self) -> Option<&Image> {
        self.occlusion.filter(|_| self.stages.occlusion).and_then(|o| o.hiz.pyramid())
    }

    fn inputs<'b>(&'b self, t: &'b FrameTargets<'b>, materials: Option<&'b MaterialBindings<'b>>) -> RecordInputs<'b> {
        RecordInputs {
            tree: t.tree,
            world: t.world,
            terrain: VistaTerrain::new(t.world, self.sector_data),
            sector_data: self.sector_data,
            view_buffer: self.view_buffer,
            targets: t.targets,
            gbuffer: t.gbuffer,
            materials,
            hiz: self.hiz(),
            effects: self.effects,
        }
    }

    /// Every built effect records at `point`, in registry order.
    fn at(&self, point: FramePoint, frame: &mut Frame<'_, '_>, log: &mut FrameLog, inputs: &RecordInputs) {
        for e in self.effects {
            e.record(point, frame, log, inputs);
        }
    }

    /// The LOD phase. `lod`: the constants of the camera the LOD is chosen
    /// for when it is not the frame's (`view`'s): the phase then reads
    /// them from its own buffer, and the frame's buffer gets `view`
    /// first, on the same queue, for whatever else reads it.
    #[allow(clippy::too_many_arguments)]
    pub fn record_lod(
        &self,
        frame: &mut Frame<'_, '_>,
        log: &mut FrameLog,
        tree: &GpuQuadtree,
        params: &TraverseParams,
        view: &TerrainViewGpu,
        lod: Option<&TerrainViewGpu>,
        visibility: Option<&Buffer>,
    ) {
        let (traverse, lod_map, select) = (self.traverse, self.lod_map, self.select);
        let (view_buffer, view) = match lod {
            Some(lod) => {
                frame.untimed(FramePass::SELECT_PATCHES.queue(), |r| {
                    r.barrier(vk::PipelineStageFlags2::ALL_COMMANDS, vk::PipelineStageFlags2::ALL_TRANSFER);
                    r.update_buffer(self.view_buffer, 0, bytemuck::bytes_of(view));
                    r.barrier(vk::PipelineStageFlags2::ALL_TRANSFER, vk::PipelineStageFlags2::ALL_COMMANDS);
                });
                (self.lod_view_buffer, lod)
            }
            None => (self.view_buffer, view),
        };
        pass(frame, log, FramePass::TRAVERSE, |r| traverse.record(r, tree, params, TraverseMode::SingleDispatch));
        pass(frame, log, FramePass::LOD_MAP, |r| lod_map.record(r, traverse));
        pass(frame, log, FramePass::SECTOR_DATA, |r| self.sector_data.record(r, tree));
        if let Some(t) = self.triangles {
            let view_bytes = bytemuck::bytes_of(view);
            let inputs = EmitInputs {
                traverse,
                tree,
                lod_map,
                view: view_buffer,
                view_bytes,
                frustum: self.stages.frustum,
                holes: self.stages.hole,
                facing: self.stages.cone,
            };
            let phase = if self.triangle_phases(t) { EmitPhase::Early } else { EmitPhase::All };
            pass(frame, log, FramePass::EMIT_TRIANGLES, |r| t.emit.record(r, &inputs, phase));
            pass(frame, log, FramePass::EMIT_FINE, |r| t.fine.record(r, &t.emit, &inputs, false));
            return;
        }
        pass(frame, log, FramePass::SELECT_PATCHES, |r| {
            select.record(r, traverse, tree, lod_map, view_buffer, bytemuck::bytes_of(view))
        });
        let cull = self.cull_frame();
        pass(frame, log, FramePass::CULL_PATCHES, |r| {
            self.cull.record(r, traverse, tree, lod_map, select, view_buffer, cull, visibility)
        });
    }

    /// The cells an effect's surface replaces (terrain_sink.rs).
    fn sink(&self) -> Option<&Buffer> {
        self.effects.iter().find_map(|e| e.terrain_sink())
    }

    /// What the effects record before the terrain's draws, the draws (both
    /// occlusion phases), then what the effects draw beside them.
    pub fn record_draws(&self, frame: &mut Frame<'_, '_>, log: &mut FrameLog, t: &FrameTargets) {
        let (tree, targets, gb) = (t.tree, t.targets, t.gbuffer);
        let (geometry, view, sink) = (self.geometry, self.view_buffer, self.sink());
        let base = materials(self.effects, false);
        self.at(FramePoint::BeforeTerrainDraws, frame, log, &self.inputs(t, base.as_ref()));
        if let Some(tri) = self.triangles {
            pass(frame, log, FramePass::TERRAIN_TRIANGLES, |r| {
                tri.draw.record(r, targets, gb, view, &tri.emit, false, tree, sink)
            });
            self.record_triangles_late(frame, log, t, tri);
            self.at(FramePoint::AfterTerrainDraws, frame, log, &self.inputs(t, base.as_ref()));
            return;
        }
        pass(frame, log, FramePass::TERRAIN_GEOMETRY, |r| {
            geometry.record(r, targets, gb, view, &self.cull.lists().list, tree, sink, true)
        });
        if let Some(holes) = self.holes_drawn(log, FramePass::TERRAIN_HOLES) {
            pass(frame, log, FramePass::TERRAIN_HOLES, |r| {
                holes.record(r, targets, gb, view, self.cull.lists(), geometry, tree, sink, false)
            });
        }
        if let Some(o) = self.occlusion {
            self.record_phase_two(frame, log, t, o);
        }
        self.at(FramePoint::AfterTerrainDraws, frame, log, &self.inputs(t, base.as_ref()));
    }

    /// Whether the per-triangle rule's cut runs in two phases this frame.
    fn triangle_phases(&self, t: &TrianglePath) -> bool {
        t.hiz.is_some() && self.triangle_phases
    }

    /// The per-triangle rule's phase 2, where occlusion is built: the
    /// pyramid of phase 1's depth, the subtrees it leaves visible and
    /// their draw.
    fn record_triangles_late(
        &self,
        frame: &mut Frame<'_, '_>,
        log: &mut FrameLog,
        t: &FrameTargets,
        tri: &TrianglePath,
    ) {
        let Some(hiz) = &tri.hiz else { return };
        let late = [
            FramePass::HIZ_BUILD,
            FramePass::EMIT_TRIANGLES_LATE,
            FramePass::EMIT_FINE_LATE,
            FramePass::TERRAIN_TRIANGLES_LATE,
        ];
        if !self.triangle_phases(tri) {
            let why = if self.stages.occlusion { Skip::LodCamera } else { Skip::OcclusionOff };
            late.into_iter().for_each(|p| log.skipped(p, why));
            return;
        }
        let (tree, targets, gb, view) = (t.tree, t.targets, t.gbuffer, self.view_buffer);
        pass(frame, log, FramePass::HIZ_BUILD, |r| hiz.record(r, targets.depth));
        let pyramid = hiz.pyramid().expect("hiz_build ran");
        let inputs = EmitInputs {
            traverse: self.traverse,
            tree,
            lod_map: self.lod_map,
            view,
            view_bytes: &[],
            frustum: self.stages.frustum,
            holes: self.stages.hole,
            facing: self.stages.cone,
        };
        let phase = EmitPhase::Late(pyramid, targets.depth.extent);
        pass(frame, log, FramePass::EMIT_TRIANGLES_LATE, |r| tri.emit.record(r, &inputs, phase));
        pass(frame, log, FramePass::EMIT_FINE_LATE, |r| tri.fine.record(r, &tri.emit, &inputs, true));
        pass(frame, log, FramePass::TERRAIN_TRIANGLES_LATE, |r| {
            tri.draw.record(r, targets, gb, view, &tri.emit, true, tree, self.sink())
        });
    }

    fn record_phase_two(&self, frame: &mut Frame<'_, '_>, log: &mut FrameLog, t: &FrameTargets, o: &Occlusion) {
        let (tree, targets, gb) = (t.tree, t.targets, t.gbuffer);
        if !self.stages.occlusion {
            let passes = [FramePass::HIZ_BUILD, FramePass::CULL_OCCLUDED, FramePass::TERRAIN_GEOMETRY_LATE];
            for p in passes.into_iter().chain(self.holes.map(|_| FramePass::TERRAIN_HOLES_LATE)) {
                log.skipped(p, Skip::OcclusionOff);
            }
            frame.untimed(QueueKind::Graphics, |r| {
                o.cull.lists.reset(r);
                r.barrier(vk::PipelineStageFlags2::ALL_TRANSFER, vk::PipelineStageFlags2::ALL_COMMANDS);
            });
            return;
        }
        let (traverse, lod_map, select, cull) = (self.traverse, self.lod_map, self.select, self.cull_frame());
        let (geometry, view) = (self.geometry, self.view_buffer);
        pass(frame, log, FramePass::HIZ_BUILD, |r| o.hiz.record(r, targets.depth));
        pass(frame, log, FramePass::CULL_OCCLUDED, |r| {
            o.cull.record(r, traverse, tree, lod_map, select, view, cull, &o.hiz, targets.depth)
        });
        let late = &o.cull.lists;
        pass(frame, log, FramePass::TERRAIN_GEOMETRY_LATE, |r| {
            geometry.record(r, targets, gb, view, &late.list, tree, self.sink(), false)
        });
        if let Some(holes) = self.holes_drawn(log, FramePass::TERRAIN_HOLES_LATE) {
            pass(frame, log, FramePass::TERRAIN_HOLES_LATE, |r| {
                holes.record(r, targets, gb, view, late, geometry, tree, self.sink(), true)
            });
        }
    }

    /// Classification, the tile shading and what the effects record
    /// around it, then the resolve and the debug view.
    pub fn record_shading(&self, frame: &mut Frame<'_, '_>, log: &mut FrameLog, t: &FrameTargets) {
        let (targets, gb) = (t.targets, t.gbuffer);
        let base = materials(self.effects, false);
        let before = self.inputs(t, base.as_ref());
        self.at(FramePoint::BeforeClassify, frame, log, &before);
        let classify = self.classify;
        pass(frame, log, FramePass::CLASSIFY_TILES, |r| classify.record(r, gb, self.force_flavours));
        self.at(FramePoint::BeforeTiles, frame, log, &before);
        let shading = materials(self.effects, true);
        self.record_tiles(frame, log, t, shading.as_ref());
        let after = self.inputs(t, shading.as_ref());
        self.at(FramePoint::AfterTiles, frame, log, &after);
        self.at(FramePoint::BeforeResolve, frame, log, &after);
        let Some(resolve) = self.resolve else {
            let layout = depth_layout(targets.depth.format, false);
            frame.untimed(QueueKind::Graphics, |r| r.transition(targets.depth, layout));
            return;
        };
        let mut inputs = ResolveInputs {
            terrain: after.terrain,
            sector_data: self.sector_data,
            tree: t.tree,
            shadows: None,
            fog: None,
        };
        for e in self.effects {
            e.bind_resolve(&mut inputs);
        }
        pass(frame, log, FramePass::LIGHTING_RESOLVE, |r| resolve.record(r, targets, gb, self.view_buffer, &inputs));
        match self.debug {
            Some((p, view)) => pass(frame, log, FramePass::DEBUG_VIEW, |r| p.record(r, targets, gb, view)),
            None => log.skipped(FramePass::DEBUG_VIEW, Skip::NoDebugView),
        }
    }

    /// One timed draw per variant of the tile shading.
    fn record_tiles(
        &self,
        frame: &mut Frame<'_, '_>,
        log: &mut FrameLog,
        t: &FrameTargets,
        m: Option<&MaterialBindings>,
    ) {
        let (tree, targets, gb) = (t.tree, t.targets, t.gbuffer);
        let lists = self.classify.lists.as_ref().expect("prepared before the frame");
        let terrain = VistaTerrain::new(t.world, self.sector_data);
        frame.untimed(QueueKind::Graphics, |r| GbufferTiles::begin(r, targets, gb));
        for (i, bits) in self.gbuffer_tiles.variants().into_iter().enumerate() {
            let tiles = self.gbuffer_tiles;
            frame.pass(variant_label(bits), false, QueueKind::Graphics, |r| {
                let sector = self.sector_data.buffer();
                tiles.record_variant(r, bits, i == 0, targets, gb, self.view_buffer, lists, sector, terrain, tree, m)
            });
        }
        log.ran(FramePass::GBUFFER_TILES, None);
    }
}

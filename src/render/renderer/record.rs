//! Recording one frame, phase by phase: checks, streaming, the effects'
//! plans, the quadtree update, the LOD phase, the draws, the shading and
//! the counters' copy (see [`TerrainRenderer::record_frame`]).

use super::{counter_lists, TerrainRenderer};
use crate::effects::frame_effect::{PlanInputs, SharedPlan};
use crate::effects::Effect;
use crate::error::Result;
use crate::frame::{Frame, QueueKind};
use crate::gpu::{Context, FrameCommands, QueueMode};
use crate::passes::quadtree_update::QuadtreeUpdatePass;
use crate::passes::terrain_geometry::RenderTargets;
use crate::passes::terrain_query::VistaTerrain;
use crate::render::frame_passes::{FramePasses, FrameTargets};
use crate::render::telemetry::CounterSources;
use crate::scene::graph::{FrameLog, FramePass, Skip};
use crate::scene::shading::{ShadeRules, Shading};
use crate::scene::view::{TerrainViewGpu, View};
use crate::terrain::quadtree::texture_extent;
use crate::terrain::selection::TraverseParams;

/// What the frame knew when it began.
struct Begun<'c> {
    ctx: &'c Context,
    /// The context's number of the frame.
    ctx_frame: u64,
    /// The resident terrain changes this frame.
    terrain_changed: bool,
    /// What the traversal selects for (the streaming's too).
    params: TraverseParams,
    /// The view the LOD is chosen for, when not the frame's.
    lod_view: Option<View>,
}

impl TerrainRenderer {
    /// Records one frame into the command buffers of `mode`: its phases.
    pub fn record_frame(
        &mut self,
        mut cmds: FrameCommands,
        mode: QueueMode,
        view: &View,
        targets: &RenderTargets,
    ) -> Result<()> {
        let started = std::time::Instant::now();
        let view = &self.check_frame(view, targets)?;
        let ctx = match &mut cmds {
            FrameCommands::One(r) => r.context(),
            FrameCommands::Split { graphics, .. } => graphics.context(),
        };
        self.prepare_frame(ctx, view, targets)?;
        let ctx_frame = ctx.frame_recording();
        self.telemetry.harvest(ctx);
        if let (Some(t), Some([early, late])) =
            (&mut self.triangles, self.telemetry.latest().and_then(|c| c.triangle_lists))
        {
            t.emit.emitted(early.triangles, late.triangles);
        }
        let lod_view = self.lod_camera.map(|camera| View { camera, ..view.clone() });
        let params = lod_view.as_ref().unwrap_or(view).traverse_params();
        self.terrain.stream(&params)?;
        let switched_off = self.switched_off();
        // The frame borrows the executor while the rest of the renderer
        // records into it.
        let next = self.exec.as_ref().expect("one frame records at a time").next_frame();
        if let Some(t) = &mut self.triangles {
            t.emit.select_frame(ctx, next)?;
        }
        let mut exec = self.exec.take().expect("one frame records at a time");
        self.select_copies(exec.next_frame());
        let terrain_changed = self.terrain.tree.has_work();
        let begin = std::time::Instant::now();
        let mut frame = exec.begin(cmds, mode);
        let query_ms = begin.elapsed().as_secs_f64() * 1e3;
        let mut log = self.graph.begin_frame(frame.number());
        log.switched_off = switched_off;
        let begun = Begun { ctx, ctx_frame, terrain_changed, params, lod_view };
        let recorded = self.record_phases(&mut frame, &mut log, &begun, view, targets);
        let number = frame.number();
        drop(frame);
        // The executor's read of finished timestamps is the driver's time
        // (lavapipe drains the device there), not the renderer's work.
        exec.set_cpu_ms(number, started.elapsed().as_secs_f64() * 1e3 - query_ms, query_ms);
        self.exec = Some(exec);
        recorded?;
        self.graph.end_frame(log);
        self.mode = Some(mode);
        Ok(())
    }

    /// After the frame began: the quadtree update, the effects' plans, the
    /// passes and the counters' copy.
    fn record_phases(
        &mut self,
        frame: &mut Frame<'_, '_>,
        log: &mut FrameLog,
        begun: &Begun,
        view: &View,
        targets: &RenderTargets,
    ) -> Result<()> {
        let (ctx, ctx_frame) = (begun.ctx, begun.ctx_frame);
        let (shade, number) = (self.frame_shade(), frame.number());
        let gpu = self.view_constants(view, &shade);
        let visibility = self.occlusion.as_ref().map(|o| o.cull.visibility());
        record_quadtree_update(frame, log, &mut self.terrain.tree, &self.update, visibility)?;
        let plan = PlanInputs {
            ctx,
            frame: [number, ctx_frame],
            view,
            camera_world: [gpu.camera_world[0], gpu.camera_world[1], gpu.camera_world[2]],
            terrain: &self.terrain,
            vista_terrain: VistaTerrain::new(&self.terrain.world, &self.sector_data),
            shade: &shade,
            effects: &self.effects,
            switches: self.switches,
            holes: self.holes.is_some() && self.switches.holes,
            hiz: self.occlusion.is_some() && self.stages.occlusion,
            depth_size: targets.depth.extent,
            terrain_changed: begun.terrain_changed,
        };
        let mut shared = SharedPlan::default();
        self.built.iter().for_each(|e| e.share(&mut shared));
        for e in &mut self.built {
            e.plan(&plan, &shared)?;
        }
        self.prepare_resolve(ctx, log)?;
        let lod_gpu = begun.lod_view.as_ref().map(|v| self.view_constants(v, &shade));
        self.record_passes(frame, log, &begun.params, targets, (&gpu, lod_gpu.as_ref()), &shade);
        self.record_counters(frame, number, ctx_frame);
        Ok(())
    }

    /// The GPU's view constants of the next frame.
    fn view_constants(&self, view: &View, shade: &ShadeRules) -> TerrainViewGpu {
        let world = &self.terrain.world;
        let mut gpu = view.gpu(world, texture_extent(world), &self.effects.lighting, shade);
        gpu.lod_params[2] = self.lod.refine_levels as f32;
        gpu.lod_params[3] = if self.lod.stitched() { 0.0 } else { 1.0 };
        gpu
    }

    /// The resolve's variant for what shows this frame; a built effect
    /// switched on that does not show yet (it catches up) is logged as
    /// switched off.
    fn prepare_resolve(&mut self, ctx: &Context, log: &mut FrameLog) -> Result<()> {
        for e in self.built.iter().filter(|e| !e.shown() && self.switches.on(e.effect())) {
            log.switched_off.insert(0, e.effect());
        }
        let shown = |effect| self.built.iter().any(|e| e.effect() == effect && e.shown());
        let (shadows, atmosphere) = (shown(Effect::Shadows), self.switches.on(Effect::Atmosphere));
        match &mut self.resolve {
            Some(resolve) => resolve.prepare(ctx, self.switches.lighting, shadows, atmosphere),
            None => Ok(()),
        }
    }

    fn record_passes(
        &self,
        frame: &mut Frame<'_, '_>,
        log: &mut FrameLog,
        params: &TraverseParams,
        targets: &RenderTargets,
        (gpu, lod_gpu): (&TerrainViewGpu, Option<&TerrainViewGpu>),
        shade: &ShadeRules,
    ) {
        let passes = FramePasses {
            traverse: &self.traverse,
            lod_map: &self.lod_map,
            sector_data: &self.sector_data,
            select: &self.select,
            cull: &self.cull,
            occlusion: self.occlusion.as_ref(),
            triangles: self.triangles.as_ref(),
            geometry: &self.geometry,
            holes: self.holes.as_ref(),
            classify: &self.classify,
            gbuffer_tiles: &self.gbuffer_tiles,
            resolve: self.resolve.as_ref(),
            debug: self.debug_pass.as_ref().zip(self.debug_view),
            view_buffer: self.view_buffer.current(),
            lod_view_buffer: self.lod_view_buffer.current(),
            stages: self.stages,
            // A cut made for another camera cannot be tested against this
            // view's depth.
            triangle_phases: self.stages.occlusion && lod_gpu.is_none(),
            holes_off: !self.switches.holes,
            force_flavours: if self.shading == Shading::Tiled { 0 } else { shade.allowed },
            effects: &self.built,
        };
        let tree = &self.terrain.tree;
        let gbuffer = self.gbuffer.as_ref().expect("made by prepare_frame");
        let t = FrameTargets { tree, world: &self.terrain.world, targets, gbuffer };
        let visibility = self.occlusion.as_ref().map(|o| o.cull.visibility());
        passes.record_lod(frame, log, tree, params, gpu, lod_gpu, visibility);
        passes.record_draws(frame, log, &t);
        passes.record_shading(frame, log, &t);
    }

    /// The frame's counters, copied for the telemetry to read frames late.
    fn record_counters(&mut self, frame: &mut Frame<'_, '_>, number: u64, ctx_frame: u64) {
        let sources = CounterSources {
            traverse: self.traverse.output(),
            lists: counter_lists(&self.cull, &self.occlusion),
            triangle_lists: self.triangles.as_ref().map_or([None, None], |t| [Some(t.emit.list()), t.emit.late_list()]),
            tiles: self.classify.lists.as_ref().map(|l| &l.buffer),
            select: self.select.levels(),
            effects: self.built.iter().filter_map(|e| e.counters().map(|(b, _)| b)).collect(),
        };
        let telemetry = &mut self.telemetry;
        frame.untimed(QueueKind::Graphics, |r| telemetry.record(r, number, ctx_frame, &sources));
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
        self.lod_view_buffer.select(frame);
    }
}

/// The quadtree's changes; the last frame's reach this frame's node
/// texture copy too.
fn record_quadtree_update(
    frame: &mut Frame<'_, '_>,
    log: &mut FrameLog,
    tree: &mut crate::terrain::gpu_quadtree::GpuQuadtree,
    update: &QuadtreeUpdatePass,
    visibility: Option<&crate::gpu::Buffer>,
) -> Result<()> {
    if tree.has_work() || tree.previous_updates().is_some() {
        let writes =
            frame.pass(QuadtreeUpdatePass::NAME, false, QueueKind::Compute, |r| update.record(r, tree, visibility))?;
        log.ran(FramePass::QUADTREE_UPDATE, Some(u64::from(writes)));
    } else {
        log.skipped(FramePass::QUADTREE_UPDATE, Skip::NothingToUpload);
    }
    Ok(())
}

//! The pass report: which effects are on and why, the pipelines built, and
//! per pass of the last recorded frame whether it was not built, built but
//! idle, or ran, with its GPU time and the work it did; GPU memory per
//! effect. `vista render --report` prints it and writes report.json.
//!
//! Building it reads the frame's GPU counters back and so waits for the
//! GPU: it is for tools and tests. An engine's frame loop reads the same
//! counters frames late with `TerrainRenderer::latest_counters`.

use crate::effects::{Effect, EffectDecision};
use crate::error::Result;
use crate::frame::{FrameTimings, QueueKind};
use crate::gpu::{Context, QueueMode};
use crate::passes::gbuffer_tiles::variant_label;
use crate::render::renderer::TerrainRenderer;
use crate::render::telemetry::FrameCounters;
use crate::render::telemetry::TRIANGLES_PER_PATCH;
pub use crate::scene::graph::PassWork;
use crate::scene::graph::{FramePass, Outcome};
use crate::shaders::quadtree_update as update_sh;
use serde::Serialize;
use std::fmt::Write as _;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PassState {
    /// Its effect is off: no pipeline, no resource, never recorded.
    NotBuilt,
    /// Built, but nothing to do this frame: skipped on the CPU, or recorded
    /// with zero indirect work decided on the GPU.
    Idle,
    Ran,
}

/// What a pass did; a field is absent where it does not apply.
#[derive(Debug, Clone, Serialize)]
pub struct PassReport {
    pub name: &'static str,
    /// Phase 2 of occlusion culling (a drawing pass's second run).
    pub late: bool,
    /// The queue it ran on (graphics unless compute ran on its own queue).
    pub queue: QueueKind,
    /// The effects the pass exists for; empty: every scene needs it.
    pub effects: Vec<Effect>,
    pub state: PassState,
    /// Whether it carries timestamps this frame.
    pub recorded: bool,
    pub reason: String,
    pub gpu_ms: Option<f64>,
    pub work: PassWork,
}

#[derive(Debug, Clone, Serialize)]
pub struct ResourceMemory {
    pub name: String,
    pub bytes: u64,
    /// Effects it exists for; empty: every scene needs it.
    pub effects: Vec<Effect>,
}

#[derive(Debug, Clone, Serialize)]
pub struct FrameReport {
    /// The frame executor's number of the frame reported.
    pub frame: u64,
    /// How the frame was submitted.
    pub queue_mode: QueueMode,
    pub effects: Vec<EffectDecision>,
    /// Built effects switched off this frame (`FrameSwitches`).
    pub switched_off: Vec<Effect>,
    pub pipelines: Vec<String>,
    pub passes: Vec<PassReport>,
    pub memory: Vec<ResourceMemory>,
}

impl FrameReport {
    /// Bytes of resources that exist for `effect` alone.
    pub fn memory_of(&self, effect: Effect) -> u64 {
        self.memory.iter().filter(|m| m.effects == [effect]).map(|m| m.bytes).sum()
    }

    /// Bytes every scene needs.
    pub fn core_memory(&self) -> u64 {
        self.memory.iter().filter(|m| m.effects.is_empty()).map(|m| m.bytes).sum()
    }

    pub fn total_memory(&self) -> u64 {
        self.memory.iter().map(|m| m.bytes).sum()
    }

    /// Labels of the passes recorded this frame, in order.
    pub fn recorded_passes(&self) -> Vec<String> {
        self.passes.iter().filter(|p| p.recorded).map(|p| crate::frame::pass_label(p.name, p.late)).collect()
    }

    /// The pass named `name` (phase 1 where it runs twice).
    pub fn pass(&self, name: &str) -> Option<&PassReport> {
        self.passes.iter().find(|p| p.name == name && !p.late)
    }

    /// Phase 2 of the drawing pass `name`.
    pub fn late_pass(&self, name: &str) -> Option<&PassReport> {
        self.passes.iter().find(|p| p.name == name && p.late)
    }

    /// The report as text, one line per effect, pipeline group and pass.
    pub fn to_text(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "effects:");
        for d in &self.effects {
            let _ = writeln!(s, "  {:<16} {:<4} {}", d.effect.name(), if d.on { "on" } else { "off" }, d.reason);
        }
        if !self.switched_off.is_empty() {
            let names: Vec<&str> = self.switched_off.iter().map(|e| e.name()).collect();
            let _ = writeln!(s, "switched off this frame (built, FrameSwitches): {}", names.join(", "));
        }
        let _ = writeln!(s, "pipelines ({}): {}", self.pipelines.len(), self.pipelines.join(", "));
        let _ = writeln!(s, "passes of frame {} (queues: {}):", self.frame, self.queue_mode.name());
        for p in &self.passes {
            let state = match p.state {
                PassState::NotBuilt => "not built",
                PassState::Idle => "idle",
                PassState::Ran => "ran",
            };
            let ms = p.gpu_ms.map(|m| format!("{m:.3} ms")).unwrap_or_else(|| "-".into());
            let text = [work_text(&p.work), p.reason.clone()].into_iter().filter(|t| !t.is_empty()).collect::<Vec<_>>();
            let label = crate::frame::pass_label(p.name, p.late);
            let queue = match p.queue {
                QueueKind::Graphics => "",
                QueueKind::Compute => " [compute queue]",
            };
            let _ = writeln!(s, "  {label:<44} {state:<9} {ms:>10}  {}{queue}", text.join("; "));
        }
        let mb = |b: u64| b as f64 / (1024.0 * 1024.0);
        let _ =
            write!(s, "GPU memory: {:.2} MiB in all; core {:.2} MiB", mb(self.total_memory()), mb(self.core_memory()));
        for d in self.effects.iter().filter(|d| d.on) {
            let _ = write!(s, ", {} {:.2} MiB", d.effect.name(), mb(self.memory_of(d.effect)));
            let shared: Vec<&ResourceMemory> =
                self.memory.iter().filter(|m| m.effects.len() > 1 && m.effects.contains(&d.effect)).collect();
            if !shared.is_empty() {
                let bytes: u64 = shared.iter().map(|m| m.bytes).sum();
                let _ = write!(s, " (+{:.2} MiB shared with another effect)", mb(bytes));
            }
        }
        s.push('\n');
        s
    }
}

fn work_text(w: &PassWork) -> String {
    let mut parts = Vec::new();
    let mut add = |v: Option<u64>, what: &str| {
        if let Some(v) = v {
            parts.push(format!("{v} {what}"));
        }
    };
    add(w.writes, "writes");
    add(w.shadow_nodes, "shadow nodes");
    add(w.dispatch_groups, "groups");
    add(w.patches_tested, "patches tested");
    add(w.instances, "instances");
    add(w.triangles, "triangles");
    parts.join(", ")
}

/// The report of the last recorded frame; `timings` should be that frame's
/// (their GPU times are attached where the frame numbers match). Waits for
/// the GPU to read the frame's counters.
pub fn frame_report(ctx: &Context, r: &TerrainRenderer, timings: Option<&FrameTimings>) -> Result<FrameReport> {
    let log = r.graph.last_frame().expect("frame_report needs a recorded frame");
    let timings = timings.filter(|t| t.frame == log.frame);
    let counters = r.read_counters(ctx)?;
    let mode = r.queue_mode().unwrap_or(QueueMode::Single);
    let mut passes = Vec::new();
    for node in r.graph.nodes() {
        let pass = node.pass;
        let ran_on = match (mode, pass.queue()) {
            (QueueMode::AsyncCompute, QueueKind::Compute) => QueueKind::Compute,
            _ => QueueKind::Graphics,
        };
        let mut report = PassReport {
            name: pass.name(),
            late: pass.late(),
            queue: ran_on,
            effects: node.effects.clone(),
            state: PassState::NotBuilt,
            recorded: false,
            reason: node.why_not.clone().unwrap_or_default(),
            gpu_ms: None,
            work: PassWork::default(),
        };
        if pass == FramePass::GBUFFER_TILES && log.outcome(pass).is_some() {
            passes.extend(tile_variants(r, &counters, timings, &report));
            continue;
        }
        match log.outcome(pass) {
            None => {}
            Some(Outcome::Skipped(why)) => {
                report.state = PassState::Idle;
                report.reason = format!("not recorded: {}", why.reason());
            }
            Some(Outcome::Recorded { cpu_work }) => {
                report.recorded = true;
                report.gpu_ms = timings
                    .and_then(|t| t.passes.iter().find(|p| p.name == pass.name() && p.late == pass.late()))
                    .map(|p| p.gpu_ms);
                let (work, idle) = work_of(r, pass, *cpu_work, &counters);
                report.state = if idle.is_some() { PassState::Idle } else { PassState::Ran };
                report.reason = idle.map(|i| format!("recorded with nothing to do: {i}")).unwrap_or_default();
                if let (FramePass::DEBUG_VIEW, Some(v)) = (pass, r.debug_view) {
                    report.reason = format!("showing {}", v.name());
                }
                if pass == FramePass::LIGHTING_RESOLVE && !log.switched_off.is_empty() {
                    let names: Vec<&str> = log.switched_off.iter().map(|e| e.name()).collect();
                    report.reason = format!("the variant without {} (switched off this frame)", names.join(" and "));
                }
                report.work = work;
            }
        }
        passes.push(report);
    }
    let memory = r.memory().into_iter().map(|(name, bytes, effects)| ResourceMemory { name, bytes, effects }).collect();
    Ok(FrameReport {
        frame: log.frame,
        queue_mode: mode,
        effects: r.effects().to_vec(),
        switched_off: log.switched_off.clone(),
        pipelines: r.pipelines(),
        passes,
        memory,
    })
}

/// One entry per variant draw of the tile shading, each timed on its own.
fn tile_variants(
    r: &TerrainRenderer,
    counters: &FrameCounters,
    timings: Option<&FrameTimings>,
    base: &PassReport,
) -> Vec<PassReport> {
    let report = |bits: u32| {
        let name = variant_label(bits);
        let tiles = counters.tiles.get(bits as usize).copied().unwrap_or(0);
        PassReport {
            name,
            state: if tiles > 0 { PassState::Ran } else { PassState::Idle },
            recorded: true,
            reason: if tiles > 0 {
                String::new()
            } else {
                "recorded with nothing to do: no tile needs this variant (0 instances)".into()
            },
            gpu_ms: timings.and_then(|t| t.passes.iter().find(|p| p.name == name)).map(|p| p.gpu_ms),
            work: PassWork { instances: Some(u64::from(tiles)), ..PassWork::default() },
            ..base.clone()
        }
    };
    r.gbuffer_tiles.variants().into_iter().map(report).collect()
}

/// A recorded pass's work, and why it was idle if it had none.
fn work_of(
    r: &TerrainRenderer,
    pass: FramePass,
    cpu_work: Option<u64>,
    c: &FrameCounters,
) -> (PassWork, Option<&'static str>) {
    let nodes = u64::from(c.traverse.nodes);
    let groups = |g: u64| PassWork { dispatch_groups: Some(g), ..PassWork::default() };
    let draw = |n: u32| PassWork {
        dispatch_groups: None,
        instances: Some(u64::from(n)),
        triangles: Some(u64::from(n) * TRIANGLES_PER_PATCH),
        ..PassWork::default()
    };
    let [solid, holey, late_solid, late_holey] = c.instances;
    let no_nodes = (nodes == 0).then_some("the traversal listed no node (0 groups, indirect)");
    match pass {
        FramePass::QUADTREE_UPDATE => {
            let writes = cpu_work.unwrap_or(0);
            let work = PassWork {
                writes: Some(writes),
                dispatch_groups: Some(writes.div_ceil(u64::from(update_sh::WORKGROUP_SIZE[0]))),
                ..PassWork::default()
            };
            (work, (writes == 0).then_some("payload copies only, no quadtree write"))
        }
        FramePass::TRAVERSE => (groups(1), None),
        FramePass::LOD_MAP => (groups(nodes), no_nodes),
        FramePass::SECTOR_DATA => (groups(r.sector_data.groups()), None),
        // Two dispatches of one group per listed node.
        FramePass::SELECT_PATCHES => (groups(2 * nodes), no_nodes),
        FramePass::CULL_PATCHES => {
            (PassWork { patches_tested: Some(u64::from(c.cull.patches_in)), ..groups(nodes) }, no_nodes)
        }
        FramePass::TERRAIN_GEOMETRY => {
            (draw(solid), (solid == 0).then_some("no visible patch without holes (0 instances)"))
        }
        FramePass::TERRAIN_HOLES => (draw(holey), (holey == 0).then_some("no visible patch has holes (0 instances)")),
        FramePass::HIZ_BUILD => {
            let levels = r.occlusion.as_ref().and_then(|o| o.hiz.pyramid()).map_or(0, |p| p.mip_levels);
            (groups(u64::from(levels)), None)
        }
        FramePass::CULL_OCCLUDED => {
            let tested = u64::from(c.cull.occlusion_tested);
            (PassWork { patches_tested: Some(tested), ..groups(nodes) }, no_nodes)
        }
        FramePass::TERRAIN_GEOMETRY_LATE => {
            (draw(late_solid), (late_solid == 0).then_some("the pyramid left no new patch visible (0 instances)"))
        }
        FramePass::TERRAIN_HOLES_LATE => {
            (draw(late_holey), (late_holey == 0).then_some("the pyramid left no new patch with holes (0 instances)"))
        }
        FramePass::CLASSIFY_TILES => {
            let tiles = r.classify.lists.as_ref().map_or(0, |l| u64::from(l.push.capacity));
            (groups(tiles), None)
        }
        // Reported per variant by the caller.
        FramePass::GBUFFER_TILES => (PassWork::default(), None),
        FramePass::LIGHTING_RESOLVE | FramePass::DEBUG_VIEW => (PassWork::default(), None),
        // The effects' passes: their folders know their work.
        _ => {
            let size = r.gbuffer.as_ref().map_or([0, 0], |g| g.size());
            let of_effect = r.built_effects().iter().find_map(|e| e.work(pass, cpu_work, c, size));
            of_effect.unwrap_or_default()
        }
    }
}

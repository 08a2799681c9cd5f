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
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct PassWork {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dispatch_groups: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub instances: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub triangles: Option<u64>,
    /// Quadtree texel/description writes (quadtree_update).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub writes: Option<u64>,
    /// Patches tested (cull_patches; cull_occluded: against the pyramid,
    /// those phase 1 did not draw).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub patches_tested: Option<u64>,
    /// Nodes whose sun shadow texture was made (sun_shadows).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shadow_nodes: Option<u64>,
    /// Virtual-texture pages rendered (vt_pages).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pages: Option<u64>,
}

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
            effects: pass.effects().to_vec(),
            state: PassState::NotBuilt,
            recorded: false,
            reason: node.why_not.clone().unwrap_or_default(),
            gpu_ms: None,
            work: PassWork::default(),
        };
        if pass == FramePass::GbufferTiles && log.outcome(pass).is_some() {
            // One entry per variant draw, each timed on its own.
            for bits in r.gbuffer_tiles.variants() {
                let name = variant_label(bits);
                let tiles = counters.tiles.get(bits as usize).copied().unwrap_or(0);
                passes.push(PassReport {
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
                    ..report.clone()
                });
            }
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
                if let (FramePass::DebugView, Some(v)) = (pass, r.debug_view) {
                    report.reason = format!("showing {}", v.name());
                }
                if pass == FramePass::LightingResolve && !log.switched_off.is_empty() {
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
        FramePass::QuadtreeUpdate => {
            let writes = cpu_work.unwrap_or(0);
            let work = PassWork {
                writes: Some(writes),
                dispatch_groups: Some(writes.div_ceil(u64::from(update_sh::WORKGROUP_SIZE[0]))),
                ..PassWork::default()
            };
            (work, (writes == 0).then_some("payload copies only, no quadtree write"))
        }
        FramePass::Traverse => (groups(1), None),
        FramePass::LodMap => (groups(nodes), no_nodes),
        FramePass::SectorData => (groups(r.sector_data.groups()), None),
        // Two dispatches of one group per listed node.
        FramePass::SelectPatches => (groups(2 * nodes), no_nodes),
        FramePass::CullPatches => {
            (PassWork { patches_tested: Some(u64::from(c.cull.patches_in)), ..groups(nodes) }, no_nodes)
        }
        FramePass::TerrainGeometry => {
            (draw(solid), (solid == 0).then_some("no visible patch without holes (0 instances)"))
        }
        FramePass::TerrainHoles => (draw(holey), (holey == 0).then_some("no visible patch has holes (0 instances)")),
        FramePass::HizBuild => {
            let levels = r.occlusion.as_ref().and_then(|o| o.hiz.pyramid()).map_or(0, |p| p.mip_levels);
            (groups(u64::from(levels)), None)
        }
        FramePass::CullOccluded => {
            let tested = u64::from(c.cull.occlusion_tested);
            (PassWork { patches_tested: Some(tested), ..groups(nodes) }, no_nodes)
        }
        FramePass::TerrainGeometryLate => {
            (draw(late_solid), (late_solid == 0).then_some("the pyramid left no new patch visible (0 instances)"))
        }
        FramePass::TerrainHolesLate => {
            (draw(late_holey), (late_holey == 0).then_some("the pyramid left no new patch with holes (0 instances)"))
        }
        FramePass::ClassifyTiles => {
            let tiles = r.classify.lists.as_ref().map_or(0, |l| u64::from(l.push.capacity));
            (groups(tiles), None)
        }
        // Reported per variant by the caller.
        FramePass::GbufferTiles => (PassWork::default(), None),
        FramePass::SunShadows => {
            let jobs = cpu_work.unwrap_or(0);
            let side = r.sun_shadows.as_ref().map_or(0, |s| u64::from(s.params.resolution));
            let [wx, wy, _] = crate::shaders::sun_shadows::WORKGROUP_SIZE;
            let per_node = side.div_ceil(u64::from(wx)) * side.div_ceil(u64::from(wy));
            (PassWork { shadow_nodes: Some(jobs), ..groups(jobs * per_node) }, None)
        }
        FramePass::VtUpdate => (PassWork { writes: cpu_work, ..groups(1) }, None),
        FramePass::VtPages => {
            let pages = cpu_work.unwrap_or(0);
            let [wx, wy, _] = crate::shaders::vt_pages::WORKGROUP_SIZE;
            let side = u64::from(crate::effects::virtual_texture::layout::PADDED_TILE);
            let per_page = side.div_ceil(u64::from(wx)) * side.div_ceil(u64::from(wy));
            (PassWork { pages: Some(pages), ..groups(pages * per_page) }, None)
        }
        FramePass::VtFeedback => {
            let [wx, wy, _] = crate::shaders::vt_feedback::WORKGROUP_SIZE;
            let stride = crate::shaders::consts::VT_FEEDBACK_STRIDE;
            let size = r.gbuffer.as_ref().map_or([0, 0], |g| g.size());
            let cells = size.map(|s| s.div_ceil(stride));
            (groups(u64::from(cells[0].div_ceil(wx)) * u64::from(cells[1].div_ceil(wy))), None)
        }
        FramePass::GrassPigment => {
            let [wx, wy, _] = crate::shaders::grass_pigment::WORKGROUP_SIZE;
            let side = crate::shaders::consts::GRASS_PIGMENT_TEXELS;
            (groups(u64::from(side.div_ceil(wx)) * u64::from(side.div_ceil(wy))), None)
        }
        FramePass::GrassPlace => {
            let [wx, wy, _] = crate::shaders::grass_place::WORKGROUP_SIZE;
            let side = r.near.grass.as_ref().map_or(0, |g| g.params.side());
            let in_range = c.grass.map_or(0, |g| u64::from(g.in_range));
            let work = PassWork { ..groups(u64::from(side.div_ceil(wx) * side.div_ceil(wy))) };
            (work, (in_range == 0).then_some("no cell of the square lies within the radius"))
        }
        FramePass::GrassDraw => {
            let drawn = c.grass.map_or(0, |g| g.drawn);
            let per_tuft =
                u64::from(crate::shaders::consts::GRASS_BLADES * crate::shaders::consts::GRASS_BLADE_VERTICES / 3);
            let work = PassWork {
                instances: Some(u64::from(drawn)),
                triangles: Some(u64::from(drawn) * per_tuft),
                ..PassWork::default()
            };
            (work, (drawn == 0).then_some("no tuft placed and visible (0 instances)"))
        }
        FramePass::CliffMeshBuild => {
            let side = r.near.cliff_meshes.as_ref().map_or(0, |c| c.params.side());
            (groups(u64::from((side * side).div_ceil(crate::shaders::cliff_mesh_build::WORKGROUP_SIZE[0]))), None)
        }
        // Its instances are counted on the GPU (vista render's cliff meshes: line).
        FramePass::CliffMeshes => (PassWork::default(), None),
        FramePass::DecalMeshes => {
            let m = r.near.decal_meshes.as_ref();
            let work = PassWork {
                instances: m.map(|m| u64::from(m.meshes)),
                triangles: m.map(|m| m.triangles),
                ..PassWork::default()
            };
            (work, None)
        }
        FramePass::AssetDraw => {
            let a = r.near.assets.as_ref().map(|(_, a)| a);
            let instances = a.map_or(0, |a| a.draws.iter().map(|(_, _, n)| u64::from(*n)).sum());
            let work = PassWork {
                instances: Some(instances),
                triangles: Some(a.map_or(0, |a| a.triangles())),
                ..PassWork::default()
            };
            (work, None)
        }
        FramePass::LightingResolve | FramePass::DebugView => (PassWork::default(), None),
    }
}

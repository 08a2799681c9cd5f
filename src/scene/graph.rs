//! The frame's pass graph, built from the effect decisions: every pass the
//! renderer knows, in frame order, with the effects it exists for and the
//! queue it belongs to. It is a chain: each pass reads what the passes
//! before it wrote, and the passes end in full barriers, so order is the
//! only edge; where compute is split off, the compute passes come first and
//! the graphics command buffer waits for them (a timeline semaphore). A pass
//! whose effect is off is not built; each frame logs which built passes
//! were recorded and which were skipped because the CPU knew they had
//! nothing to do. Occlusion culling draws twice: the drawing passes appear
//! again as phase 2 after `hiz_build` and `cull_occluded`. Effect `grass`
//! then renders its pigment map and places its tufts (culled by that
//! pyramid). Shading follows: `classify_tiles`, `gbuffer_tiles` (one
//! timed draw per variant built), `asset_draw`, `grass_draw`, `sun_shadows` (effect
//! `shadows`: skipped while every resident node's shadow is current),
//! `lighting_resolve` and, when one is asked for, `debug_view`.

use crate::frame::QueueKind;
use crate::scene::effect::{Effect, EffectDecision};
use crate::shaders as sh;
use serde::Serialize;

/// A pass of the frame: its name (pass, shader and timer label, from the
/// shader bank) and whether it is occlusion's phase 2 of a drawing pass.
/// The core passes are the constants here; an effect's are constants in
/// its folder, declared to the graph by its kind ([`EffectPass`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
pub struct FramePass {
    name: &'static str,
    late: bool,
}

impl FramePass {
    pub const QUADTREE_UPDATE: FramePass = FramePass::new(sh::quadtree_update::PASS);
    pub const TRAVERSE: FramePass = FramePass::new(sh::traverse::PASS);
    pub const LOD_MAP: FramePass = FramePass::new(sh::lod_map::PASS);
    pub const SECTOR_DATA: FramePass = FramePass::new(sh::sector_data::PASS);
    pub const SELECT_PATCHES: FramePass = FramePass::new(sh::select_patches::PASS);
    pub const CULL_PATCHES: FramePass = FramePass::new(sh::cull_patches::PASS);
    /// The per-triangle rule's cut (instead of select and cull).
    pub const EMIT_TRIANGLES: FramePass = FramePass::new(sh::emit_triangles::PASS);
    /// The per-triangle rule below a LOD-0 node's samples (the cells the cut reached).
    pub const EMIT_FINE: FramePass = FramePass::new(sh::emit_fine::PASS);
    pub const TERRAIN_GEOMETRY: FramePass = FramePass::new(sh::terrain_geometry_vert::PASS);
    pub const TERRAIN_HOLES: FramePass = FramePass::new(sh::terrain_holes_vert::PASS);
    /// The per-triangle rule's draw (instead of terrain_geometry and terrain_holes).
    pub const TERRAIN_TRIANGLES: FramePass = FramePass::new(sh::terrain_triangles_vert::PASS);
    pub const HIZ_BUILD: FramePass = FramePass::new(sh::hiz_build::PASS);
    pub const CULL_OCCLUDED: FramePass = FramePass::new(sh::cull_occluded::PASS);
    /// Phase 2 of occlusion culling: the patches the pyramid left visible.
    pub const TERRAIN_GEOMETRY_LATE: FramePass = FramePass::phase_two(sh::terrain_geometry_vert::PASS);
    pub const TERRAIN_HOLES_LATE: FramePass = FramePass::phase_two(sh::terrain_holes_vert::PASS);
    /// Phase 2 of the per-triangle rule's cut: the subtrees the pyramid
    /// left visible that phase 1 did not draw, and their draw.
    pub const EMIT_TRIANGLES_LATE: FramePass = FramePass::phase_two(sh::emit_triangles::PASS);
    pub const EMIT_FINE_LATE: FramePass = FramePass::phase_two(sh::emit_fine::PASS);
    pub const TERRAIN_TRIANGLES_LATE: FramePass = FramePass::phase_two(sh::terrain_triangles_vert::PASS);
    pub const CLASSIFY_TILES: FramePass = FramePass::new(sh::classify_tiles::PASS);
    /// One draw per variant built, each timed on its own.
    pub const GBUFFER_TILES: FramePass = FramePass::new(sh::gbuffer_tiles_vert::PASS);
    pub const LIGHTING_RESOLVE: FramePass = FramePass::new(sh::lighting_resolve_vert::PASS);
    /// A debug view over the display image, when one is asked for.
    pub const DEBUG_VIEW: FramePass = FramePass::new(sh::debug_view_vert::PASS);

    /// The pass of the shader bank's `name` (its `PASS`).
    pub const fn new(name: &'static str) -> FramePass {
        FramePass { name, late: false }
    }

    const fn phase_two(name: &'static str) -> FramePass {
        FramePass { name, late: true }
    }

    /// Pass, shader and timer label (from the shader bank).
    pub fn name(self) -> &'static str {
        self.name
    }

    /// Phase 2 of a drawing pass.
    pub fn late(self) -> bool {
        self.late
    }

    /// Timer and debug label: the name, marked in phase 2.
    pub fn label(self) -> String {
        crate::frame::pass_label(self.name, self.late)
    }

    /// The queue the pass belongs to when compute is split off: the LOD
    /// phase; phase 2 reads phase 1's depth, so the pyramid and its culling
    /// stay with the graphics work, as do the effects' passes.
    pub fn queue(self) -> QueueKind {
        let compute = [
            FramePass::QUADTREE_UPDATE,
            FramePass::TRAVERSE,
            FramePass::LOD_MAP,
            FramePass::SECTOR_DATA,
            FramePass::SELECT_PATCHES,
            FramePass::CULL_PATCHES,
            FramePass::EMIT_TRIANGLES,
            FramePass::EMIT_FINE,
        ];
        if compute.contains(&self) {
            QueueKind::Compute
        } else {
            QueueKind::Graphics
        }
    }
}

/// The points of the frame where effects record, in frame order; at each,
/// effects record in registry order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FramePoint {
    /// After the LOD phase, before the terrain's draws: what they read
    /// (the terrain's sink).
    BeforeTerrainDraws,
    /// After the terrain's draws (both occlusion phases): meshes drawn into
    /// the geometry pass.
    AfterTerrainDraws,
    /// Before the tiles are classified: compute that reads the frame's
    /// depth pyramid.
    BeforeClassify,
    /// After classification, before the tile shading: what it samples.
    BeforeTiles,
    /// After the tile shading: draws into the G-buffer on top of it.
    AfterTiles,
    /// Before the lighting resolve: what it samples.
    BeforeResolve,
}

/// A pass an effect records at a point, and the effects it exists for
/// (all needed).
#[derive(Debug, Clone, Copy)]
pub struct EffectPass {
    pub point: FramePoint,
    pub pass: FramePass,
    pub effects: &'static [Effect],
}

/// The frame's core passes and the points between them, in order.
enum Step {
    Pass(FramePass, &'static [Effect]),
    Point(FramePoint),
}

const FRAME: [Step; 27] = [
    Step::Pass(FramePass::QUADTREE_UPDATE, &[]),
    Step::Pass(FramePass::TRAVERSE, &[]),
    Step::Pass(FramePass::LOD_MAP, &[]),
    Step::Pass(FramePass::SECTOR_DATA, &[]),
    Step::Pass(FramePass::SELECT_PATCHES, &[]),
    Step::Pass(FramePass::CULL_PATCHES, &[]),
    Step::Pass(FramePass::EMIT_TRIANGLES, &[]),
    Step::Pass(FramePass::EMIT_FINE, &[]),
    Step::Point(FramePoint::BeforeTerrainDraws),
    Step::Pass(FramePass::TERRAIN_GEOMETRY, &[]),
    Step::Pass(FramePass::TERRAIN_HOLES, &[Effect::Holes]),
    Step::Pass(FramePass::TERRAIN_TRIANGLES, &[]),
    Step::Pass(FramePass::HIZ_BUILD, &[Effect::Occlusion]),
    Step::Pass(FramePass::CULL_OCCLUDED, &[Effect::Occlusion]),
    Step::Pass(FramePass::TERRAIN_GEOMETRY_LATE, &[Effect::Occlusion]),
    Step::Pass(FramePass::TERRAIN_HOLES_LATE, &[Effect::Holes, Effect::Occlusion]),
    Step::Pass(FramePass::EMIT_TRIANGLES_LATE, &[Effect::Occlusion]),
    Step::Pass(FramePass::EMIT_FINE_LATE, &[Effect::Occlusion]),
    Step::Pass(FramePass::TERRAIN_TRIANGLES_LATE, &[Effect::Occlusion]),
    Step::Point(FramePoint::AfterTerrainDraws),
    Step::Point(FramePoint::BeforeClassify),
    Step::Pass(FramePass::CLASSIFY_TILES, &[]),
    Step::Point(FramePoint::BeforeTiles),
    Step::Pass(FramePass::GBUFFER_TILES, &[]),
    Step::Point(FramePoint::AfterTiles),
    Step::Point(FramePoint::BeforeResolve),
    Step::Pass(FramePass::LIGHTING_RESOLVE, &[]),
];

/// Why a built pass was not recorded this frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Skip {
    NothingToUpload,
    /// Occlusion is built but switched off this frame (`CullStages`).
    OcclusionOff,
    /// The per-triangle rule's cut is made for another camera this frame
    /// (`TerrainRenderer::lod_camera`): one phase emits all of it.
    LodCamera,
    /// No node arrived and every resident node's shadow was made for this sun.
    ShadowsCurrent,
    /// Effect `shadows` is built but switched off this frame (`FrameSwitches`).
    ShadowsOff,
    /// Effect `holes` is built but switched off this frame (`FrameSwitches`).
    HolesOff,
    /// No debug view asked for (`TerrainRenderer::debug_view`).
    NoDebugView,
    /// No sub-texture moved and no page arrived or left.
    NoVtWrites,
    /// Every page the frames read back asked for is resident, or waits for
    /// a tile no view still uses.
    NoVtPages,
    /// The camera stayed in the pigment map's step and the terrain did not
    /// change.
    PigmentCurrent,
    /// A decal edit left no displacement decal.
    NoDisplacement,
    /// The camera stayed in the cliff meshes' step and the terrain did not
    /// change.
    CliffMeshesCurrent,
}

impl Skip {
    pub fn reason(self) -> &'static str {
        match self {
            Skip::NothingToUpload => "no node arrived or left this frame or the last (known on the CPU)",
            Skip::OcclusionOff => "occlusion switched off this frame (culling stages)",
            Skip::LodCamera => "the cut is made for another camera (lod_camera): one phase draws all of it",
            Skip::ShadowsCurrent => "idle: every resident node's shadow is made for this sun (known on the CPU)",
            Skip::ShadowsOff => "shadows switched off this frame (FrameSwitches; built, redone when back on)",
            Skip::HolesOff => "holes switched off this frame (FrameSwitches; every patch drawn solid)",
            Skip::NoDebugView => "no debug view asked for (TerrainRenderer::debug_view)",
            Skip::NoVtWrites => "idle: no sub-texture moved and no page arrived or left (known on the CPU)",
            Skip::NoVtPages => "idle: no page the read-back requests named is missing (known on the CPU)",
            Skip::CliffMeshesCurrent => {
                "idle: the camera stayed in the cliff meshes' step and no node arrived or left (known on the CPU)"
            }
            Skip::NoDisplacement => "idle: a decal edit left no displacement decal (known on the CPU)",
            Skip::PigmentCurrent => {
                "idle: the camera stayed in the pigment map's step and no node arrived or left (known on the CPU)"
            }
        }
    }
}

/// What a recorded pass did, as far as the CPU and the frame's counters
/// know (the pass report's columns).
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

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PassNode {
    pub pass: FramePass,
    /// The effects it exists for, all needed (empty: every scene).
    pub effects: Vec<Effect>,
    pub built: bool,
    /// Why not built, when not.
    pub why_not: Option<String>,
}

/// One frame's fate of each built pass.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// Recorded; `cpu_work` is what the CPU knew of its size (e.g. writes).
    Recorded {
        cpu_work: Option<u64>,
    },
    Skipped(Skip),
}

#[derive(Debug, Clone)]
pub struct FrameLog {
    /// The frame executor's frame number.
    pub frame: u64,
    pub entries: Vec<(FramePass, Outcome)>,
    /// Built effects switched off this frame (`FrameSwitches`).
    pub switched_off: Vec<Effect>,
}

impl FrameLog {
    pub fn ran(&mut self, pass: FramePass, cpu_work: Option<u64>) {
        self.entries.push((pass, Outcome::Recorded { cpu_work }));
    }

    pub fn skipped(&mut self, pass: FramePass, why: Skip) {
        self.entries.push((pass, Outcome::Skipped(why)));
    }

    pub fn outcome(&self, pass: FramePass) -> Option<&Outcome> {
        self.entries.iter().find(|(p, _)| *p == pass).map(|(_, o)| o)
    }
}

/// A pass built unless an effect it needs is off (then why not).
fn node(pass: FramePass, effects: &[Effect], decisions: &[EffectDecision]) -> PassNode {
    let off = effects.iter().filter_map(|e| decisions.iter().find(|d| d.effect == *e)).find(|d| !d.on);
    PassNode {
        pass,
        effects: effects.to_vec(),
        built: off.is_none(),
        why_not: off.map(|d| format!("effect {} is off: {}", d.effect.name(), d.reason)),
    }
}

pub struct PassGraph {
    nodes: Vec<PassNode>,
    last: Option<FrameLog>,
}

impl PassGraph {
    /// The graph of these decisions: the core passes, each effect's
    /// (`effect_passes`, in registry order) at its point, and the debug
    /// view last.
    pub fn new(decisions: &[EffectDecision], effect_passes: &[EffectPass]) -> PassGraph {
        let mut order: Vec<(FramePass, &[Effect])> = Vec::new();
        for step in &FRAME {
            match step {
                Step::Pass(pass, effects) => order.push((*pass, effects)),
                Step::Point(point) => {
                    order.extend(effect_passes.iter().filter(|p| p.point == *point).map(|p| (p.pass, p.effects)));
                }
            }
        }
        order.push((FramePass::DEBUG_VIEW, &[]));
        let nodes = order.into_iter().map(|(pass, effects)| node(pass, effects, decisions)).collect();
        PassGraph { nodes, last: None }
    }

    /// Marks a pass of an effect that is on as not built: it has nothing
    /// to do for this scene (`why`).
    pub fn not_built(&mut self, pass: FramePass, why: String) {
        if let Some(n) = self.nodes.iter_mut().find(|n| n.pass == pass) {
            n.built = false;
            n.why_not = Some(why);
        }
    }

    pub fn nodes(&self) -> &[PassNode] {
        &self.nodes
    }

    /// Most passes one frame records (sizes the timestamp pools).
    pub fn max_recorded(&self) -> u32 {
        self.nodes.iter().filter(|n| n.built).count() as u32
    }

    pub fn begin_frame(&self, frame: u64) -> FrameLog {
        FrameLog { frame, entries: Vec::new(), switched_off: Vec::new() }
    }

    /// Keeps the log; every built pass must have been accounted for, in
    /// graph order, and no other (a programmer error otherwise).
    pub fn end_frame(&mut self, log: FrameLog) {
        let built: Vec<FramePass> = self.nodes.iter().filter(|n| n.built).map(|n| n.pass).collect();
        let logged: Vec<FramePass> = log.entries.iter().map(|(p, _)| *p).collect();
        assert_eq!(logged, built, "frame {} did not follow the pass graph", log.frame);
        self.last = Some(log);
    }

    /// The log of the last recorded frame.
    pub fn last_frame(&self) -> Option<&FrameLog> {
        self.last.as_ref()
    }
}

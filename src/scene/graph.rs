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

/// Every pass of a frame, in order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum FramePass {
    QuadtreeUpdate,
    Traverse,
    LodMap,
    SectorData,
    SelectPatches,
    CullPatches,
    TerrainGeometry,
    TerrainHoles,
    HizBuild,
    CullOccluded,
    /// Phase 2 of occlusion culling: the patches the pyramid left visible.
    TerrainGeometryLate,
    TerrainHolesLate,
    /// Effect `cliff_meshes`: the meshes of the steep cells near the camera
    /// (when the camera left their step or the terrain changed).
    CliffMeshBuild,
    /// Effect `cliff_meshes`: their draw into the geometry pass.
    CliffMeshes,
    /// Effect `decals`: the displacement decals' meshes (built only where
    /// a decal displaces).
    DecalMeshes,
    /// Effect `grass`: the pigment map (when the camera left its step or
    /// the terrain changed).
    GrassPigment,
    /// Effect `grass`: placement and culling of the tufts.
    GrassPlace,
    ClassifyTiles,
    /// Effect `virtual_texture`: the indirection and sub-texture writes.
    VtUpdate,
    /// Effect `virtual_texture`: the pages missing, up to the budget.
    VtPages,
    /// Effect `virtual_texture`: the pages this frame samples.
    VtFeedback,
    /// One draw per variant built, each timed on its own.
    GbufferTiles,
    /// Effect `assets`: the example assets, blended into the terrain.
    AssetDraw,
    /// Effect `grass`: the one indirect draw of every tuft kept.
    GrassDraw,
    /// Effect `shadows`: the shadow textures of arrived and stale nodes.
    SunShadows,
    LightingResolve,
    /// A debug view over the display image, when one is asked for.
    DebugView,
}

impl FramePass {
    pub const ALL: [FramePass; 27] = [
        FramePass::QuadtreeUpdate,
        FramePass::Traverse,
        FramePass::LodMap,
        FramePass::SectorData,
        FramePass::SelectPatches,
        FramePass::CullPatches,
        FramePass::TerrainGeometry,
        FramePass::TerrainHoles,
        FramePass::HizBuild,
        FramePass::CullOccluded,
        FramePass::TerrainGeometryLate,
        FramePass::TerrainHolesLate,
        FramePass::CliffMeshBuild,
        FramePass::CliffMeshes,
        FramePass::DecalMeshes,
        FramePass::GrassPigment,
        FramePass::GrassPlace,
        FramePass::ClassifyTiles,
        FramePass::VtUpdate,
        FramePass::VtPages,
        FramePass::VtFeedback,
        FramePass::GbufferTiles,
        FramePass::AssetDraw,
        FramePass::GrassDraw,
        FramePass::SunShadows,
        FramePass::LightingResolve,
        FramePass::DebugView,
    ];

    /// Pass, shader and timer label (from the shader bank).
    pub fn name(self) -> &'static str {
        match self {
            FramePass::QuadtreeUpdate => sh::quadtree_update::PASS,
            FramePass::Traverse => sh::traverse::PASS,
            FramePass::LodMap => sh::lod_map::PASS,
            FramePass::SectorData => sh::sector_data::PASS,
            FramePass::SelectPatches => sh::select_patches::PASS,
            FramePass::CullPatches => sh::cull_patches::PASS,
            FramePass::TerrainGeometry | FramePass::TerrainGeometryLate => sh::terrain_geometry_vert::PASS,
            FramePass::TerrainHoles | FramePass::TerrainHolesLate => sh::terrain_holes_vert::PASS,
            FramePass::HizBuild => sh::hiz_build::PASS,
            FramePass::CullOccluded => sh::cull_occluded::PASS,
            FramePass::ClassifyTiles => sh::classify_tiles::PASS,
            FramePass::VtUpdate => sh::vt_update::PASS,
            FramePass::VtPages => sh::vt_pages::PASS,
            FramePass::VtFeedback => sh::vt_feedback::PASS,
            FramePass::GbufferTiles => sh::gbuffer_tiles_vert::PASS,
            FramePass::GrassPigment => sh::grass_pigment::PASS,
            FramePass::GrassPlace => sh::grass_place::PASS,
            FramePass::GrassDraw => sh::grass_draw_vert::PASS,
            FramePass::AssetDraw => sh::asset_draw_vert::PASS,
            FramePass::DecalMeshes => sh::decal_meshes_vert::PASS,
            FramePass::CliffMeshBuild => sh::cliff_mesh_build::PASS,
            FramePass::CliffMeshes => sh::cliff_meshes_vert::PASS,
            FramePass::SunShadows => sh::sun_shadows::PASS,
            FramePass::LightingResolve => sh::lighting_resolve_vert::PASS,
            FramePass::DebugView => sh::debug_view_vert::PASS,
        }
    }

    /// Phase 2 of a drawing pass.
    pub fn late(self) -> bool {
        matches!(self, FramePass::TerrainGeometryLate | FramePass::TerrainHolesLate)
    }

    /// Timer and debug label: the name, marked in phase 2.
    pub fn label(self) -> String {
        crate::frame::pass_label(self.name(), self.late())
    }

    /// The queue the pass belongs to when compute is split off: phase 2
    /// reads phase 1's depth, so the pyramid and its culling stay with the
    /// graphics work.
    pub fn queue(self) -> QueueKind {
        match self {
            FramePass::QuadtreeUpdate
            | FramePass::Traverse
            | FramePass::LodMap
            | FramePass::SectorData
            | FramePass::SelectPatches
            | FramePass::CullPatches => QueueKind::Compute,
            _ => QueueKind::Graphics,
        }
    }

    /// The effects the pass exists for, all needed (empty: every scene).
    pub fn effects(self) -> &'static [Effect] {
        match self {
            FramePass::TerrainHoles => &[Effect::Holes],
            FramePass::HizBuild | FramePass::CullOccluded | FramePass::TerrainGeometryLate => &[Effect::Occlusion],
            FramePass::TerrainHolesLate => &[Effect::Holes, Effect::Occlusion],
            FramePass::SunShadows => &[Effect::Shadows],
            FramePass::GrassPigment | FramePass::GrassPlace | FramePass::GrassDraw => &[Effect::Grass],
            FramePass::AssetDraw => &[Effect::Assets],
            FramePass::DecalMeshes => &[Effect::Decals],
            FramePass::CliffMeshBuild | FramePass::CliffMeshes => &[Effect::CliffMeshes],
            FramePass::VtUpdate | FramePass::VtPages | FramePass::VtFeedback => &[Effect::VirtualTexture],
            _ => &[],
        }
    }
}

/// Why a built pass was not recorded this frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Skip {
    NothingToUpload,
    /// Occlusion is built but switched off this frame (`CullStages`).
    OcclusionOff,
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

pub struct PassGraph {
    nodes: Vec<PassNode>,
    last: Option<FrameLog>,
}

impl PassGraph {
    pub fn new(decisions: &[EffectDecision]) -> PassGraph {
        let nodes = FramePass::ALL
            .into_iter()
            .map(|pass| {
                let decision =
                    pass.effects().iter().filter_map(|e| decisions.iter().find(|d| d.effect == *e)).find(|d| !d.on);
                match decision {
                    Some(d) if !d.on => PassNode {
                        pass,
                        built: false,
                        why_not: Some(format!("effect {} is off: {}", d.effect.name(), d.reason)),
                    },
                    _ => PassNode { pass, built: true, why_not: None },
                }
            })
            .collect();
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

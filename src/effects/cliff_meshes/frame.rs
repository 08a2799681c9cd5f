//! Effect `cliff_meshes` in the frame: built again, before the terrain's
//! draws (which read its sink), when the camera leaves its step or the
//! terrain changes; drawn into the geometry pass after the terrain's draws.

use super::CliffMeshes;
use crate::effects::frame_effect::{
    BuildInputs, EffectStats, FrameEffect, FramePoint, PlanInputs, RecordInputs, SharedPlan, Work,
};
use crate::error::Result;
use crate::frame::{Frame, QueueKind};
use crate::gpu::Context;
use crate::passes::counters::FrameCounters;
use crate::scene::effect::Effect;
use crate::scene::graph::{FrameLog, FramePass, PassWork, Skip};
use std::any::Any;

/// Its passes: built again when the camera left their step or the
/// terrain changed; their draw into the geometry pass.
pub const CLIFF_MESH_BUILD: FramePass = FramePass::new(crate::shaders::cliff_mesh_build::PASS);
pub const CLIFF_MESHES: FramePass = FramePass::new(crate::shaders::cliff_meshes_vert::PASS);

/// Builds effect `cliff_meshes` when it is on.
pub fn build(b: &mut BuildInputs) -> Result<Option<Box<dyn FrameEffect>>> {
    if !b.on(Effect::CliffMeshes) {
        return Ok(None);
    }
    Ok(Some(Box::new(CliffMeshes::new(b.ctx, b.effects.cliff_meshes, b.depth)?)))
}

impl FrameEffect for CliffMeshes {
    fn effect(&self) -> Effect {
        Effect::CliffMeshes
    }

    fn plan(&mut self, p: &PlanInputs, _: &SharedPlan) -> Result<()> {
        self.planned = CliffMeshes::plan(self, p.camera_world, p.vista_terrain, p.terrain_changed);
        Ok(())
    }

    fn record(&self, point: FramePoint, frame: &mut Frame<'_, '_>, log: &mut FrameLog, r: &RecordInputs) {
        match point {
            FramePoint::BeforeTerrainDraws => match &self.planned {
                Some(push) => {
                    let sector = r.sector_data.buffer();
                    frame.pass(CLIFF_MESH_BUILD.name(), false, QueueKind::Graphics, |rec| {
                        self.record_build(rec, push, sector, r.tree)
                    });
                    log.ran(CLIFF_MESH_BUILD, None);
                }
                None => log.skipped(CLIFF_MESH_BUILD, Skip::CliffMeshesCurrent),
            },
            FramePoint::AfterTerrainDraws => {
                frame.pass(CLIFF_MESHES.name(), false, QueueKind::Graphics, |rec| {
                    self.record_draw(rec, r.targets, r.gbuffer, r.view_buffer)
                });
                log.ran(CLIFF_MESHES, None);
            }
            _ => {}
        }
    }

    fn terrain_sink(&self) -> Option<&crate::gpu::Buffer> {
        self.sink().map(|s| s.buffer())
    }

    fn pipelines(&self) -> Vec<String> {
        self.pipeline_labels().to_vec()
    }

    fn memory(&self) -> Vec<(String, u64, Vec<Effect>)> {
        CliffMeshes::memory(self).into_iter().map(|(n, b)| (n, b, vec![Effect::CliffMeshes])).collect()
    }

    fn work(&self, pass: FramePass, _: Option<u64>, _: &FrameCounters, _: [u32; 2]) -> Option<Work> {
        match pass {
            CLIFF_MESH_BUILD => {
                let side = self.params.side();
                let groups = (side * side).div_ceil(crate::shaders::cliff_mesh_build::WORKGROUP_SIZE[0]);
                Some((PassWork { dispatch_groups: Some(u64::from(groups)), ..PassWork::default() }, None))
            }
            // Its instances are counted on the GPU (vista render's cliff meshes: line).
            CLIFF_MESHES => Some((PassWork::default(), None)),
            _ => None,
        }
    }

    fn stats(&self, ctx: &Context, _: &FrameCounters) -> Result<Option<EffectStats>> {
        let (c, _) = self.read(ctx)?;
        let line = format!(
            "cliff meshes: {} cells within the radius, {} steep ones meshed ({} triangles), {} past the capacity",
            c.tested, c.cells, c.triangles, c.overflow
        );
        let value = serde_json::to_value(c).expect("plain counters");
        Ok(Some(EffectStats { key: "cliff_meshes", value, lines: vec![line] }))
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

//! Effect `assets` in the frame: one draw per asset kind after the tile
//! shading, blended into the terrain.

use super::asset_draw::AssetDraw;
use super::AssetResources;
use crate::effects::frame_effect::{BuildInputs, FrameEffect, FramePoint, RecordInputs, Work};
use crate::error::Result;
use crate::frame::{Frame, QueueKind};
use crate::passes::counters::FrameCounters;
use crate::scene::effect::{Effect, MaterialsMode};
use crate::scene::graph::{FrameLog, FramePass, PassWork};
use std::any::Any;

/// Its pass: the assets, blended into the terrain.
pub const ASSET_DRAW: FramePass = FramePass::new(crate::shaders::asset_draw_vert::PASS);

/// The built effect: the pass and the meshes and instances it draws.
pub struct Assets {
    pub draw: AssetDraw,
    pub resources: AssetResources,
}

/// Builds effect `assets` when it is on; the assets take the splat
/// blend's colour when the material resources exist in splat mode.
pub fn build(b: &mut BuildInputs) -> Result<Option<Box<dyn FrameEffect>>> {
    if !b.on(Effect::Assets) {
        return Ok(None);
    }
    let materials = b.on(Effect::Splat) || b.on(Effect::Cliffs);
    let splat_colours = materials && b.effects.materials == MaterialsMode::Splat;
    Ok(Some(Box::new(Assets {
        draw: AssetDraw::new(b.ctx, b.depth.format, splat_colours, b.layout)?,
        resources: AssetResources::new(b.ctx, b.assets, b.effects.assets)?,
    })))
}

impl FrameEffect for Assets {
    fn effect(&self) -> Effect {
        Effect::Assets
    }

    fn record(&self, point: FramePoint, frame: &mut Frame<'_, '_>, log: &mut FrameLog, r: &RecordInputs) {
        if point != FramePoint::AfterTiles {
            return;
        }
        let m = r.materials.filter(|_| self.draw.materials());
        frame.pass(ASSET_DRAW.name(), false, QueueKind::Graphics, |rec| {
            let (view, sector) = (r.view_buffer, r.sector_data.buffer());
            self.draw.record(rec, r.targets, r.gbuffer, view, &self.resources, r.terrain, sector, r.tree, m)
        });
        log.ran(ASSET_DRAW, None);
    }

    fn pipelines(&self) -> Vec<String> {
        vec![self.draw.pipeline_label().to_string()]
    }

    fn memory(&self) -> Vec<(String, u64, Vec<Effect>)> {
        self.resources.memory().into_iter().map(|(n, b)| (n, b, vec![Effect::Assets])).collect()
    }

    fn work(&self, pass: FramePass, _: Option<u64>, _: &FrameCounters, _: [u32; 2]) -> Option<Work> {
        if pass != ASSET_DRAW {
            return None;
        }
        let a = &self.resources;
        let instances = a.draws.iter().map(|(_, _, n)| u64::from(*n)).sum();
        let work = PassWork { instances: Some(instances), triangles: Some(a.triangles()), ..PassWork::default() };
        Some((work, None))
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

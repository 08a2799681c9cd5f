//! Effect `grass` in the frame: its plan, its three passes (the pigment
//! map and the placement before the tiles are classified, the draw after
//! the tile shading), its counters and numbers.

use super::gpu::{Grass, GrassFrameInputs, GrassHeaderGpu};
use super::GrassCounters;
use crate::effects::frame_effect::{
    BuildInputs, EffectStats, FrameEffect, FramePoint, PlanInputs, RecordInputs, SharedPlan, Work,
};
use crate::effects::virtual_texture::VirtualTexture;
use crate::error::Result;
use crate::frame::{Frame, QueueKind};
use crate::gpu::{Buffer, Context};
use crate::passes::counters::FrameCounters;
use crate::scene::effect::Effect;
use crate::scene::graph::{FrameLog, FramePass, PassWork, Skip};
use crate::shaders::consts::{GRASS_BLADES, GRASS_BLADE_VERTICES, GRASS_PIGMENT_TEXELS};
use std::any::Any;

/// Its passes: the pigment map (when the camera left its step or the
/// terrain changed), the placement and culling of the tufts, and the one
/// indirect draw of every tuft kept.
pub const GRASS_PIGMENT: FramePass = FramePass::new(crate::shaders::grass_pigment::PASS);
pub const GRASS_PLACE: FramePass = FramePass::new(crate::shaders::grass_place::PASS);
pub const GRASS_DRAW: FramePass = FramePass::new(crate::shaders::grass_draw_vert::PASS);

/// Triangles of one tuft.
const TUFT_TRIANGLES: u64 = (GRASS_BLADES * GRASS_BLADE_VERTICES / 3) as u64;

/// Builds effect `grass` when it is on.
pub fn build(b: &mut BuildInputs) -> Result<Option<Box<dyn FrameEffect>>> {
    if !b.on(Effect::Grass) {
        return Ok(None);
    }
    let variants = (b.occlusion, b.on(Effect::Decals));
    Ok(Some(Box::new(Grass::new(b.ctx, &b.effects.grass, variants, b.depth.format, b.layout)?)))
}

fn counters_of(c: &FrameCounters) -> Option<GrassCounters> {
    let bytes = c.of(Effect::Grass)?;
    Some(bytemuck::pod_read_unaligned::<GrassHeaderGpu>(bytes).counters())
}

fn pass(frame: &mut Frame<'_, '_>, log: &mut FrameLog, p: FramePass, f: impl FnOnce(&mut crate::gpu::Recorder)) {
    frame.pass(p.name(), false, QueueKind::Graphics, f);
    log.ran(p, None);
}

impl Grass {
    fn record_placement(&self, frame: &mut Frame<'_, '_>, log: &mut FrameLog, r: &RecordInputs) {
        let f = self.frame.as_ref().expect("planned before recording");
        let sector = r.sector_data.buffer();
        let decals = r.find::<VirtualTexture>().and_then(VirtualTexture::decal_resources);
        if f.pigment_due {
            let m = r.materials.expect("grass needs splat's materials");
            pass(frame, log, GRASS_PIGMENT, |rec| self.record_pigment(rec, f, sector, r.tree, m, decals));
        } else {
            log.skipped(GRASS_PIGMENT, Skip::PigmentCurrent);
        }
        pass(frame, log, GRASS_PLACE, |rec| self.record_place(rec, f, r.view_buffer, r.hiz, sector, r.tree, decals));
    }
}

impl FrameEffect for Grass {
    fn effect(&self) -> Effect {
        Effect::Grass
    }

    fn plan(&mut self, p: &PlanInputs, shared: &SharedPlan) -> Result<()> {
        let inputs = GrassFrameInputs {
            camera_world: p.camera_world,
            terrain: p.vista_terrain,
            depth_size: p.depth_size,
            holes: p.holes,
            hiz: p.hiz,
            terrain_changed: p.terrain_changed,
        };
        self.frame = Some(self.begin_frame(&inputs, shared.decals.as_deref()));
        Ok(())
    }

    fn record(&self, point: FramePoint, frame: &mut Frame<'_, '_>, log: &mut FrameLog, r: &RecordInputs) {
        match point {
            FramePoint::BeforeClassify => self.record_placement(frame, log, r),
            FramePoint::AfterTiles => {
                let f = self.frame.as_ref().expect("planned before recording");
                pass(frame, log, GRASS_DRAW, |rec| self.record_draw(rec, f, r.view_buffer, r.targets, r.gbuffer));
            }
            _ => {}
        }
    }

    fn pipelines(&self) -> Vec<String> {
        self.pipeline_labels()
    }

    fn memory(&self) -> Vec<(String, u64, Vec<Effect>)> {
        Grass::memory(self).into_iter().map(|(n, b)| (n, b, vec![Effect::Grass])).collect()
    }

    fn work(&self, pass: FramePass, _: Option<u64>, c: &FrameCounters, _: [u32; 2]) -> Option<Work> {
        let groups = |g: u64| PassWork { dispatch_groups: Some(g), ..PassWork::default() };
        let counters = counters_of(c).unwrap_or_default();
        match pass {
            GRASS_PIGMENT => {
                let [wx, wy, _] = crate::shaders::grass_pigment::WORKGROUP_SIZE;
                let side = GRASS_PIGMENT_TEXELS;
                Some((groups(u64::from(side.div_ceil(wx)) * u64::from(side.div_ceil(wy))), None))
            }
            GRASS_PLACE => {
                let [wx, wy, _] = crate::shaders::grass_place::WORKGROUP_SIZE;
                let side = self.params.side();
                let work = groups(u64::from(side.div_ceil(wx) * side.div_ceil(wy)));
                Some((work, (counters.in_range == 0).then_some("no cell of the square lies within the radius")))
            }
            GRASS_DRAW => {
                let drawn = counters.drawn;
                let work = PassWork {
                    instances: Some(u64::from(drawn)),
                    triangles: Some(u64::from(drawn) * TUFT_TRIANGLES),
                    ..PassWork::default()
                };
                Some((work, (drawn == 0).then_some("no tuft placed and visible (0 instances)")))
            }
            _ => None,
        }
    }

    fn counters(&self) -> Option<(&Buffer, u64)> {
        Some((self.header(), GrassHeaderGpu::BYTES))
    }

    fn stats(&self, _: &Context, c: &FrameCounters) -> Result<Option<EffectStats>> {
        let Some(counters) = counters_of(c) else { return Ok(None) };
        let triangles = u64::from(counters.drawn) * TUFT_TRIANGLES;
        let memory_bytes: u64 = Grass::memory(self).iter().map(|(_, b)| b).sum();
        let skipped = match &self.params.occurrence {
            Some(o) => {
                format!(" ({} skipped by the occurrence map of {})", counters.skipped_occurrence, o.folder.display())
            }
            None => String::new(),
        };
        let line = format!(
            "grass: {} cells in range{skipped}, {} tufts placed, {} culled by the frustum, {} by the depth pyramid, \
             {} drawn ({triangles} triangles); {:.2} MiB",
            counters.in_range,
            counters.placed,
            counters.culled_frustum,
            counters.culled_hiz,
            counters.drawn,
            memory_bytes as f64 / f64::from(1u32 << 20)
        );
        let mut value = serde_json::to_value(counters).expect("plain counters");
        value["triangles"] = triangles.into();
        value["memory_bytes"] = memory_bytes.into();
        Ok(Some(EffectStats { key: "grass", value, lines: vec![line] }))
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

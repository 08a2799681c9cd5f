//! Effects `virtual_texture` and `decals` in the frame: the pages planned
//! on the CPU, the displacement decals' meshes drawn after the terrain,
//! the page passes before the tile shading (which then samples the cache),
//! and their numbers.

use super::decal_mesh::DecalMeshes;
use super::decal_meshes::DecalMeshPass;
use super::stats::VtStats;
use super::{VirtualTexture, VtCamera};
use crate::effects::frame_effect::{
    BuildInputs, EffectStats, FrameEffect, FramePoint, PlanInputs, RecordInputs, SharedPlan, Work,
};
use crate::error::Result;
use crate::frame::{Frame, QueueKind};
use crate::gpu::Context;
use crate::passes::counters::FrameCounters;
use crate::passes::gbuffer_tiles::MaterialBindings;
use crate::scene::effect::Effect;
use crate::scene::graph::{FrameLog, FramePass, PassWork, Skip};
use std::any::Any;

/// Its passes: the displacement decals' meshes (effect `decals`, built
/// only where a decal displaces); the indirection and sub-texture writes,
/// the pages missing (up to the budget), the pages this frame samples.
pub const DECAL_MESHES: FramePass = FramePass::new(crate::shaders::decal_meshes_vert::PASS);
pub const VT_UPDATE: FramePass = FramePass::new(crate::shaders::vt_update::PASS);
pub const VT_PAGES: FramePass = FramePass::new(crate::shaders::vt_pages::PASS);
pub const VT_FEEDBACK: FramePass = FramePass::new(crate::shaders::vt_feedback::PASS);

/// Builds the virtual texture when it is on, with the decals' objects
/// when `decals` is, and their meshes' pass when one displaces.
pub fn build(b: &mut BuildInputs) -> Result<Option<Box<dyn FrameEffect>>> {
    if !b.on(Effect::VirtualTexture) {
        return Ok(None);
    }
    let decals = b.on(Effect::Decals).then_some(b.decals);
    let params = b.effects.virtual_texture;
    let mut vt = VirtualTexture::new(b.ctx, b.world.extent_m, params, b.frames_in_flight, decals)?;
    if let Some(set) = decals {
        let meshes = DecalMeshes::build(&set.decals, &set.textures);
        if meshes.meshes == 0 {
            b.graph.not_built(DECAL_MESHES, "no decal displaces the terrain (displace_m)".into());
        } else {
            vt.decal_meshes = Some(DecalMeshPass::new(b.ctx, &meshes, b.depth)?);
        }
    }
    Ok(Some(Box::new(vt)))
}

fn pass(
    frame: &mut Frame<'_, '_>,
    log: &mut FrameLog,
    p: FramePass,
    n: Option<u64>,
    f: impl FnOnce(&mut crate::gpu::Recorder),
) {
    frame.pass(p.name(), false, QueueKind::Graphics, f);
    log.ran(p, n);
}

impl VirtualTexture {
    fn record_decal_meshes(&self, frame: &mut Frame<'_, '_>, log: &mut FrameLog, r: &RecordInputs) {
        let Some(m) = &self.decal_meshes else { return };
        if m.is_empty() {
            log.skipped(DECAL_MESHES, Skip::NoDisplacement);
            return;
        }
        let (view, sector) = (r.view_buffer, r.sector_data.buffer());
        pass(frame, log, DECAL_MESHES, None, |rec| {
            m.record(rec, r.targets, r.gbuffer, view, r.terrain, sector, r.tree)
        });
    }

    fn record_pages_and_feedback(&self, frame: &mut Frame<'_, '_>, log: &mut FrameLog, r: &RecordInputs) {
        let f = self.frame.as_ref().expect("planned before recording");
        let m = r.materials.expect("the virtual texture caches splat's materials");
        if f.init {
            frame.untimed(QueueKind::Graphics, |rec| self.record_init(rec));
        }
        if f.writes.is_empty() {
            log.skipped(VT_UPDATE, Skip::NoVtWrites);
        } else {
            let n = Some(f.writes.len() as u64);
            pass(frame, log, VT_UPDATE, n, |rec| self.record_update(rec, &f.writes));
        }
        if f.jobs.is_empty() {
            log.skipped(VT_PAGES, Skip::NoVtPages);
        } else {
            let (n, sector) = (Some(f.jobs.len() as u64), r.sector_data.buffer());
            pass(frame, log, VT_PAGES, n, |rec| self.record_pages(rec, f, r.terrain, sector, r.tree, m));
        }
        pass(frame, log, VT_FEEDBACK, None, |rec| self.record_feedback(rec, f, r.view_buffer, r.targets, r.gbuffer));
    }
}

impl FrameEffect for VirtualTexture {
    fn effect(&self) -> Effect {
        Effect::VirtualTexture
    }

    fn share(&self, shared: &mut SharedPlan) {
        shared.decals = self.uploaded_decals().map(<[_]>::to_vec);
    }

    fn plan(&mut self, p: &PlanInputs, _: &SharedPlan) -> Result<()> {
        let view = p.view;
        let camera = VtCamera {
            xy: [view.camera.position_m[0], view.camera.position_m[1]],
            pixel_rad: 2.0 * (view.fov_y_deg.to_radians() * 0.5).tan() / f64::from(view.size[1]),
            // A pixel at the near flavour's far end can lie this far away.
            range_m: f64::from(p.shade.far_end_m) * view.corner_secant(),
            size: view.size,
        };
        self.frame = Some(self.begin_frame(p.ctx, p.frame[0], p.frame[1], camera, p.terrain));
        Ok(())
    }

    fn record(&self, point: FramePoint, frame: &mut Frame<'_, '_>, log: &mut FrameLog, r: &RecordInputs) {
        match point {
            FramePoint::AfterTerrainDraws => self.record_decal_meshes(frame, log, r),
            FramePoint::BeforeTiles => self.record_pages_and_feedback(frame, log, r),
            _ => {}
        }
    }

    fn bind_materials<'a>(&'a self, m: &mut Option<MaterialBindings<'a>>, shading: bool) {
        if let (true, Some(m)) = (shading, m.as_mut()) {
            m.virtual_texture = Some(self.bindings());
        }
    }

    fn settled(&self) -> bool {
        VirtualTexture::settled(self)
    }

    fn catch_up(&mut self, on: bool) {
        self.set_catch_up(on);
    }

    fn pipelines(&self) -> Vec<String> {
        let mut out: Vec<String> = self.pipeline_labels().map(str::to_string).to_vec();
        out.extend(self.decal_meshes.iter().map(|p| p.pipeline_label().to_string()));
        out
    }

    fn memory(&self) -> Vec<(String, u64, Vec<Effect>)> {
        let tag = |e: Effect| move |(n, b): (String, u64)| (n, b, vec![e]);
        let mut out: Vec<_> = VirtualTexture::memory(self).into_iter().map(tag(Effect::VirtualTexture)).collect();
        out.extend(self.decal_memory().into_iter().map(tag(Effect::Decals)));
        out.extend(self.decal_meshes.iter().flat_map(DecalMeshPass::memory).map(tag(Effect::Decals)));
        out
    }

    fn work(&self, pass: FramePass, cpu_work: Option<u64>, _: &FrameCounters, size: [u32; 2]) -> Option<Work> {
        let groups = |g: u64| PassWork { dispatch_groups: Some(g), ..PassWork::default() };
        let work = match pass {
            VT_UPDATE => PassWork { writes: cpu_work, ..groups(1) },
            VT_PAGES => {
                let pages = cpu_work.unwrap_or(0);
                let [wx, wy, _] = crate::shaders::vt_pages::WORKGROUP_SIZE;
                let side = u64::from(super::layout::PADDED_TILE);
                let per_page = side.div_ceil(u64::from(wx)) * side.div_ceil(u64::from(wy));
                PassWork { pages: Some(pages), ..groups(pages * per_page) }
            }
            VT_FEEDBACK => {
                let [wx, wy, _] = crate::shaders::vt_feedback::WORKGROUP_SIZE;
                let cells = size.map(|s| s.div_ceil(crate::shaders::consts::VT_FEEDBACK_STRIDE));
                groups(u64::from(cells[0].div_ceil(wx)) * u64::from(cells[1].div_ceil(wy)))
            }
            DECAL_MESHES => {
                let m = self.decal_meshes.as_ref();
                let (instances, triangles) = (m.map(|m| u64::from(m.meshes)), m.map(|m| m.triangles));
                PassWork { instances, triangles, ..PassWork::default() }
            }
            _ => return None,
        };
        Some((work, None))
    }

    fn stats(&self, _: &Context, _: &FrameCounters) -> Result<Option<EffectStats>> {
        let s = VtStats::of(self);
        let lines = s.lines();
        let value = serde_json::to_value(&s).expect("plain numbers");
        Ok(Some(EffectStats { key: "virtual_texture", value, lines }))
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

impl VirtualTexture {
    /// Effect `decals`: replaces the decals (see
    /// [`VirtualTexture::set_decals`]) and makes the displacement meshes
    /// again; checked first, so a refused edit changes nothing. A renderer
    /// made without a displacement decal cannot take one (its pass was not
    /// built).
    pub fn edit_decals(&mut self, ctx: &Context, decals: Vec<super::decals::Decal>, frame: u64) -> Result<u32> {
        let meshes = DecalMeshes::build(&decals, self.decal_textures());
        if self.decal_meshes.is_none() && meshes.meshes > 0 {
            return Err(crate::error::Error::BadInput(
                "a displacement decal (displace_m) added to a renderer made without one: give one at creation".into(),
            ));
        }
        let dropped = self.set_decals(decals, frame)?;
        if let Some(pass) = &mut self.decal_meshes {
            pass.replace(ctx, &meshes)?;
        }
        Ok(dropped)
    }
}

//! Effect `shadows` in the frame: which nodes' shadow textures are marched
//! (arrived and stale ones, up to the budget), the pass before the
//! lighting resolve, and the atlas the resolve samples.

use super::sun_shadows::{MarchOver, SunShadowJob, SunShadows, MAX_UPDATE_BUDGET};
use super::{MarchSun, NodeExtent, ShadowSchedule};
use crate::effects::frame_effect::{BuildInputs, FrameEffect, FramePoint, PlanInputs, RecordInputs, SharedPlan, Work};
use crate::error::Result;
use crate::frame::{Frame, QueueKind};
use crate::passes::counters::FrameCounters;
use crate::passes::lighting_resolve::{ResolveInputs, ShadowInput};
use crate::scene::effect::Effect;
use crate::scene::graph::{FrameLog, FramePass, PassWork, Skip};
use crate::terrain::Terrain;
use crate::world::NodeId;
use glam::DVec3;
use std::any::Any;

/// Its pass: the shadow textures of arrived and stale nodes.
pub const SUN_SHADOWS: FramePass = FramePass::new(crate::shaders::sun_shadows::PASS);

/// The built effect: the pass and its atlas, and which nodes it redoes when.
pub struct Shadows {
    pub pass: SunShadows,
    pub schedule: ShadowSchedule,
    /// Switched off in an earlier frame and not back on yet.
    were_off: bool,
    /// A render waiting to settle: the largest budget every frame.
    catch_up: bool,
    /// This frame: switched on, the jobs, shown (every slot current), the
    /// sun's direction and elevation (degrees).
    on: bool,
    jobs: Vec<SunShadowJob>,
    shown: bool,
    sun: DVec3,
    elevation_deg: f64,
}

/// Builds effect `shadows` when it is on.
pub fn build(b: &mut BuildInputs) -> Result<Option<Box<dyn FrameEffect>>> {
    if !b.on(Effect::Shadows) {
        return Ok(None);
    }
    Ok(Some(Box::new(Shadows {
        pass: SunShadows::new(b.ctx, b.effects.shadows, b.slot_capacity, b.on(Effect::Vegetation))?,
        schedule: ShadowSchedule::default(),
        were_off: false,
        catch_up: false,
        on: false,
        jobs: Vec::new(),
        shown: false,
        sun: DVec3::Z,
        elevation_deg: 90.0,
    })))
}

impl Shadows {
    /// This frame's jobs. Switched off, none; switched back on, every
    /// resident node's shadow is stale (nodes arrived meanwhile were not
    /// marched) and they are redone as fast as the job list allows.
    /// `canopy_m`: the tallest canopy on the ground (an arrival's ridge
    /// casts that much higher).
    fn jobs(&mut self, terrain: &Terrain, canopy_m: f64) -> Vec<SunShadowJob> {
        let tree = &terrain.tree;
        if !self.on {
            self.were_off = true;
            return Vec::new();
        }
        let mut budget = self.pass.params.update_budget;
        if std::mem::take(&mut self.were_off) {
            let resident: Vec<_> =
                terrain.resident_nodes().into_iter().filter_map(|n| Some((n, tree.shadow.slot_of(n)?))).collect();
            self.schedule.restart(&resident);
        }
        if !self.schedule.ready() || self.catch_up {
            budget = MAX_UPDATE_BUDGET;
        }
        let world = terrain.world;
        let march = MarchSun { dir: self.sun.as_vec3().to_array(), reach_m: f64::from(self.pass.params.reach_m) };
        let extent = |n: NodeId| {
            let slot = tree.shadow.slot_of(n)?;
            let [lo, hi] = tree.shadow.height_range(slot);
            let [x0, y0, x1, y1] = world.bounds_m(n);
            Some((slot, NodeExtent { bounds_m: [x0, y0, x1, y1], min_m: lo, max_m: hi + canopy_m }))
        };
        self.schedule.plan(march, budget, tree.arrived(), extent)
    }
}

impl FrameEffect for Shadows {
    fn effect(&self) -> Effect {
        Effect::Shadows
    }

    fn plan(&mut self, p: &PlanInputs, shared: &SharedPlan) -> Result<()> {
        self.on = p.switches.on(Effect::Shadows);
        self.sun = p.effects.lighting.sun_dir();
        self.elevation_deg = p.effects.lighting.sun_elevation_deg;
        self.jobs = self.jobs(p.terrain, f64::from(shared.canopy_top_m.unwrap_or(0.0)));
        // Switched back on, the shadows show once every slot holds its own
        // node's texture again; until then the lighting goes without them.
        self.shown = self.on && self.schedule.ready();
        Ok(())
    }

    fn record(&self, point: FramePoint, frame: &mut Frame<'_, '_>, log: &mut FrameLog, r: &RecordInputs) {
        if point != FramePoint::BeforeResolve {
            return;
        }
        if !self.on {
            log.skipped(SUN_SHADOWS, Skip::ShadowsOff);
        } else if self.jobs.is_empty() {
            log.skipped(SUN_SHADOWS, Skip::ShadowsCurrent);
        } else {
            frame.pass(SUN_SHADOWS.name(), false, QueueKind::Graphics, |rec| {
                let canopy = r.effects.iter().find_map(|e| e.canopy());
                let on = MarchOver { terrain: r.terrain, sector_data: r.sector_data, tree: r.tree, canopy };
                self.pass.record(rec, &self.jobs, self.sun, on)
            });
            log.ran(SUN_SHADOWS, Some(self.jobs.len() as u64));
        }
    }

    fn bind_resolve<'a>(&'a self, r: &mut ResolveInputs<'a>) {
        if self.on {
            let p = &self.pass.params;
            let penumbra = p.penumbra(self.elevation_deg);
            r.shadows = Some(ShadowInput { atlas: &self.pass.atlas, penumbra, resolution: p.resolution });
        }
    }

    fn shown(&self) -> bool {
        self.shown
    }

    fn settled(&self) -> bool {
        self.schedule.stale() == 0
    }

    fn catch_up(&mut self, on: bool) {
        self.catch_up = on;
    }

    fn pipelines(&self) -> Vec<String> {
        self.pass.pipeline_labels().map(str::to_string).collect()
    }

    fn memory(&self) -> Vec<(String, u64, Vec<Effect>)> {
        self.pass.memory().into_iter().map(|(n, b)| (n, b, vec![Effect::Shadows])).collect()
    }

    fn work(&self, pass: FramePass, cpu_work: Option<u64>, _: &FrameCounters, _: [u32; 2]) -> Option<Work> {
        if pass != SUN_SHADOWS {
            return None;
        }
        let jobs = cpu_work.unwrap_or(0);
        let side = u64::from(self.pass.params.resolution);
        let [wx, wy, _] = crate::shaders::sun_shadows::WORKGROUP_SIZE;
        let per_node = side.div_ceil(u64::from(wx)) * side.div_ceil(u64::from(wy));
        let work = PassWork { shadow_nodes: Some(jobs), dispatch_groups: Some(jobs * per_node), ..PassWork::default() };
        Some((work, None))
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

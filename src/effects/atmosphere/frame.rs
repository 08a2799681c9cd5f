//! Effect `atmosphere` in the frame: no pass of its own, the fog and sky
//! constants of the lighting resolve's ATMOSPHERE variant.

use super::AtmosphereParams;
use crate::effects::frame_effect::{BuildInputs, FrameEffect, PlanInputs, SharedPlan};
use crate::error::Result;
use crate::passes::lighting_resolve::ResolveInputs;
use crate::scene::effect::Effect;
use std::any::Any;

pub struct Atmosphere {
    pub params: AtmosphereParams,
    /// This frame's constants (None: switched off).
    fog: Option<[[f32; 4]; 3]>,
}

/// Builds effect `atmosphere` when it is on.
pub fn build(b: &mut BuildInputs) -> Result<Option<Box<dyn FrameEffect>>> {
    if !b.on(Effect::Atmosphere) {
        return Ok(None);
    }
    Ok(Some(Box::new(Atmosphere { params: b.effects.atmosphere, fog: None })))
}

impl FrameEffect for Atmosphere {
    fn effect(&self) -> Effect {
        Effect::Atmosphere
    }

    fn plan(&mut self, p: &PlanInputs, _: &SharedPlan) -> Result<()> {
        let low_m = p.terrain.world.height_range_m[0];
        self.fog = p.switches.on(Effect::Atmosphere).then(|| self.params.gpu(low_m));
        Ok(())
    }

    fn bind_resolve<'a>(&'a self, r: &mut ResolveInputs<'a>) {
        r.fog = self.fog;
    }

    fn pipelines(&self) -> Vec<String> {
        Vec::new()
    }

    fn memory(&self) -> Vec<(String, u64, Vec<Effect>)> {
        Vec::new()
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

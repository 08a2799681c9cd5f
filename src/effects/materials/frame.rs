//! The material effects (`splat`, `cliffs`) in the frame: no pass of their
//! own, the material table and detail textures every pass that shades a
//! material samples.

use super::gpu::MaterialResources;
use crate::effects::frame_effect::{BuildInputs, FrameEffect};
use crate::error::Result;
use crate::passes::gbuffer_tiles::MaterialBindings;
use crate::scene::effect::Effect;
use std::any::Any;

pub struct Materials {
    pub resources: MaterialResources,
    /// The material effects that are on (they share the resources).
    users: Vec<Effect>,
}

/// Builds the material resources when `splat` or `cliffs` is on.
pub fn build(b: &mut BuildInputs) -> Result<Option<Box<dyn FrameEffect>>> {
    let users: Vec<Effect> = [Effect::Splat, Effect::Cliffs].into_iter().filter(|e| b.on(*e)).collect();
    if users.is_empty() {
        return Ok(None);
    }
    Ok(Some(Box::new(Materials { resources: MaterialResources::new(b.ctx, b.effects)?, users })))
}

impl FrameEffect for Materials {
    fn effect(&self) -> Effect {
        Effect::Splat
    }

    fn bind_materials<'a>(&'a self, m: &mut Option<MaterialBindings<'a>>, _: bool) {
        *m = Some(self.resources.bindings());
    }

    fn pipelines(&self) -> Vec<String> {
        Vec::new()
    }

    fn memory(&self) -> Vec<(String, u64, Vec<Effect>)> {
        vec![("material_table + detail textures".into(), self.resources.memory_bytes(), self.users.clone())]
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

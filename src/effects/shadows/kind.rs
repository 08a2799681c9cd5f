//! Effect `shadows` as a scene names it.

use super::sun_shadows::MAX_UPDATE_BUDGET;
use crate::effects::core::needs_lit_image;
use crate::effects::frame_effect::{BuildInputs, FrameEffect};
use crate::effects::kind::{EffectKind, Verdict, WorldContent};
use crate::effects::requested::Effects;
use crate::error::Result;
use crate::scene::effect::Effect;
use crate::scene::graph::{EffectPass, FramePoint};
use crate::scene::params::{number, whole};
use std::path::Path;

pub struct ShadowsKind;
impl EffectKind for ShadowsKind {
    fn passes(&self) -> &'static [EffectPass] {
        &[EffectPass { point: FramePoint::BeforeResolve, pass: super::frame::SUN_SHADOWS, effects: &[Effect::Shadows] }]
    }

    fn build(&self, b: &mut BuildInputs) -> Result<Option<Box<dyn FrameEffect>>> {
        super::frame::build(b)
    }

    fn effect(&self) -> Effect {
        Effect::Shadows
    }

    fn slot_bytes(&self, fx: &Effects) -> u64 {
        super::sun_shadows::layer_bytes(fx.shadows.resolution)
    }

    fn parameters(&self) -> &'static [&'static str] {
        &["resolution", "steps", "update_budget", "softness_deg", "reach_m"]
    }

    fn read(&self, fx: &mut Effects, key: &str, name: &str, v: &toml::Value, _: &Path) -> Result<()> {
        let p = &mut fx.shadows;
        match name {
            "resolution" => p.resolution = whole(key, v, 2, i64::from(crate::shaders::consts::SUN_SHADOW_MAX_SIDE))?,
            "steps" => p.steps = whole(key, v, 1, 1024)?,
            "update_budget" => p.update_budget = whole(key, v, 1, i64::from(MAX_UPDATE_BUDGET))?,
            "softness_deg" => p.softness_deg = number(key, v, 0.0, 10.0)? as f32,
            "reach_m" => p.reach_m = number(key, v, 1.0, 1e7)? as f32,
            _ => unreachable!("{key} is not read"),
        }
        Ok(())
    }

    fn verdict(&self, fx: &Effects, content: &WorldContent, _: bool) -> Verdict {
        needs_lit_image(fx, content)
    }
}

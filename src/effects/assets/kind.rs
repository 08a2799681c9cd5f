//! Effect `assets` as a scene names it.

use crate::effects::frame_effect::{BuildInputs, FrameEffect};
use crate::effects::kind::{EffectKind, Verdict, WorldContent};
use crate::effects::requested::Effects;
use crate::error::Result;
use crate::scene::effect::Effect;
use crate::scene::graph::{EffectPass, FramePoint};
use crate::scene::params::number;
use std::path::Path;

pub struct AssetsKind;
impl EffectKind for AssetsKind {
    fn passes(&self) -> &'static [EffectPass] {
        &[EffectPass { point: FramePoint::AfterTiles, pass: super::frame::ASSET_DRAW, effects: &[Effect::Assets] }]
    }

    fn build(&self, b: &mut BuildInputs) -> Result<Option<Box<dyn FrameEffect>>> {
        super::frame::build(b)
    }

    fn effect(&self) -> Effect {
        Effect::Assets
    }

    fn parameters(&self) -> &'static [&'static str] {
        &["blend_height_m"]
    }

    fn read(&self, fx: &mut Effects, key: &str, _: &str, v: &toml::Value, _: &Path) -> Result<()> {
        fx.assets.blend_height_m = number(key, v, 0.0, 100.0)? as f32;
        Ok(())
    }

    fn verdict(&self, _: &Effects, content: &WorldContent, _: bool) -> Verdict {
        if content.assets == 0 {
            return Verdict::Off("the scene has no assets ([[assets]])".into());
        }
        Verdict::On
    }
}

//! Effect `grass` as a scene names it: its parameters and when it can grow.

use crate::effects::frame_effect::{BuildInputs, FrameEffect};
use crate::effects::kind::{EffectKind, Verdict, WorldContent};
use crate::effects::materials::kinds::CONTROL_MAP_MODE;
use crate::effects::requested::Effects;
use crate::error::Result;
use crate::scene::effect::{Effect, MaterialsMode};
use crate::scene::graph::{EffectPass, FramePoint};
use std::path::Path;

pub struct GrassKind;
impl EffectKind for GrassKind {
    fn passes(&self) -> &'static [EffectPass] {
        const ON: &[Effect] = &[Effect::Grass];
        &[
            EffectPass { point: FramePoint::BeforeClassify, pass: super::frame::GRASS_PIGMENT, effects: ON },
            EffectPass { point: FramePoint::BeforeClassify, pass: super::frame::GRASS_PLACE, effects: ON },
            EffectPass { point: FramePoint::AfterTiles, pass: super::frame::GRASS_DRAW, effects: ON },
        ]
    }

    fn build(&self, b: &mut BuildInputs) -> Result<Option<Box<dyn FrameEffect>>> {
        super::frame::build(b)
    }

    fn effect(&self) -> Effect {
        Effect::Grass
    }

    fn parameters(&self) -> &'static [&'static str] {
        &super::GrassParams::PARAMETERS
    }

    fn read(&self, fx: &mut Effects, key: &str, name: &str, v: &toml::Value, base: &Path) -> Result<()> {
        fx.grass.read(key, name, v, base)
    }

    fn validate(&self, fx: &Effects) -> Result<()> {
        fx.grass.validate()
    }

    fn verdict(&self, fx: &Effects, _: &WorldContent, _: bool) -> Verdict {
        if fx.materials == MaterialsMode::ControlMap {
            Verdict::Off(format!(
                "its rules are by splat material id and the materials are the control map's {CONTROL_MAP_MODE}"
            ))
        } else if !fx.is_on(Effect::Splat) {
            Verdict::Off("it grows by the splat material ids and effect splat is off".into())
        } else if !fx.grass.grows() {
            Verdict::Off("no material grows grass (effects.grass.density)".into())
        } else {
            Verdict::On
        }
    }
}

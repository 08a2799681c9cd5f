//! Effect `atmosphere` as a scene names it.

use crate::effects::core::needs_lit_image;
use crate::effects::frame_effect::{BuildInputs, FrameEffect};
use crate::effects::kind::{EffectKind, Verdict, WorldContent};
use crate::effects::requested::Effects;
use crate::error::Result;
use crate::scene::effect::Effect;
use crate::scene::params::{bad, colour, number};
use std::path::Path;

pub struct AtmosphereKind;
impl EffectKind for AtmosphereKind {
    fn build(&self, b: &mut BuildInputs) -> Result<Option<Box<dyn FrameEffect>>> {
        super::frame::build(b)
    }

    fn effect(&self) -> Effect {
        Effect::Atmosphere
    }

    fn parameters(&self) -> &'static [&'static str] {
        &["visibility_km", "scale_height_m", "haze_color", "sun_g", "zenith_color", "air_depth"]
    }

    fn read(&self, fx: &mut Effects, key: &str, name: &str, v: &toml::Value, _: &Path) -> Result<()> {
        let a = &mut fx.atmosphere;
        match name {
            "visibility_km" => a.visibility_km = number(key, v, 0.01, 1e5)? as f32,
            "scale_height_m" => a.scale_height_m = number(key, v, 1.0, 1e5)? as f32,
            "haze_color" => {
                let c = colour(key, v)?;
                if c.iter().any(|&x| x > 1.0) {
                    return Err(bad(format!("{key} = {c:?}: a share of the light scattered, each 0..=1")));
                }
                a.haze_color = c;
            }
            "sun_g" => a.sun_g = number(key, v, 0.0, 0.95)? as f32,
            "zenith_color" => a.zenith_color = colour(key, v)?,
            "air_depth" => a.air_depth = number(key, v, 0.0, 10.0)? as f32,
            _ => unreachable!("{key} is not read"),
        }
        Ok(())
    }

    fn verdict(&self, fx: &Effects, content: &WorldContent, _: bool) -> Verdict {
        needs_lit_image(fx, content)
    }
}

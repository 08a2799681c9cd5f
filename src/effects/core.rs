//! The core effects: switches of the terrain passes themselves (holes,
//! culling stages, lighting, queries), with no folder of their own.

use super::kind::{EffectKind, Verdict, WorldContent};
use super::requested::Effects;
use crate::error::Result;
use crate::scene::effect::Effect;
use crate::scene::params::{bad, colour, number, wrong};
use crate::scene::tonemap::Tonemap;
use std::path::Path;

/// The output leaves the lighting to the engine (output `gbuffer`).
pub(super) const ENGINE_LIGHTS: &str = "output gbuffer leaves the lighting to the engine";

pub struct Holes;
impl EffectKind for Holes {
    fn effect(&self) -> Effect {
        Effect::Holes
    }

    fn verdict(&self, _: &Effects, content: &WorldContent, force: bool) -> Verdict {
        match &content.holes_missing {
            Some(why) if force => Verdict::Forced(why.clone()),
            Some(why) => Verdict::Off(why.clone()),
            None => Verdict::OnWith(content.holes_present.clone()),
        }
    }
}

pub struct ConeCull;
impl EffectKind for ConeCull {
    fn effect(&self) -> Effect {
        Effect::ConeCull
    }
}

pub struct Occlusion;
impl EffectKind for Occlusion {
    fn effect(&self) -> Effect {
        Effect::Occlusion
    }
}

pub struct Queries;
impl EffectKind for Queries {
    fn effect(&self) -> Effect {
        Effect::Queries
    }
}

pub struct Lighting;
impl EffectKind for Lighting {
    fn effect(&self) -> Effect {
        Effect::Lighting
    }

    fn parameters(&self) -> &'static [&'static str] {
        &["sun_azimuth_deg", "sun_elevation_deg", "sun_color", "sky_color", "clay_albedo", "tonemap", "exposure_ev"]
    }

    fn read(&self, fx: &mut Effects, key: &str, name: &str, v: &toml::Value, _: &Path) -> Result<()> {
        let l = &mut fx.lighting;
        match name {
            "sun_azimuth_deg" => l.sun_azimuth_deg = number(key, v, -360.0, 360.0)?,
            "sun_elevation_deg" => l.sun_elevation_deg = number(key, v, -90.0, 90.0)?,
            "sun_color" => l.sun_color = colour(key, v)?,
            "sky_color" => l.sky_color = colour(key, v)?,
            // Zero would read as "off" on the GPU: the range starts above it.
            "clay_albedo" => l.clay_albedo = Some(number(key, v, 1e-3, 1.0)? as f32),
            "tonemap" => {
                let names: Vec<&str> = Tonemap::ALL.iter().map(|t| t.name()).collect();
                let expected = format!("one of {}", names.join(", "));
                let name = v.as_str().ok_or_else(|| wrong(key, &expected, v))?;
                l.tonemap = Tonemap::from_name(name)
                    .ok_or_else(|| bad(format!("{key} = {name:?} is not a tonemapper ({expected})")))?;
            }
            // 2^20 either way keeps the exposed image finite in f32.
            "exposure_ev" => l.exposure_ev = Some(number(key, v, -20.0, 20.0)? as f32),
            _ => unreachable!("{key} is not read"),
        }
        Ok(())
    }

    fn verdict(&self, _: &Effects, content: &WorldContent, _: bool) -> Verdict {
        if content.engine_lights {
            return Verdict::Off(ENGINE_LIGHTS.into());
        }
        Verdict::On
    }
}

/// Shadows and the atmosphere change the lit image: off when the engine
/// lights or vista's lighting is off.
pub(super) fn needs_lit_image(fx: &Effects, content: &WorldContent) -> Verdict {
    if content.engine_lights {
        Verdict::Off(ENGINE_LIGHTS.into())
    } else if !fx.is_on(Effect::Lighting) {
        Verdict::Off("it changes the lit image and effect lighting is off".into())
    } else {
        Verdict::On
    }
}

//! The material effects as a scene names them: `splat` (the near
//! materials, splat map or control map) and `cliffs` (their tri-planar
//! cliff flavours).

use crate::effects::frame_effect::{BuildInputs, FrameEffect};
use crate::effects::kind::{EffectKind, Verdict, WorldContent};
use crate::effects::requested::Effects;
use crate::error::Result;
use crate::scene::effect::{Effect, MaterialsMode};
use crate::scene::params::{boolean, file, number, seed};
use std::path::Path;

/// The note of effects that the control-map materials replace.
pub(crate) const CONTROL_MAP_MODE: &str = "([materials] mode = \"control_map\")";

pub struct Splat;
impl EffectKind for Splat {
    fn build(&self, b: &mut BuildInputs) -> Result<Option<Box<dyn FrameEffect>>> {
        super::frame::build(b)
    }

    fn effect(&self) -> Effect {
        Effect::Splat
    }

    fn parameters(&self) -> &'static [&'static str] {
        &["materials", "far_start_m", "far_band_m"]
    }

    fn read(&self, fx: &mut Effects, key: &str, name: &str, v: &toml::Value, base: &Path) -> Result<()> {
        let shade = &mut fx.shade;
        match name {
            "materials" => fx.splat_materials = Some(file(key, v, base)?),
            "far_start_m" => {
                let band = shade.far_end_m - shade.far_start_m;
                shade.far_start_m = number(key, v, 0.0, 1e7)? as f32;
                shade.far_end_m = shade.far_start_m + band;
            }
            "far_band_m" => shade.far_end_m = shade.far_start_m + number(key, v, 1.0, 1e7)? as f32,
            _ => unreachable!("{key} is not read"),
        }
        Ok(())
    }

    fn verdict(&self, fx: &Effects, _: &WorldContent, _: bool) -> Verdict {
        match fx.materials {
            MaterialsMode::ControlMap => Verdict::OnWith(format!("the control-map flavour {CONTROL_MAP_MODE}")),
            MaterialsMode::Splat => Verdict::On,
        }
    }
}

pub struct Cliffs;
impl EffectKind for Cliffs {
    fn effect(&self) -> Effect {
        Effect::Cliffs
    }

    fn parameters(&self) -> &'static [&'static str] {
        &["slope_deg", "band_deg", "near_far_m", "stochastic", "hash_seed"]
    }

    fn read(&self, fx: &mut Effects, key: &str, name: &str, v: &toml::Value, _: &Path) -> Result<()> {
        let shade = &mut fx.shade;
        match name {
            "slope_deg" => shade.cliff_slope_deg = number(key, v, 0.0, 90.0)? as f32,
            "band_deg" => shade.cliff_band_deg = number(key, v, 0.0, 45.0)? as f32,
            "near_far_m" => {
                let m = number(key, v, 0.0, 1e6)? as f32;
                shade.cliff_split_start_m = m;
                shade.cliff_split_end_m = m * 5.0 / 3.0;
            }
            "stochastic" => shade.stochastic = boolean(key, v)?,
            "hash_seed" => shade.hash_seed = seed(key, v)?,
            _ => unreachable!("{key} is not read"),
        }
        Ok(())
    }

    fn verdict(&self, fx: &Effects, _: &WorldContent, _: bool) -> Verdict {
        match fx.materials {
            MaterialsMode::ControlMap => Verdict::Off(format!(
                "the control-map materials shade slopes with their tri-planar background {CONTROL_MAP_MODE}"
            )),
            MaterialsMode::Splat => Verdict::On,
        }
    }
}

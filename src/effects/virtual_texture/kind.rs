//! Effects `virtual_texture` and `decals` (drawn into its pages) as a
//! scene names them.

use crate::effects::frame_effect::{BuildInputs, FrameEffect};
use crate::effects::kind::{EffectKind, Verdict, WorldContent};
use crate::effects::materials::kinds::CONTROL_MAP_MODE;
use crate::effects::requested::Effects;
use crate::error::Result;
use crate::scene::effect::{Effect, MaterialsMode};
use crate::scene::graph::{EffectPass, FramePoint};
use crate::scene::params::{bad, number, whole};
use std::path::Path;

pub struct VirtualTextureKind;
impl EffectKind for VirtualTextureKind {
    fn passes(&self) -> &'static [EffectPass] {
        const ON: &[Effect] = &[Effect::VirtualTexture];
        &[
            EffectPass {
                point: FramePoint::AfterTerrainDraws,
                pass: super::frame::DECAL_MESHES,
                effects: &[Effect::Decals],
            },
            EffectPass { point: FramePoint::BeforeTiles, pass: super::frame::VT_UPDATE, effects: ON },
            EffectPass { point: FramePoint::BeforeTiles, pass: super::frame::VT_PAGES, effects: ON },
            EffectPass { point: FramePoint::BeforeTiles, pass: super::frame::VT_FEEDBACK, effects: ON },
        ]
    }

    fn build(&self, b: &mut BuildInputs) -> Result<Option<Box<dyn FrameEffect>>> {
        super::frame::build(b)
    }

    fn effect(&self) -> Effect {
        Effect::VirtualTexture
    }

    fn parameters(&self) -> &'static [&'static str] {
        &["cache_mb", "pages_per_frame", "region_m", "indirection", "window_m"]
    }

    fn read(&self, fx: &mut Effects, key: &str, name: &str, v: &toml::Value, _: &Path) -> Result<()> {
        let p = &mut fx.virtual_texture;
        match name {
            "cache_mb" => p.cache_mb = whole(key, v, 1, 4096)?,
            "pages_per_frame" => {
                p.pages_per_frame = whole(key, v, 1, i64::from(crate::shaders::consts::VT_MAX_JOBS))?;
            }
            "region_m" => p.region_m = number(key, v, 1.0, 1e5)?,
            "window_m" => p.window_m = number(key, v, 1.0, 1e6)?,
            "indirection" => {
                let side = whole(key, v, 64, 2048)?;
                if !side.is_power_of_two() {
                    return Err(bad(format!("{key} = {side}: the indirection's side must be a power of two")));
                }
                p.indirection = side;
            }
            _ => unreachable!("{key} is not read"),
        }
        Ok(())
    }

    fn verdict(&self, fx: &Effects, _: &WorldContent, _: bool) -> Verdict {
        if fx.materials == MaterialsMode::ControlMap {
            Verdict::Off(format!(
                "its pages cache the splat blend and the materials are the control map's {CONTROL_MAP_MODE}"
            ))
        } else if !fx.is_on(Effect::Splat) {
            Verdict::Off("its pages cache the splat materials and effect splat is off".into())
        } else {
            Verdict::On
        }
    }
}

pub struct DecalsKind;
impl EffectKind for DecalsKind {
    fn effect(&self) -> Effect {
        Effect::Decals
    }

    fn verdict(&self, _: &Effects, content: &WorldContent, _: bool) -> Verdict {
        if content.decals == 0 {
            return Verdict::Off("the scene has no decals ([[decals]])".into());
        }
        Verdict::On
    }

    fn needs(&self) -> &'static [(Effect, &'static str)] {
        &[(
            Effect::VirtualTexture,
            "decals are drawn into the virtual texture's pages and effect virtual_texture is off",
        )]
    }
}

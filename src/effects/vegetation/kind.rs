//! Effect `vegetation` as a scene names it: its parameters and when it
//! has something to draw.

use crate::effects::frame_effect::{BuildInputs, FrameEffect};
use crate::effects::kind::{EffectKind, Verdict, WorldContent};
use crate::effects::requested::Effects;
use crate::error::Result;
use crate::scene::effect::Effect;
use crate::scene::graph::{EffectPass, FramePoint};
use crate::world::vegetation::VegetationKind;
use std::path::Path;

pub struct VegetationKindOf;
impl EffectKind for VegetationKindOf {
    fn passes(&self) -> &'static [EffectPass] {
        const ON: &[Effect] = &[Effect::Vegetation];
        &[
            EffectPass { point: FramePoint::BeforeClassify, pass: super::frame::VEGETATION_CULL, effects: ON },
            EffectPass { point: FramePoint::AfterTiles, pass: super::frame::VEGETATION_DRAW, effects: ON },
        ]
    }

    fn build(&self, b: &mut BuildInputs) -> Result<Option<Box<dyn FrameEffect>>> {
        super::frame::build(b)
    }

    fn effect(&self) -> Effect {
        Effect::Vegetation
    }

    fn parameters(&self) -> &'static [&'static str] {
        &[
            "folder",
            "lod_m",
            "tree_draw_m",
            "bush_draw_m",
            "tree_height_m",
            "bush_height_m",
            "blend_height_m",
            "canopy_cell_m",
        ]
    }

    fn read(&self, fx: &mut Effects, key: &str, name: &str, v: &toml::Value, base: &Path) -> Result<()> {
        fx.vegetation.read(key, name, v, base)
    }

    fn verdict(&self, fx: &Effects, _: &WorldContent, _: bool) -> Verdict {
        match &fx.vegetation.set {
            None => Verdict::Off("no vegetation folder (effects.vegetation.folder, from `vista vegetate`)".into()),
            Some(s) if !s.instances.iter().any(|i| s.types[i.ty as usize].1 != VegetationKind::Grass) => {
                Verdict::Off(format!("{} holds no tree or bush", s.folder.display()))
            }
            Some(_) => Verdict::On,
        }
    }
}

//! Effect `cliff_meshes` as a scene names it.

use crate::effects::frame_effect::{BuildInputs, FrameEffect};
use crate::effects::kind::{EffectKind, Verdict, WorldContent};
use crate::effects::requested::Effects;
use crate::error::Result;
use crate::scene::effect::{Effect, MaterialsMode};
use crate::scene::graph::{EffectPass, FramePoint};
use std::path::Path;

pub struct CliffMeshesKind;
impl EffectKind for CliffMeshesKind {
    fn passes(&self) -> &'static [EffectPass] {
        const ON: &[Effect] = &[Effect::CliffMeshes];
        &[
            EffectPass { point: FramePoint::BeforeTerrainDraws, pass: super::frame::CLIFF_MESH_BUILD, effects: ON },
            EffectPass { point: FramePoint::AfterTerrainDraws, pass: super::frame::CLIFF_MESHES, effects: ON },
        ]
    }

    fn build(&self, b: &mut BuildInputs) -> Result<Option<Box<dyn FrameEffect>>> {
        super::frame::build(b)
    }

    fn effect(&self) -> Effect {
        Effect::CliffMeshes
    }

    fn parameters(&self) -> &'static [&'static str] {
        &super::CliffMeshParams::PARAMETERS
    }

    fn read(&self, fx: &mut Effects, key: &str, name: &str, v: &toml::Value, _: &Path) -> Result<()> {
        fx.cliff_meshes.read(key, name, v)
    }

    fn validate(&self, fx: &Effects) -> Result<()> {
        fx.cliff_meshes.validate()
    }

    fn verdict(&self, fx: &Effects, _: &WorldContent, _: bool) -> Verdict {
        if fx.materials == MaterialsMode::ControlMap || !fx.is_on(Effect::Cliffs) {
            return Verdict::Off("the cliff flavours shade the meshes and effect cliffs is off".into());
        }
        Verdict::On
    }
}

//! [`Effects`]: what a scene asks for, each effect on or off with its
//! parameters (`parse.rs` reads them from a scene's `[effects]` table).

use super::assets::AssetParams;
use super::atmosphere::AtmosphereParams;
use super::cliff_meshes::CliffMeshParams;
use super::grass::GrassParams;
use super::shadows::sun_shadows::ShadowParams;
use super::virtual_texture::VtParams;
use crate::error::Result;
use crate::scene::effect::{Effect, MaterialsMode};
use crate::scene::params::{bad, file, number, wrong};
use crate::scene::shading::ShadeRules;
use crate::scene::view::Lighting;
use std::path::{Path, PathBuf};

/// The effects a scene asks for, with their parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct Effects {
    on: [bool; Effect::ALL.len()],
    /// Set explicitly (scene or code) rather than left at the default.
    named: [bool; Effect::ALL.len()],
    pub lighting: Lighting,
    /// Classification and cliff parameters (`allowed` is decided by the
    /// renderer from the effects that are on).
    pub shade: ShadeRules,
    /// Material set of the splat map (a file that must exist); in
    /// control-map mode also its `[[control_texture]]` table.
    pub splat_materials: Option<PathBuf>,
    /// The near material flavour's kind (scene `[materials] mode`).
    pub materials: MaterialsMode,
    /// A painted control map (16-bit PNG over the world's extent); `None`
    /// in control-map mode: words made from the material rules.
    pub control_map: Option<PathBuf>,
    pub virtual_texture: VtParams,
    pub shadows: ShadowParams,
    pub atmosphere: AtmosphereParams,
    pub grass: GrassParams,
    pub assets: AssetParams,
    pub cliff_meshes: CliffMeshParams,
    pub vegetation: crate::effects::vegetation::VegetationDrawParams,
}

impl Default for Effects {
    /// Every effect at its default (see [`Effect::default_on`]).
    fn default() -> Self {
        Effects {
            on: Effect::ALL.map(Effect::default_on),
            named: [false; Effect::ALL.len()],
            lighting: Lighting::default(),
            shade: ShadeRules::default(),
            splat_materials: None,
            materials: MaterialsMode::Splat,
            control_map: None,
            virtual_texture: VtParams::default(),
            shadows: ShadowParams::default(),
            atmosphere: AtmosphereParams::default(),
            grass: GrassParams::default(),
            assets: AssetParams::default(),
            cliff_meshes: CliffMeshParams::default(),
            vegetation: Default::default(),
        }
    }
}

impl Effects {
    /// Every effect requested (those not implemented are reported off).
    pub fn all() -> Effects {
        Effects { on: [true; Effect::ALL.len()], named: [true; Effect::ALL.len()], ..Effects::default() }
    }

    /// Geometry and lighting only.
    pub fn minimal() -> Effects {
        Effects::default().with(Effect::Holes, false).with(Effect::ConeCull, false)
    }

    pub fn is_on(&self, e: Effect) -> bool {
        self.on[e as usize]
    }

    pub fn set(&mut self, e: Effect, on: bool) {
        self.on[e as usize] = on;
        self.named[e as usize] = true;
    }

    /// Whether `e` was set explicitly rather than left at its default.
    pub fn is_named(&self, e: Effect) -> bool {
        self.named[e as usize]
    }

    pub fn with(mut self, e: Effect, on: bool) -> Effects {
        self.set(e, on);
        self
    }

    /// Reads a scene's `[materials]` table: `mode` ("splat" or
    /// "control_map"), `control_map` (a 16-bit PNG, relative to `base`),
    /// `tighten` (the tri-planar tighten factor, 0..1). Errors are one line
    /// naming the key.
    pub fn read_materials(&mut self, t: &toml::Table, base: &Path) -> Result<()> {
        const KNOWN: [&str; 3] = ["mode", "control_map", "tighten"];
        for (k, v) in t {
            let key = format!("materials.{k}");
            match k.as_str() {
                "mode" => {
                    let want = "\"splat\" or \"control_map\"";
                    self.materials = match v.as_str() {
                        Some("splat") => MaterialsMode::Splat,
                        Some("control_map") => MaterialsMode::ControlMap,
                        Some(other) => return Err(bad(format!("{key} = {other:?} is not a mode ({want})"))),
                        None => return Err(wrong(&key, want, v)),
                    };
                }
                "control_map" => self.control_map = Some(file(&key, v, base)?),
                "tighten" => self.shade.tighten = number(&key, v, 0.0, 1.0)? as f32,
                _ => return Err(bad(format!("unknown key {key} (known: {})", KNOWN.join(", ")))),
            }
        }
        if self.control_map.is_some() && self.materials != MaterialsMode::ControlMap {
            return Err(bad("materials.control_map needs materials.mode = \"control_map\"".into()));
        }
        Ok(())
    }
}

//! The optional effects, one folder each (its scene parameters, CPU
//! state, passes and report), driven by the renderer through two small
//! traits: [`EffectKind`] (the scene side: parameters, and whether it can
//! run in this scene and world) and [`FrameEffect`] (the built side: its
//! passes at named points of the frame, its counters and memory). The
//! registry (`KINDS`, below) lists them; each effect is on or off with its parameters,
//! the renderer builds pipelines, resources and passes only for effects
//! that are on, and a world lacking an effect's data switches it off with
//! a reason instead of paying for an idle path. Scene files name them in
//! an `[effects]` table:
//!
//! ```toml
//! [effects]
//! holes = true                          # a bool ...
//! lighting = { sun_elevation_deg = 25 } # ... or a table (enabled = true implied)
//! [effects.splat]
//! enabled = false
//! materials = "materials.toml"          # files are relative to the scene file
//! ```

pub mod assets;
pub mod atmosphere;
pub mod cliff_meshes;
mod core;
mod decide;
pub mod frame_effect;
pub mod grass;
pub mod kind;
pub mod materials;
mod parse;
pub mod registry;
mod requested;
pub mod shadows;
pub mod vegetation;
pub mod virtual_texture;

pub use crate::scene::effect::{Effect, EffectDecision, FrameSwitches, MaterialsMode};
pub use decide::decide;
pub use frame_effect::{FrameEffect, FramePoint};
pub use kind::{EffectKind, Verdict, WorldContent};
pub use requested::Effects;

/// The registry: every effect's kind, in `Effect::ALL` order. An effect is
/// its folder, its `mod` line above, its line here and its line in
/// `scene::effect`'s list.
pub(crate) static KINDS: [&dyn EffectKind; Effect::ALL.len()] = [
    &core::Holes,
    &core::ConeCull,
    &core::Occlusion,
    &materials::kinds::Cliffs,
    &cliff_meshes::kind::CliffMeshesKind,
    &materials::kinds::Splat,
    &virtual_texture::kind::VirtualTextureKind,
    &core::Lighting,
    &core::Queries,
    &virtual_texture::kind::DecalsKind,
    &assets::kind::AssetsKind,
    &grass::kind::GrassKind,
    &shadows::kind::ShadowsKind,
    &atmosphere::kind::AtmosphereKind,
    &vegetation::kind::VegetationKindOf,
];

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::Result;
    use crate::scene::tonemap::Tonemap;
    use std::path::Path;

    fn parse(text: &str) -> Result<Effects> {
        let t: toml::Table = toml::from_str(text).unwrap();
        Effects::from_toml(&t, Path::new("."))
    }

    #[test]
    fn the_registry_has_one_kind_per_effect_in_order() {
        let listed: Vec<Effect> = registry::kinds().iter().map(|k| k.effect()).collect();
        assert_eq!(listed, Effect::ALL);
    }

    #[test]
    fn names_round_trip_and_defaults() {
        for e in Effect::ALL {
            assert_eq!(Effect::from_name(e.name()), Some(e));
        }
        let d = Effects::default();
        assert!(d.is_on(Effect::Holes) && d.is_on(Effect::Lighting) && !d.is_on(Effect::Queries));
    }

    /// Decals live in the pages: on only with the virtual texture and with
    /// decals to draw, each refusal saying why.
    #[test]
    fn decals_need_the_virtual_texture_and_decals() {
        let fx = |vt: bool| {
            Effects::default().with(Effect::Splat, true).with(Effect::VirtualTexture, vt).with(Effect::Decals, true)
        };
        let decals = |fx: &Effects, n: usize| {
            let content = WorldContent { decals: n, ..WorldContent::default() };
            decide(fx, &content, false).into_iter().find(|d| d.effect == Effect::Decals).unwrap()
        };
        assert!(decals(&fx(true), 2).on);
        let no_vt = decals(&fx(false), 2);
        assert!(!no_vt.on && no_vt.reason.contains("virtual_texture is off"), "{}", no_vt.reason);
        let no_splat = decals(&fx(true).with(Effect::Splat, false), 2);
        assert!(!no_splat.on && no_splat.reason.contains("virtual_texture is off"), "{}", no_splat.reason);
        let none = decals(&fx(true), 0);
        assert!(!none.on && none.reason.contains("no decals"), "{}", none.reason);
        assert!(parse("decals = { file = \"x\" }").unwrap_err().to_string().contains("unknown parameter"));
    }

    /// Grass grows by splat material ids: off without splat, in control-map
    /// mode or when no material grows it, each refusal saying why; its
    /// parameters are read by material name and checked together.
    #[test]
    fn grass_needs_splat_ids_and_a_material_that_grows_it() {
        let grass = |fx: &Effects| {
            decide(fx, &WorldContent::default(), false).into_iter().find(|d| d.effect == Effect::Grass).unwrap()
        };
        let fx = parse("splat = true\ngrass = { radius_m = 20, density = { grass = 2, rock = 0.5 }, tint = { rock = [1, 0.5, 0.5] } }").unwrap();
        assert!(grass(&fx).on, "{}", grass(&fx).reason);
        assert_eq!(
            (fx.grass.radius_m, fx.grass.rules[1].density, fx.grass.rules[1].tint),
            (20.0, 0.5, [1.0, 0.5, 0.5])
        );
        let no_splat = grass(&fx.clone().with(Effect::Splat, false));
        assert!(!no_splat.on && no_splat.reason.contains("splat is off"), "{}", no_splat.reason);
        let mut control = fx.clone();
        control.materials = MaterialsMode::ControlMap;
        assert!(grass(&control).reason.contains("control map"));
        let bare = parse("splat = true\ngrass = { density = { grass = 0, scree = 0 } }").unwrap();
        assert!(grass(&bare).reason.contains("no material grows grass"), "{}", grass(&bare).reason);
        for (text, key) in [
            ("grass = { density = { moss = 1 } }", "effects.grass.density.moss: no such material"),
            ("grass = { density = { grass = 9 } }", "needs 2.25 per 0.5 m cell, at most 1"),
            ("grass = { radius_m = 500 }", "cells a side"),
            ("grass = { tint = { grass = 1 } }", "effects.grass.tint.grass must be an array"),
            ("grass = { blades = 3 }", "unknown parameter effects.grass.blades"),
        ] {
            let e = parse(text).unwrap_err().to_string();
            assert!(e.contains(key) && !e.contains('\n'), "{text}: {e}");
        }
    }

    #[test]
    fn bools_tables_and_parameters() {
        let fx = parse("holes = false\nlighting = { sun_elevation_deg = 25, sky_color = [0.1, 0.2, 0.3] }\n").unwrap();
        assert!(!fx.is_on(Effect::Holes));
        assert!(fx.is_on(Effect::Lighting));
        assert_eq!(fx.lighting.sun_elevation_deg, 25.0);
        assert_eq!(fx.lighting.sky_color, [0.1, 0.2, 0.3]);
        assert_eq!(fx.lighting.clay_albedo, None);
        assert_eq!(parse("lighting = { clay_albedo = 0.5 }\n").unwrap().lighting.clay_albedo, Some(0.5));
        assert_eq!((fx.lighting.tonemap, fx.lighting.exposure_ev()), (Tonemap::Aces, 0.5));
        let clip = parse("lighting = { tonemap = \"clip\", exposure_ev = -1.5 }\n").unwrap();
        assert_eq!((clip.lighting.tonemap, clip.lighting.exposure_ev()), (Tonemap::Clip, -1.5));
        // The clip's own default keeps the earlier image.
        assert_eq!(parse("lighting = { tonemap = \"clip\" }\n").unwrap().lighting.exposure_ev(), 0.0);
        assert!(!parse("[lighting]\nenabled = false\n").unwrap().is_on(Effect::Lighting));
    }

    #[test]
    fn errors_name_the_key() {
        for (text, key) in [
            ("holse = true", "effects.holse"),
            ("holes = 1", "effects.holes must be true, false or a table"),
            ("lighting = { sun_color = \"red\" }", "effects.lighting.sun_color must be an array"),
            ("lighting = { sun = 1 }", "unknown parameter effects.lighting.sun"),
            ("cliffs = { materials = \"x\" }", "unknown parameter effects.cliffs.materials"),
            ("splat = { materials = \"no/such/file.toml\" }", "effects.splat.materials: file"),
            ("lighting = { sun_elevation_deg = 95 }", "outside"),
            // 0 would mean "no clay" on the GPU.
            ("lighting = { clay_albedo = 0 }", "effects.lighting.clay_albedo = 0 is outside"),
            (
                "lighting = { tonemap = \"agx\" }",
                "effects.lighting.tonemap = \"agx\" is not a tonemapper (one of aces, clip)",
            ),
            ("lighting = { tonemap = 1 }", "effects.lighting.tonemap must be one of aces, clip"),
            ("lighting = { exposure_ev = 40 }", "effects.lighting.exposure_ev = 40 is outside"),
            ("shadows = { resolution = 1 }", "effects.shadows.resolution = 1 is outside 2..=257"),
            ("shadows = { steps = 2.5 }", "effects.shadows.steps must be a whole number 1..=1024"),
            ("shadows = { update_budget = 0 }", "effects.shadows.update_budget = 0 is outside 1..=64"),
            ("shadows = { softness_deg = -1 }", "effects.shadows.softness_deg = -1 is outside"),
            ("atmosphere = { visibility_km = 0 }", "effects.atmosphere.visibility_km = 0 is outside"),
            ("atmosphere = { haze_color = [1, 2, 0] }", "effects.atmosphere.haze_color = [1.0, 2.0, 0.0]: a share"),
            ("atmosphere = { sun_g = 1 }", "effects.atmosphere.sun_g = 1 is outside"),
            ("cliff_meshes = { radius_m = 3000 }", "effects.cliff_meshes.radius_m = 3000 is outside"),
            ("cliff_meshes = { radius_m = 1000, cell_m = 1 }", "effects.cliff_meshes: radius_m 1000 over cell_m 1"),
            ("cliff_meshes = { seed = 1 }", "unknown parameter effects.cliff_meshes.seed"),
        ] {
            let e = parse(text).unwrap_err().to_string();
            assert!(e.contains(key) && !e.contains('\n'), "{text}: {e}");
        }
    }
}

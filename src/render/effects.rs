//! Scene effects: what a scene asks the renderer to simulate. Each effect is
//! on or off with its parameters; the renderer builds pipelines, resources
//! and passes only for effects that are on (static gating), and a world
//! lacking an effect's data switches it off with a reason instead of paying
//! for an idle path. Scene files name them in an `[effects]` table:
//!
//! ```toml
//! [effects]
//! holes = true                          # a bool ...
//! lighting = { sun_elevation_deg = 25 } # ... or a table (enabled = true implied)
//! [effects.splat]
//! enabled = false
//! materials = "materials.toml"          # files are relative to the scene file
//! ```

use crate::error::{Error, Result};
use crate::passes::sun_shadows::{ShadowParams, MAX_UPDATE_BUDGET};
use crate::render::assets::AssetParams;
use crate::render::atmosphere::AtmosphereParams;
use crate::render::cliff_meshes::CliffMeshParams;
use crate::render::grass::GrassParams;
use crate::render::shading::ShadeRules;
use crate::render::tonemap::Tonemap;
use crate::render::view::Lighting;
use crate::render::virtual_texture::VtParams;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Every effect a scene can name, in report order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Effect {
    /// Hole regions and the trimmed world edge: the hole stage of
    /// `cull_patches`, its hole list and the `terrain_holes` draw.
    Holes,
    /// Backface-cone stage of `cull_patches` and the per-patch cone atlas.
    ConeCull,
    /// Two-phase Hi-Z occlusion culling: `hiz_build`, `cull_occluded`, the
    /// phase 2 draws, the visibility bits and the depth pyramid.
    Occlusion,
    /// Tri-planar cliff shading.
    Cliffs,
    /// Procedural cliff meshes near the camera (render/cliff_meshes.rs):
    /// `cliff_mesh_build` and the `cliff_meshes` draw into the geometry
    /// pass, shaded by the cliff flavours (needs `cliffs`).
    CliffMeshes,
    /// Detail materials from the splat map.
    Splat,
    /// Adaptive virtual texturing (seed 001): the splat blend cached in
    /// pages (`vt_update`, `vt_pages`, `vt_feedback`) and the
    /// virtual-texture flavour of `gbuffer_tiles` in place of splat's
    /// (needs `splat`'s materials).
    VirtualTexture,
    /// Sun and sky lighting of the output (the normal atlas); off, the
    /// output is unlit albedo.
    Lighting,
    /// Sector data each frame, for `TerrainQuery` (height, normal and
    /// material at any point, on the GPU).
    Queries,
    /// Decals (`RendererOptions::decals`, a scene's `[[decals]]`) blended
    /// into the virtual texture's pages by `vt_pages`' DECALS variant
    /// (needs `virtual_texture`).
    Decals,
    /// GPU grass (render/grass): `grass_pigment`, `grass_place` and the
    /// one indirect draw `grass_draw` into the G-buffer (needs `splat`'s
    /// material ids, in splat mode).
    Grass,
    /// The example assets grounded in the terrain (render/assets.rs): the
    /// `asset_draw` pass of a scene's `[[assets]]`, blended into the
    /// terrain by terrain_blend.glsl.
    Assets,
    /// Terrain sun shadows from the height field: the `sun_shadows` pass and
    /// its per-node shadow atlas, sampled by `lighting_resolve` (needs
    /// `lighting`).
    Shadows,
    /// Aerial perspective and sky: `lighting_resolve`'s ATMOSPHERE variant
    /// (needs `lighting`).
    Atmosphere,
}

impl Effect {
    pub const ALL: [Effect; 14] = [
        Effect::Holes,
        Effect::ConeCull,
        Effect::Occlusion,
        Effect::Cliffs,
        Effect::CliffMeshes,
        Effect::Splat,
        Effect::VirtualTexture,
        Effect::Lighting,
        Effect::Queries,
        Effect::Decals,
        Effect::Grass,
        Effect::Assets,
        Effect::Shadows,
        Effect::Atmosphere,
    ];

    /// The scene-file key.
    pub fn name(self) -> &'static str {
        match self {
            Effect::Holes => "holes",
            Effect::ConeCull => "cone_cull",
            Effect::Occlusion => "occlusion",
            Effect::Cliffs => "cliffs",
            Effect::CliffMeshes => "cliff_meshes",
            Effect::Splat => "splat",
            Effect::VirtualTexture => "virtual_texture",
            Effect::Lighting => "lighting",
            Effect::Queries => "queries",
            Effect::Decals => "decals",
            Effect::Grass => "grass",
            Effect::Assets => "assets",
            Effect::Shadows => "shadows",
            Effect::Atmosphere => "atmosphere",
        }
    }

    pub fn from_name(name: &str) -> Option<Effect> {
        Effect::ALL.into_iter().find(|e| e.name() == name)
    }

    /// On when a scene does not name it.
    pub fn default_on(self) -> bool {
        matches!(self, Effect::Holes | Effect::ConeCull | Effect::Occlusion | Effect::Lighting)
    }

    /// Why this version cannot run it, for effects not implemented yet: a
    /// scene may ask for them (and is checked), the report says they are off.
    pub fn unavailable(self) -> Option<&'static str> {
        match self {
            Effect::Grass
            | Effect::CliffMeshes
            | Effect::Assets
            | Effect::Decals
            | Effect::VirtualTexture
            | Effect::Holes
            | Effect::ConeCull
            | Effect::Occlusion
            | Effect::Lighting
            | Effect::Queries
            | Effect::Cliffs
            | Effect::Splat
            | Effect::Shadows
            | Effect::Atmosphere => None,
        }
    }

    /// Parameter names a table may give besides `enabled`.
    fn parameters(self) -> &'static [&'static str] {
        match self {
            Effect::Lighting => &[
                "sun_azimuth_deg",
                "sun_elevation_deg",
                "sun_color",
                "sky_color",
                "clay_albedo",
                "tonemap",
                "exposure_ev",
            ],
            Effect::Cliffs => &["slope_deg", "band_deg", "near_far_m", "stochastic", "hash_seed"],
            Effect::Splat => &["materials", "far_start_m", "far_band_m"],
            Effect::VirtualTexture => &["cache_mb", "pages_per_frame", "region_m", "indirection"],
            Effect::Grass => &GrassParams::PARAMETERS,
            Effect::Assets => &["blend_height_m"],
            Effect::CliffMeshes => &CliffMeshParams::PARAMETERS,
            Effect::Shadows => &["resolution", "steps", "update_budget", "softness_deg", "reach_m"],
            Effect::Atmosphere => {
                &["visibility_km", "scale_height_m", "haze_color", "sun_g", "zenith_color", "air_depth"]
            }
            _ => &[],
        }
    }
}

/// Which near material flavour the `splat` effect builds (scene
/// `[materials] mode`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MaterialsMode {
    /// Far Cry 5's splat map: material ids blended by height, cliffs
    /// tri-planar in their own flavours.
    #[default]
    Splat,
    /// REDengine 3's control map (seed 004): a background and an overlay
    /// texture per texel, blended by slope; the background is tri-planar,
    /// so the cliff flavours are not built.
    ControlMap,
}

impl MaterialsMode {
    pub fn name(self) -> &'static str {
        match self {
            MaterialsMode::Splat => "splat",
            MaterialsMode::ControlMap => "control_map",
        }
    }
}

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
}

/// Effects a built renderer switches off for a frame without rebuilding
/// anything (`TerrainRenderer::switches`; `vista view`'s toggles). Off:
/// - `holes`: `cull_patches` treats every patch as solid (holes and the
///   trimmed edge drawn filled) and the `terrain_holes` draws are skipped;
/// - `splat`, `cliffs`: their flavours leave the frame's allowed set, so
///   the classification never picks them and their tile variants draw
///   nothing;
/// - `lighting`: the output is unlit albedo (which also takes `shadows`
///   and `atmosphere` off);
/// - `shadows`: `sun_shadows` is skipped; `atmosphere`: no fog or sky.
///
/// The lighting uses the variant without what is off (made the first
/// time it is asked for). The culling stages switch the same way through
/// `CullStages`. Switching on an effect the renderer did not build does
/// nothing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameSwitches {
    pub holes: bool,
    pub cliffs: bool,
    pub splat: bool,
    pub lighting: bool,
    pub shadows: bool,
    pub atmosphere: bool,
}

impl Default for FrameSwitches {
    fn default() -> Self {
        FrameSwitches { holes: true, cliffs: true, splat: true, lighting: true, shadows: true, atmosphere: true }
    }
}

impl FrameSwitches {
    /// The effects a frame can switch off, in `Effect::ALL` order.
    pub const SWITCHABLE: [Effect; 6] =
        [Effect::Holes, Effect::Cliffs, Effect::Splat, Effect::Lighting, Effect::Shadows, Effect::Atmosphere];

    /// The switch of `effect` (None: not switchable per frame).
    pub fn get_mut(&mut self, effect: Effect) -> Option<&mut bool> {
        Some(match effect {
            Effect::Holes => &mut self.holes,
            Effect::Cliffs => &mut self.cliffs,
            Effect::Splat => &mut self.splat,
            Effect::Lighting => &mut self.lighting,
            Effect::Shadows => &mut self.shadows,
            Effect::Atmosphere => &mut self.atmosphere,
            _ => return None,
        })
    }

    /// Whether `effect` runs this frame as far as the switches go: its own
    /// switch, and for shadows and the atmosphere also `lighting`'s.
    pub fn on(&self, effect: Effect) -> bool {
        let mut copy = *self;
        let own = copy.get_mut(effect).is_none_or(|on| *on);
        own && (self.lighting || !matches!(effect, Effect::Shadows | Effect::Atmosphere))
    }
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

    /// Reads a scene's `[effects]` table; files it names are resolved
    /// against `base` (the scene file's folder) and must exist. Errors are
    /// one line naming the key (`effects.lighting.sun_color: ...`).
    pub fn from_toml(table: &toml::Table, base: &Path) -> Result<Effects> {
        let mut fx = Effects::default();
        for (key, value) in table {
            let Some(effect) = Effect::from_name(key) else {
                let known: Vec<&str> = Effect::ALL.iter().map(|e| e.name()).collect();
                return Err(bad(format!("unknown effect effects.{key} (known: {})", known.join(", "))));
            };
            match value {
                toml::Value::Boolean(on) => fx.set(effect, *on),
                toml::Value::Table(t) => fx.read_table(effect, t, base)?,
                other => {
                    return Err(bad(format!(
                        "effects.{key} must be true, false or a table of parameters, not {}",
                        type_name(other)
                    )))
                }
            }
        }
        Ok(fx)
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

    fn read_table(&mut self, effect: Effect, t: &toml::Table, base: &Path) -> Result<()> {
        let name = effect.name();
        let mut on = true;
        for (k, v) in t {
            let key = format!("effects.{name}.{k}");
            if k != "enabled" && !effect.parameters().contains(&k.as_str()) {
                let mut known = vec!["enabled"];
                known.extend(effect.parameters());
                return Err(bad(format!("unknown parameter {key} (known: {})", known.join(", "))));
            }
            match k.as_str() {
                "enabled" => on = v.as_bool().ok_or_else(|| wrong(&key, "true or false", v))?,
                _ if effect == Effect::Grass => self.grass.read(&key, k, v)?,
                _ if effect == Effect::CliffMeshes => self.cliff_meshes.read(&key, k, v)?,
                "sun_azimuth_deg" => self.lighting.sun_azimuth_deg = number(&key, v, -360.0, 360.0)?,
                "sun_elevation_deg" => self.lighting.sun_elevation_deg = number(&key, v, -90.0, 90.0)?,
                "sun_color" => self.lighting.sun_color = colour(&key, v)?,
                "sky_color" => self.lighting.sky_color = colour(&key, v)?,
                // Zero would read as "off" on the GPU: the range starts above it.
                "clay_albedo" => self.lighting.clay_albedo = Some(number(&key, v, 1e-3, 1.0)? as f32),
                "tonemap" => {
                    let names: Vec<&str> = Tonemap::ALL.iter().map(|t| t.name()).collect();
                    let expected = format!("one of {}", names.join(", "));
                    let name = v.as_str().ok_or_else(|| wrong(&key, &expected, v))?;
                    self.lighting.tonemap = Tonemap::from_name(name)
                        .ok_or_else(|| bad(format!("{key} = {name:?} is not a tonemapper ({expected})")))?;
                }
                // 2^20 either way keeps the exposed image finite in f32.
                "exposure_ev" => self.lighting.exposure_ev = Some(number(&key, v, -20.0, 20.0)? as f32),
                "slope_deg" => self.shade.cliff_slope_deg = number(&key, v, 0.0, 90.0)? as f32,
                "band_deg" => self.shade.cliff_band_deg = number(&key, v, 0.0, 45.0)? as f32,
                "near_far_m" => {
                    let m = number(&key, v, 0.0, 1e6)? as f32;
                    self.shade.cliff_split_start_m = m;
                    self.shade.cliff_split_end_m = m * 5.0 / 3.0;
                }
                "stochastic" => self.shade.stochastic = v.as_bool().ok_or_else(|| wrong(&key, "true or false", v))?,
                "hash_seed" => {
                    let seed = v.as_integer().filter(|s| (0..=i64::from(u32::MAX)).contains(s));
                    self.shade.hash_seed = seed.ok_or_else(|| wrong(&key, "a whole number 0..=4294967295", v))? as u32;
                }
                "far_start_m" => {
                    let band = self.shade.far_end_m - self.shade.far_start_m;
                    self.shade.far_start_m = number(&key, v, 0.0, 1e7)? as f32;
                    self.shade.far_end_m = self.shade.far_start_m + band;
                }
                "far_band_m" => self.shade.far_end_m = self.shade.far_start_m + number(&key, v, 1.0, 1e7)? as f32,
                "cache_mb" => self.virtual_texture.cache_mb = whole(&key, v, 1, 4096)?,
                "pages_per_frame" => {
                    let max = i64::from(crate::shaders::consts::VT_MAX_JOBS);
                    self.virtual_texture.pages_per_frame = whole(&key, v, 1, max)?;
                }
                "region_m" => self.virtual_texture.region_m = number(&key, v, 1.0, 1e5)?,
                "indirection" => {
                    let side = whole(&key, v, 64, 2048)?;
                    if !side.is_power_of_two() {
                        return Err(bad(format!("{key} = {side}: the indirection's side must be a power of two")));
                    }
                    self.virtual_texture.indirection = side;
                }
                "resolution" => {
                    let max = i64::from(crate::shaders::consts::SUN_SHADOW_MAX_SIDE);
                    self.shadows.resolution = whole(&key, v, 2, max)?;
                }
                "steps" => self.shadows.steps = whole(&key, v, 1, 1024)?,
                "update_budget" => self.shadows.update_budget = whole(&key, v, 1, i64::from(MAX_UPDATE_BUDGET))?,
                "softness_deg" => self.shadows.softness_deg = number(&key, v, 0.0, 10.0)? as f32,
                "reach_m" => self.shadows.reach_m = number(&key, v, 1.0, 1e7)? as f32,
                "visibility_km" => self.atmosphere.visibility_km = number(&key, v, 0.01, 1e5)? as f32,
                "scale_height_m" => self.atmosphere.scale_height_m = number(&key, v, 1.0, 1e5)? as f32,
                "haze_color" => {
                    let c = colour(&key, v)?;
                    if c.iter().any(|&x| x > 1.0) {
                        return Err(bad(format!("{key} = {c:?}: a share of the light scattered, each 0..=1")));
                    }
                    self.atmosphere.haze_color = c;
                }
                "sun_g" => self.atmosphere.sun_g = number(&key, v, 0.0, 0.95)? as f32,
                "zenith_color" => self.atmosphere.zenith_color = colour(&key, v)?,
                "air_depth" => self.atmosphere.air_depth = number(&key, v, 0.0, 10.0)? as f32,
                "blend_height_m" => self.assets.blend_height_m = number(&key, v, 0.0, 100.0)? as f32,
                "materials" => self.splat_materials = Some(file(&key, v, base)?),
                _ => unreachable!("{key} is in the parameter list but not read"),
            }
        }
        if effect == Effect::Grass {
            self.grass.validate()?;
        }
        if effect == Effect::CliffMeshes {
            self.cliff_meshes.validate()?;
        }
        self.set(effect, on);
        Ok(())
    }
}

fn bad(msg: String) -> Error {
    Error::Scene(msg)
}

fn type_name(v: &toml::Value) -> &'static str {
    match v {
        toml::Value::String(_) => "a string",
        toml::Value::Integer(_) => "an integer",
        toml::Value::Float(_) => "a float",
        toml::Value::Boolean(_) => "a boolean",
        toml::Value::Datetime(_) => "a date",
        toml::Value::Array(_) => "an array",
        toml::Value::Table(_) => "a table",
    }
}

pub(super) fn wrong(key: &str, want: &str, v: &toml::Value) -> Error {
    bad(format!("{key} must be {want}, not {}", type_name(v)))
}

pub(super) fn number(key: &str, v: &toml::Value, lo: f64, hi: f64) -> Result<f64> {
    let x = v.as_float().or(v.as_integer().map(|i| i as f64));
    match x {
        Some(x) if x.is_finite() && (lo..=hi).contains(&x) => Ok(x),
        Some(x) => Err(bad(format!("{key} = {x} is outside {lo}..={hi}"))),
        None => Err(wrong(key, "a number", v)),
    }
}

fn whole(key: &str, v: &toml::Value, lo: i64, hi: i64) -> Result<u32> {
    let n = v.as_integer().filter(|n| (lo..=hi).contains(n));
    Ok(n.ok_or_else(|| match v.as_integer() {
        Some(n) => bad(format!("{key} = {n} is outside {lo}..={hi}")),
        None => wrong(key, &format!("a whole number {lo}..={hi}"), v),
    })? as u32)
}

pub(super) fn colour(key: &str, v: &toml::Value) -> Result<[f32; 3]> {
    let want = "an array of 3 non-negative numbers (linear RGB)";
    let arr = v.as_array().filter(|a| a.len() == 3).ok_or_else(|| wrong(key, want, v))?;
    let mut out = [0.0f32; 3];
    for (o, x) in out.iter_mut().zip(arr) {
        let x = x.as_float().or(x.as_integer().map(|i| i as f64)).filter(|x| x.is_finite() && *x >= 0.0);
        *o = x.ok_or_else(|| wrong(key, want, v))? as f32;
    }
    Ok(out)
}

fn file(key: &str, v: &toml::Value, base: &Path) -> Result<PathBuf> {
    let s = v.as_str().ok_or_else(|| wrong(key, "a file path (string)", v))?;
    let path = crate::world::resolve_relative(base, Path::new(s));
    if !path.is_file() {
        return Err(bad(format!("{key}: file {} does not exist", path.display())));
    }
    Ok(path)
}

/// What became of one effect: requested or not, on or off, and why.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EffectDecision {
    pub effect: Effect,
    pub requested: bool,
    pub on: bool,
    pub reason: String,
}

/// What the world holds that effects need; `None` when it has the data,
/// else why not.
#[derive(Debug, Clone, Default)]
pub struct WorldContent {
    pub holes_missing: Option<String>,
    pub holes_present: String,
    /// Decals given to the renderer.
    pub decals: usize,
    /// Assets given to the renderer (effect assets).
    pub assets: usize,
    /// Output `gbuffer`: the engine lights the frame, so vista's lighting
    /// effects have nothing to change.
    pub engine_lights: bool,
}

/// Decides every effect: requested and implemented and backed by the
/// world's data means on. `force` (tests only) keeps an effect on although
/// the world lacks its data, to show its path changes nothing there.
pub fn decide(fx: &Effects, content: &WorldContent, force: bool) -> Vec<EffectDecision> {
    let mut decisions = Effect::ALL
        .into_iter()
        .map(|effect| {
            let requested = fx.is_on(effect);
            let how = if fx.is_named(effect) { "" } else { " (default)" };
            let (on, reason) = if !requested {
                (false, format!("not requested{how}"))
            } else if let Some(why) = effect.unavailable() {
                (false, format!("requested, but {why}"))
            } else {
                match (effect, &content.holes_missing) {
                    (Effect::Lighting | Effect::Shadows | Effect::Atmosphere, _) if content.engine_lights => {
                        (false, "requested, but output gbuffer leaves the lighting to the engine".into())
                    }
                    // Both change the lit image, which lighting off does not make.
                    (Effect::Shadows | Effect::Atmosphere, _) if !fx.is_on(Effect::Lighting) => {
                        (false, "requested, but it changes the lit image and effect lighting is off".into())
                    }
                    (Effect::Cliffs, _) if fx.materials == MaterialsMode::ControlMap => (
                        false,
                        "requested, but the control-map materials shade slopes with their tri-planar background \
                         ([materials] mode = \"control_map\")"
                            .into(),
                    ),
                    (Effect::VirtualTexture, _) if fx.materials == MaterialsMode::ControlMap => (
                        false,
                        "requested, but its pages cache the splat blend and the materials are the control map's \
                         ([materials] mode = \"control_map\")"
                            .into(),
                    ),
                    (Effect::VirtualTexture, _) if !fx.is_on(Effect::Splat) => {
                        (false, "requested, but its pages cache the splat materials and effect splat is off".into())
                    }
                    (Effect::Grass, _) if fx.materials == MaterialsMode::ControlMap => (
                        false,
                        "requested, but its rules are by splat material id and the materials are the control map's \
                         ([materials] mode = \"control_map\")"
                            .into(),
                    ),
                    (Effect::Grass, _) if !fx.is_on(Effect::Splat) => {
                        (false, "requested, but it grows by the splat material ids and effect splat is off".into())
                    }
                    (Effect::Grass, _) if !fx.grass.grows() => {
                        (false, "requested, but no material grows grass (effects.grass.density)".into())
                    }
                    (Effect::CliffMeshes, _)
                        if fx.materials == MaterialsMode::ControlMap || !fx.is_on(Effect::Cliffs) =>
                    {
                        (false, "requested, but the cliff flavours shade the meshes and effect cliffs is off".into())
                    }
                    (Effect::Assets, _) if content.assets == 0 => {
                        (false, "requested, but the scene has no assets ([[assets]])".into())
                    }
                    (Effect::Decals, _) if content.decals == 0 => {
                        (false, "requested, but the scene has no decals ([[decals]])".into())
                    }
                    (Effect::Splat, _) if fx.materials == MaterialsMode::ControlMap => {
                        (true, format!("requested{how}: the control-map flavour ([materials] mode = \"control_map\")"))
                    }
                    (Effect::Holes, Some(why)) if force => (true, format!("forced on (test override) although {why}")),
                    (Effect::Holes, Some(why)) => (false, format!("requested, but {why}")),
                    (Effect::Holes, None) => (true, format!("requested{how}: {}", content.holes_present)),
                    _ => (true, format!("requested{how}")),
                }
            };
            EffectDecision { effect, requested, on, reason }
        })
        .collect::<Vec<_>>();
    decals_need_pages(&mut decisions);
    decisions
}

/// Decals live in the virtual texture's pages: off with it, whatever
/// switched it off.
fn decals_need_pages(decisions: &mut [EffectDecision]) {
    let vt_on = decisions.iter().any(|d| d.effect == Effect::VirtualTexture && d.on);
    if let Some(d) = decisions.iter_mut().find(|d| d.effect == Effect::Decals && d.on && !vt_on) {
        d.on = false;
        d.reason =
            "requested, but decals are drawn into the virtual texture's pages and effect virtual_texture is off".into();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Effects> {
        let t: toml::Table = toml::from_str(text).unwrap();
        Effects::from_toml(&t, Path::new("."))
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

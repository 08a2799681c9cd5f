//! The effects' names and what became of them: the vocabulary every floor
//! above shares (the scene parsing, each effect's folder, the pass graph,
//! the reports). Their parameters and decisions live in `crate::effects`.

use serde::Serialize;

/// Declares [`Effect`]: each effect's variant and scene-file key, once.
macro_rules! effects {
    ($($(#[$doc:meta])* $variant:ident = $name:literal,)*) => {
        /// Every effect a scene can name, in report order (which is also
        /// the order their built parts record at each point of the frame).
        #[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
        #[serde(rename_all = "snake_case")]
        pub enum Effect {
            $($(#[$doc])* $variant,)*
        }

        impl Effect {
            pub const ALL: [Effect; [$($name),*].len()] = [$(Effect::$variant),*];

            /// The scene-file key.
            pub fn name(self) -> &'static str {
                match self {
                    $(Effect::$variant => $name,)*
                }
            }
        }
    };
}

// One line an effect (and its doc): adding an effect adds its line here.
effects! {
    /// Hole regions and the trimmed world edge: the hole stage of
    /// `cull_patches`, its hole list and the `terrain_holes` draw.
    Holes = "holes",
    /// Backface-cone stage of `cull_patches` and the per-patch cone atlas.
    ConeCull = "cone_cull",
    /// Two-phase Hi-Z occlusion culling: `hiz_build`, `cull_occluded`, the
    /// phase 2 draws, the visibility bits and the depth pyramid.
    Occlusion = "occlusion",
    /// Tri-planar cliff shading.
    Cliffs = "cliffs",
    /// Procedural cliff meshes near the camera (effects/cliff_meshes):
    /// `cliff_mesh_build` and the `cliff_meshes` draw into the geometry
    /// pass, shaded by the cliff flavours (needs `cliffs`).
    CliffMeshes = "cliff_meshes",
    /// Detail materials from the splat map.
    Splat = "splat",
    /// Adaptive virtual texturing (seed 001): the splat blend cached in
    /// pages (`vt_update`, `vt_pages`, `vt_feedback`) and the
    /// virtual-texture flavour of `gbuffer_tiles` in place of splat's
    /// (needs `splat`'s materials).
    VirtualTexture = "virtual_texture",
    /// Sun and sky lighting of the output (the normal atlas); off, the
    /// output is unlit albedo.
    Lighting = "lighting",
    /// Sector data each frame, for `TerrainQuery` (height, normal and
    /// material at any point, on the GPU).
    Queries = "queries",
    /// Decals (`RendererOptions::decals`, a scene's `[[decals]]`) blended
    /// into the virtual texture's pages by `vt_pages`' DECALS variant
    /// (needs `virtual_texture`).
    Decals = "decals",
    /// The example assets grounded in the terrain (effects/assets): the
    /// `asset_draw` pass of a scene's `[[assets]]`, blended into the
    /// terrain by terrain_blend.glsl.
    Assets = "assets",
    /// GPU grass (effects/grass): `grass_pigment`, `grass_place` and the
    /// one indirect draw `grass_draw` into the G-buffer (needs `splat`'s
    /// material ids, in splat mode).
    Grass = "grass",
    /// Terrain sun shadows from the height field: the `sun_shadows` pass and
    /// its per-node shadow atlas, sampled by `lighting_resolve` (needs
    /// `lighting`).
    Shadows = "shadows",
    /// Aerial perspective and sky: `lighting_resolve`'s ATMOSPHERE variant
    /// (needs `lighting`).
    Atmosphere = "atmosphere",
    /// Trees and bushes of a `vista vegetate` folder (effects/vegetation):
    /// `vegetation_cull` into six indexed indirect draws, `vegetation_draw`
    /// into the G-buffer.
    Vegetation = "vegetation",
}

impl Effect {
    pub fn from_name(name: &str) -> Option<Effect> {
        Effect::ALL.into_iter().find(|e| e.name() == name)
    }

    /// On when a scene does not name it.
    pub fn default_on(self) -> bool {
        matches!(self, Effect::Holes | Effect::ConeCull | Effect::Occlusion | Effect::Lighting)
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

/// What became of one effect: requested or not, on or off, and why.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EffectDecision {
    pub effect: Effect,
    pub requested: bool,
    pub on: bool,
    pub reason: String,
}

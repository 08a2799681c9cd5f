//! Scene files (TOML): which terrain, its geometry, holes and the effects
//! the scene calls for (`vista::effects` documents each).
//!
//! ```toml
//! [world]
//! source = "procedural"        # or a PNG16 / EXR / GeoTIFF path, relative to this file
//! extent = 10240               # metres; or [x, y]
//! height_range = [0, 1600]
//! clamp_heights = false        # EXR only: clamp data outside height_range, not fail
//! spacing = 0.5
//! lods = 6
//! seed = 1
//! terraces = false             # procedural only: terraced cliffs over the eroded ground
//! origin = [340000, 5080000]   # where the south-west corner lies (e.g. UTM E, N);
//!                              # cameras and holes are then given in these coordinates
//!
//! [[holes]]
//! circle = [5000, 5000, 20]    # x, y, radius
//! [[holes]]
//! polygon = [[0, 0], [10, 0], [5, 8]]
//!
//! [effects]                    # each: true / false, or a table of parameters
//! holes = true
//! lighting = { sun_elevation_deg = 25 }
//!
//! [[stamps]]                   # height maps pasted in order on top of the source
//! source = "crater.png"        # PNG16 (0..65535) or EXR (its own min..max), as 0..1
//! center = [1024, 1024]        # metres (in the origin's coordinates, like holes)
//! size = 300                   # metres, the stamp's side
//! rotation_deg = 0             # counter-clockwise
//! height = 80                  # metres spanned by the map's 0..1
//! offset = 0                   # metres added to the stamp's heights
//! blend = "add"                # replace | add | max | min (optional: replace)
//! falloff = 20                 # metres inside the edge over which it fades in
//! control_map = "crater-control.png"  # optional (control-map mode): its words where it weighs >= 0.5
//! vegetation = "crater-veg"    # optional: its own `vista vegetate` folder, pasted with it
//!
//! [[decals]]                   # drawn into the virtual texture's pages, in order (effect decals)
//! texture = "decals/paint.png" # RGBA image (alpha: coverage), resampled to 256 x 256
//! quad = { center = [1000, 1200], size = [12, 8], rotation_deg = 30 }
//! opacity = 1                  # times the texture's alpha (default 1)
//! roughness = 0.3              # optional: blended towards (else the ground's)
//! displace_m = 0.5             # optional (quads): a displacement decal, its mesh raised by alpha x this
//! [[decals]]
//! texture = "decals/road.png"  # u across the road, v along it
//! road = { points = [[900, 1100], [1000, 1150], [1040, 1260]], width = 6, repeat = 12 }
//! [[assets]]                   # the example assets, blended into the ground (effect assets)
//! kind = "rock"                # or "trunk"
//! at = [1010, 1190]
//! scale = 1.5                  # optional (1)
//! yaw_deg = 30                 # optional (0)
//!
//! [materials]                  # the near material flavour (effect splat)
//! mode = "control_map"         # or "splat" (the default): REDengine 3's control map
//! control_map = "control.png"  # 16-bit PNG over the world (else made from the material rules)
//! tighten = 0.3                # tri-planar tighten factor of the control-map background
//!
//! [material_rules]             # where the bake puts each material (defaults: the Alps)
//! rock_slope_deg = 40          # steeper is bare rock
//! scree_slope_deg = 30         # steeper (and not rock) is scree
//! snow_line_m = 2800           # higher (and not rock) is snow
//! sea_level_m = 0              # lower is sand (sea floor)
//! beach_height_m = 2           # gentle ground this far above the sea is sand
//!
//! [vegetation]                  # `vista vegetate` (every key optional; docs/vegetation.md)
//! cell_m = 5                   # generator cell: at most one tree or bush each
//! iterations = 32              # resource flow steps (a cell each)
//! latitude_deg = 46            # the sun's day: latitude and day of the year
//! day_of_year = 172
//! [[vegetation.types]]         # replaces the default types (spruce, pine, juniper, meadow)
//! name = "pine"
//! kind = "tree"                # tree | bush | grass (grass: an occurrence map)
//! slope_deg = [0, 38]          # what it tolerates: slope, altitude (optional), sun share,
//! altitude_m = [0, 2200]       # least resource
//! sun = [0.6, 1.0]
//! resource = 0.6
//! ideal_resource = 1.5         # where it grows largest
//! ideal_sun = 0.95
//! [[vegetation.brushes]]       # types with densities and scales, on materials
//! name = "forest"
//! materials = ["grass"]
//! types = [{ type = "pine", density = 0.3, scale = [0.6, 1.2], scale_var = 0.15 }]
//! mask_map = "mask.png"        # (in [vegetation]) grey over the world: white keeps it out
//! [[vegetation_masks]]         # shapes nothing grows in (as holes); and decals with
//! circle = [5120, 3300, 40]    # clear_vegetation = true keep their footprint clear
//! ```

use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _, Result};
use serde::Deserialize;
use vista::effects::assets::{Asset, AssetKind};
use vista::effects::virtual_texture::decals::{Decal, DecalShape};
use vista::render::Effects;
use vista::world::vegetation::VegetationParams;
use vista::world::{Hole, MaterialRules, StampBlend, StampPlacement};

#[derive(Debug, Default)]
pub struct Scene {
    pub world: SceneWorld,
    holes: Vec<SceneHole>,
    stamps: Vec<SceneStamp>,
    decals: Vec<SceneDecal>,
    assets: Vec<SceneAsset>,
    pub effects: Effects,
    pub material_rules: MaterialRules,
    /// The `[vegetation]` table (`vista vegetate`), checked; its mask map
    /// resolved against the scene's folder.
    pub vegetation: Option<VegetationParams>,
    vegetation_masks: Vec<SceneHole>,
    /// For error messages.
    path: PathBuf,
}

/// Unknown keys are errors so a typo ("extents") cannot be silently ignored.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    #[serde(default)]
    world: SceneWorld,
    #[serde(default)]
    holes: Vec<SceneHole>,
    #[serde(default)]
    stamps: Vec<SceneStamp>,
    #[serde(default)]
    decals: Vec<SceneDecal>,
    #[serde(default)]
    assets: Vec<SceneAsset>,
    #[serde(default)]
    effects: toml::Table,
    #[serde(default)]
    materials: toml::Table,
    #[serde(default)]
    material_rules: MaterialRules,
    vegetation: Option<VegetationParams>,
    #[serde(default)]
    vegetation_masks: Vec<SceneHole>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneWorld {
    #[serde(default)]
    pub source: SceneSource,
    pub extent: Option<Extent>,
    pub height_range: Option<[f32; 2]>,
    /// Clamp EXR heights outside `height_range` instead of failing.
    #[serde(default)]
    pub clamp_heights: bool,
    pub spacing: Option<f64>,
    pub lods: Option<u32>,
    pub seed: Option<u64>,
    /// The procedural world's terraced cliffs (off: only what erosion shapes).
    #[serde(default)]
    pub terraces: bool,
    /// Where the world's south-west corner lies in the coordinates cameras
    /// and holes are given in.
    pub origin: Option<[f64; 2]>,
}

#[derive(Debug, Default, Clone, PartialEq)]
pub enum SceneSource {
    #[default]
    Procedural,
    Path(PathBuf),
}

impl<'de> Deserialize<'de> for SceneSource {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        Ok(if s == "procedural" { SceneSource::Procedural } else { SceneSource::Path(s.into()) })
    }
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(untagged)]
pub enum Extent {
    Square(f64),
    Rect([f64; 2]),
}

impl Extent {
    pub fn xy(self) -> [f64; 2] {
        match self {
            Extent::Square(e) => [e, e],
            Extent::Rect(r) => r,
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneStamp {
    source: PathBuf,
    center: [f64; 2],
    size: f64,
    #[serde(default)]
    rotation_deg: f64,
    height: f64,
    #[serde(default)]
    offset: f64,
    /// Optional: `replace` (the map pasted as it is) unless given.
    #[serde(default = "replace")]
    blend: String,
    #[serde(default)]
    falloff: f64,
    /// Its own control map (16-bit PNG over its square), control-map mode.
    control_map: Option<PathBuf>,
    /// Its own `vista vegetate` folder (`vista vegetate` pastes it).
    vegetation: Option<PathBuf>,
}

/// A stamp of the scene: its map file (resolved) and where it goes, in the
/// user's coordinates.
#[derive(Debug, Clone)]
pub struct SceneStampSpec {
    pub source: PathBuf,
    pub placement: StampPlacement,
    /// Its own control map, resolved.
    pub control_map: Option<PathBuf>,
    /// Its own vegetation folder, resolved.
    pub vegetation: Option<PathBuf>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneDecal {
    texture: PathBuf,
    quad: Option<SceneQuad>,
    road: Option<SceneRoad>,
    #[serde(default = "full")]
    opacity: f32,
    roughness: Option<f32>,
    /// A displacement decal (quads): its mesh is raised this much where
    /// the texture's alpha is 1.
    displace_m: Option<f32>,
    /// `vista vegetate` grows nothing on its footprint (a road, a helipad).
    #[serde(default)]
    clear_vegetation: bool,
}

fn full() -> f32 {
    1.0
}

fn replace() -> String {
    "replace".to_string()
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneQuad {
    center: [f64; 2],
    size: [f64; 2],
    #[serde(default)]
    rotation_deg: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneRoad {
    points: Vec<[f64; 2]>,
    width: f64,
    repeat: f64,
}

/// The scene's decals, checked, relative to the world's corner: the
/// texture files (each once) and the decals, whose `texture` indexes them.
#[derive(Debug, Clone, Default)]
pub struct SceneDecals {
    pub textures: Vec<PathBuf>,
    pub decals: Vec<Decal>,
    /// Per decal: `clear_vegetation`.
    pub clear_vegetation: Vec<bool>,
}

/// One `[[assets]]` entry (effect assets).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneAsset {
    kind: String,
    at: [f64; 2],
    #[serde(default = "one")]
    scale: f64,
    #[serde(default)]
    yaw_deg: f64,
}

fn one() -> f64 {
    1.0
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneHole {
    circle: Option<[f64; 3]>,
    polygon: Option<Vec<[f64; 2]>>,
}

impl Scene {
    /// Reads and parses `path`; a relative `source` is resolved against the
    /// scene file's folder so scenes can travel with their height maps.
    pub fn load(path: &Path) -> Result<Scene> {
        if path.is_dir() {
            bail!("--scene {} is a directory, expected a scene file (.toml)", path.display());
        }
        if let Err(e) = vista::world::require_regular_file(path) {
            if e.kind() != std::io::ErrorKind::NotFound {
                bail!("--scene {} {e}: give a scene file (.toml)", path.display());
            }
        }
        let text = std::fs::read_to_string(path).with_context(|| format!("scene file {}", path.display()))?;
        let raw: RawScene = toml::from_str(&text).map_err(|e| {
            // toml's Display spans several lines (a source excerpt); one
            // line with the line number is enough.
            // Counted on the bytes: no string slicing, whatever span the parser reports.
            let line = e.span().map(|s| text.as_bytes()[..s.start.min(text.len())].split(|&b| b == b'\n').count());
            let at = line.map(|l| format!(":{l}")).unwrap_or_default();
            let source_line = line.and_then(|l| text.lines().nth(l - 1));
            let message = crate::scene_words::reword(e.message().trim(), source_line);
            anyhow::anyhow!("scene file {}{at}: {message}", path.display())
        })?;
        let mut world = raw.world;
        if let SceneSource::Path(p) = &world.source {
            if p.is_relative() {
                let dir = path.parent().unwrap_or(Path::new("."));
                world.source = SceneSource::Path(vista::world::resolve_relative(dir, p));
            }
        }
        let dir = path.parent().unwrap_or(Path::new("."));
        let mut effects =
            Effects::from_toml(&raw.effects, dir).map_err(|e| anyhow::anyhow!("scene file {}: {e}", path.display()))?;
        effects
            .read_materials(&raw.materials, dir)
            .map_err(|e| anyhow::anyhow!("scene file {}: {e}", path.display()))?;
        raw.material_rules.validate().map_err(|e| anyhow::anyhow!("scene file {}: {e}", path.display()))?;
        let mut vegetation = raw.vegetation;
        if let Some(v) = &mut vegetation {
            v.validate().map_err(|e| anyhow::anyhow!("scene file {}: {e}", path.display()))?;
            v.mask_map = v.mask_map.as_ref().map(|m| vista::world::resolve_relative(dir, m));
        }
        let mut decals = raw.decals;
        for d in &mut decals {
            d.texture = vista::world::resolve_relative(dir, &d.texture);
        }
        let mut stamps = raw.stamps;
        for st in &mut stamps {
            st.source = vista::world::resolve_relative(dir, &st.source);
            st.control_map = st.control_map.as_ref().map(|c| vista::world::resolve_relative(dir, c));
            st.vegetation = st.vegetation.as_ref().map(|c| vista::world::resolve_relative(dir, c));
        }
        Ok(Scene {
            world,
            holes: raw.holes,
            stamps,
            decals,
            assets: raw.assets,
            effects,
            material_rules: raw.material_rules,
            vegetation,
            vegetation_masks: raw.vegetation_masks,
            path: path.to_path_buf(),
        })
    }

    /// The stamps, in order, each checked (blend word, finite numbers, a
    /// positive size, a falloff within half of it).
    pub fn stamps(&self) -> Result<Vec<SceneStampSpec>> {
        let mut out = Vec::with_capacity(self.stamps.len());
        for (i, st) in self.stamps.iter().enumerate() {
            let at = format!("scene file {}: stamp {} ({})", self.path.display(), i + 1, st.source.display());
            let Some(blend) = StampBlend::from_name(&st.blend) else {
                let words: Vec<&str> = StampBlend::ALL.iter().map(|b| b.name()).collect();
                bail!("{at}: blend \"{}\" is not one of {}", st.blend, words.join(", "));
            };
            let placement = StampPlacement {
                center_m: st.center,
                size_m: st.size,
                rotation_deg: st.rotation_deg,
                height_m: st.height,
                offset_m: st.offset,
                blend,
                falloff_m: st.falloff,
            };
            placement.validate().map_err(|e| anyhow::anyhow!("{at}: {e}"))?;
            if st.control_map.is_some() && self.effects.materials != vista::render::MaterialsMode::ControlMap {
                bail!("{at}: control_map needs [materials] mode = \"control_map\"");
            }
            let (control_map, vegetation) = (st.control_map.clone(), st.vegetation.clone());
            out.push(SceneStampSpec { source: st.source.clone(), placement, control_map, vegetation });
        }
        Ok(out)
    }

    /// The decals, each checked (one shape, finite numbers, opacity and
    /// roughness in 0..=1), moved from the user's coordinates by `-origin_m`.
    pub fn decals(&self, origin_m: [f64; 2]) -> Result<SceneDecals> {
        let mut out = SceneDecals::default();
        for (i, d) in self.decals.iter().enumerate() {
            let at = format!("scene file {}: decal {}", self.path.display(), i + 1);
            let shape = match (&d.quad, &d.road) {
                (Some(q), None) => DecalShape::Quad {
                    center_m: q.center.into(),
                    size_m: q.size.into(),
                    rotation_deg: q.rotation_deg,
                },
                (None, Some(r)) => DecalShape::Road {
                    points_m: r.points.iter().map(|&p| p.into()).collect(),
                    width_m: r.width,
                    repeat_m: r.repeat,
                },
                _ => bail!("{at}: give exactly one of quad = {{ center, size, rotation_deg }} or road = {{ points, width, repeat }}"),
            };
            let texture = match out.textures.iter().position(|t| *t == d.texture) {
                Some(t) => t,
                None => {
                    out.textures.push(d.texture.clone());
                    out.textures.len() - 1
                }
            };
            let (opacity, roughness, displace_m) = (d.opacity, d.roughness, d.displace_m);
            let decal = Decal { shape, texture: texture as u32, opacity, roughness, displace_m };
            decal.check(out.textures.len()).map_err(|why| anyhow::anyhow!("{at}: {why}"))?;
            out.decals.push(decal.translated(-glam::DVec2::from(origin_m)));
            out.clear_vegetation.push(d.clear_vegetation);
        }
        Ok(out)
    }

    /// The assets, each checked (a known kind, finite numbers, a sane
    /// scale), moved from the user's coordinates by `-origin_m`.
    pub fn assets(&self, origin_m: [f64; 2]) -> Result<Vec<Asset>> {
        let mut out = Vec::with_capacity(self.assets.len());
        for (i, a) in self.assets.iter().enumerate() {
            let at = format!("scene file {}: asset {}", self.path.display(), i + 1);
            let Some(kind) = AssetKind::from_name(&a.kind) else {
                let words: Vec<&str> = AssetKind::ALL.iter().map(|k| k.name()).collect();
                bail!("{at}: kind \"{}\" is not one of {}", a.kind, words.join(", "));
            };
            let asset = Asset { kind, at_m: a.at, scale: a.scale, yaw_deg: a.yaw_deg };
            asset.check().map_err(|why| anyhow::anyhow!("{at}: {why}"))?;
            out.push(asset.relative_to(origin_m));
        }
        Ok(out)
    }

    /// The holes, each checked: exactly one shape, finite numbers, a
    /// positive radius, at least three polygon corners.
    pub fn holes(&self) -> Result<Vec<Hole>> {
        shapes(&self.holes, &format!("scene file {}: hole", self.path.display()))
    }

    /// The `[[vegetation_masks]]` (checked as holes are), in the user's
    /// coordinates.
    pub fn vegetation_masks(&self) -> Result<Vec<Hole>> {
        shapes(&self.vegetation_masks, &format!("scene file {}: vegetation mask", self.path.display()))
    }
}

/// Circles and polygons (holes, vegetation masks), each checked; `what`
/// names them in an error ("... hole 2: ...").
fn shapes(list: &[SceneHole], what: &str) -> Result<Vec<Hole>> {
    let at = |i: usize| format!("{what} {}", i + 1);
    let mut out = Vec::with_capacity(list.len());
    for (i, h) in list.iter().enumerate() {
        let hole = match (&h.circle, &h.polygon) {
            (Some([x, y, r]), None) => {
                if ![*x, *y, *r].iter().all(|v| v.is_finite()) || *r <= 0.0 {
                    bail!("{}: circle needs finite x, y and a positive radius", at(i));
                }
                Hole::Circle { center_m: [*x, *y], radius_m: *r }
            }
            (None, Some(pts)) => {
                if pts.len() < 3 || pts.iter().flatten().any(|v| !v.is_finite()) {
                    bail!("{}: polygon needs at least 3 corners of finite numbers", at(i));
                }
                Hole::Polygon(pts.clone())
            }
            _ => bail!("{}: give exactly one of circle = [x, y, r] or polygon = [[x, y], ...]", at(i)),
        };
        out.push(hole);
    }
    Ok(out)
}

#[cfg(test)]
#[path = "scene_tests.rs"]
mod tests;

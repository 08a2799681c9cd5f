//! The splat material table: the bake writes one material id (0..=255) per
//! splat texel, and the shader looks each id up in a 256-entry table that
//! says which layers of the detail texture arrays to sample and at what
//! scale and rotation. A material file (`[effects.splat] materials = ...`)
//! adds texture sets and overrides entries of the default table:
//!
//! ```toml
//! [textures]                       # texture sets by name
//! rock = "procedural:rock"         # or three PNG files, relative to the material file:
//! granite = { albedo = "granite_a.png", normal = "granite_n.png", height = "granite_h.png" }
//! [[material]]                     # overrides one entry of the default table
//! id = 1                           # 0..=255
//! texture = "granite"              # a set named above or a default one (grass, rock, snow, scree)
//! tiling_m = 8.0                   # metres per repeat, > 0
//! rotation_deg = 30.0
//! ```
//!
//! The default sets grass, rock, snow and scree are layers 0..=3; a set in
//! `[textures]` with one of their names replaces that layer (so a file can
//! retexture rock without touching the table), other sets follow in name
//! order (`toml::Table` is sorted: the file's order is not kept).
//!
//! A control-map world (scene `[materials] mode = "control_map"`) indexes a
//! second, 32-entry table with its control words' 5-bit texture indices;
//! each entry carries seed 004's per-texture parameters:
//!
//! ```toml
//! [[control_texture]]
//! index = 5                        # 0..=31
//! texture = "granite"
//! tiling_m = 6.0
//! threshold = 0.4                  # as background: its own slope threshold (0 flat .. 1 vertical)
//! sharpness = 0.1                  # as overlay: the slope span of its blend into the background
//! slope_damp = 1.0                 # as background: flat ground flattens its normal for the slope test (0..1)
//! normal_damp = 0.8                # as background: how much of the overlay's normal is kept (0..1)
//! ```

pub mod detail_textures;
pub mod frame;
pub mod gpu;
pub mod kinds;
mod parse;
mod procedural;

use parse::{one_line, parse};

use crate::error::{Error, Result};
use crate::world::{CONTROL_TEXTURES, SLOPE_THRESHOLDS, UV_SCALES};
use std::path::{Path, PathBuf};

/// Entries in the table: every value a u8 splat texel can hold, so the
/// shader indexes it without a bounds check.
pub const MATERIAL_COUNT: usize = 256;

/// Most texture sets (layers of each detail array). Layer indices are packed
/// in 8 bits on the GPU; 64 layers of 2048² RGBA8 albedo with mips are
/// already 1.4 GB, far beyond any real budget.
pub const MAX_TEXTURE_SETS: usize = 64;

/// Built-in generated textures (see `detail_textures`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ProceduralKind {
    Grass,
    Rock,
    Snow,
    Scree,
    Dirt,
}

impl ProceduralKind {
    pub const ALL: [ProceduralKind; 5] = [
        ProceduralKind::Grass,
        ProceduralKind::Rock,
        ProceduralKind::Snow,
        ProceduralKind::Scree,
        ProceduralKind::Dirt,
    ];

    pub fn name(self) -> &'static str {
        match self {
            ProceduralKind::Grass => "grass",
            ProceduralKind::Rock => "rock",
            ProceduralKind::Snow => "snow",
            ProceduralKind::Scree => "scree",
            ProceduralKind::Dirt => "dirt",
        }
    }

    pub fn from_name(name: &str) -> Option<ProceduralKind> {
        ProceduralKind::ALL.into_iter().find(|k| k.name() == name)
    }
}

/// Where a texture set's three images come from.
#[derive(Debug, Clone, PartialEq)]
pub enum TextureSource {
    Procedural(ProceduralKind),
    /// PNG files (checked to exist when parsed, decoded when built). Normal:
    /// rgb = tangent-space normal, a = roughness; height: luminance.
    Files {
        albedo: PathBuf,
        normal: PathBuf,
        height: PathBuf,
    },
}

/// One layer in each detail texture array (albedo, normal + roughness,
/// height).
#[derive(Debug, Clone, PartialEq)]
pub struct TextureSet {
    pub name: String,
    pub source: TextureSource,
}

/// What one material id samples.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaterialEntry {
    /// Texture-array layers. Sets keep their three images on one layer, but
    /// the table does not assume it so a material could mix them later.
    pub albedo: u32,
    pub normal: u32,
    pub height: u32,
    /// Metres per repeat of the texture.
    pub tiling_m: f32,
    pub rotation_deg: f32,
}

impl MaterialEntry {
    fn on_layer(layer: u32, tiling_m: f32, rotation_deg: f32) -> MaterialEntry {
        MaterialEntry { albedo: layer, normal: layer, height: layer, tiling_m, rotation_deg }
    }
}

/// One of the control map's 32 textures and seed 004's parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControlTextureEntry {
    /// Texture-array layer (its albedo, normal and height).
    pub layer: u32,
    pub tiling_m: f32,
    /// As background: its own slope threshold (control code 0), 0..1.
    pub threshold: f32,
    /// As overlay: the slope span over which the background replaces it.
    pub sharpness: f32,
    /// As background: how far flat ground flattens its normal before the
    /// slope test (artificial materials ~0, natural ones ~1).
    pub slope_damp: f32,
    /// As background: the overlay normal's weight in the combination.
    pub normal_damp: f32,
}

/// The texture sets, the 256-entry splat table and the 32-entry control
/// table indexing them.
#[derive(Debug, Clone, PartialEq)]
pub struct MaterialSet {
    pub textures: Vec<TextureSet>,
    /// Exactly [`MATERIAL_COUNT`] entries.
    pub table: Vec<MaterialEntry>,
    /// Exactly [`CONTROL_TEXTURES`] entries.
    pub control: Vec<ControlTextureEntry>,
}

/// GPU twin of [`ControlTextureEntry`] (GLSL `ControlTexture`, std430).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ControlGpu {
    /// albedo | normal << 8 | height << 16 (one layer for all three).
    pub layers: u32,
    pub tiling_m: f32,
    pub threshold: f32,
    pub sharpness: f32,
    pub slope_damp: f32,
    pub normal_damp: f32,
    pub pad: [f32; 2],
}

/// GPU twin of the control table's head (GLSL `ControlTable`): the values
/// of the 3-bit codes, then [`ControlGpu`] per texture.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ControlTableHead {
    /// By UV scale code; code 0 is 1 (the textures' own tiling).
    pub uv_scales: [f32; 8],
    /// By slope threshold code; code 0 reads the background's own.
    pub thresholds: [f32; 8],
}

/// GPU twin of [`MaterialEntry`] (GLSL `TerrainMaterial`, std430).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct MaterialGpu {
    /// albedo | normal << 8 | height << 16.
    pub layers: u32,
    pub tiling_m: f32,
    /// The rotation as a ready-made 2x2 matrix: the shader rotates every
    /// sample's uv and its tangent frame, so no trigonometry per pixel.
    pub cos_rot: f32,
    pub sin_rot: f32,
}

impl Default for MaterialSet {
    /// The four materials the bake writes (`world::Material`: grass 0,
    /// rock 1, snow 2, scree 3) on procedural textures. Tilings differ so
    /// the repeats of blended neighbours do not line up, and so do the
    /// rotations so their grids do not either. Ids 4..=255, which the bake
    /// never writes, repeat entry 0: a stray id shows grass, not garbage.
    fn default() -> Self {
        let textures = [ProceduralKind::Grass, ProceduralKind::Rock, ProceduralKind::Snow, ProceduralKind::Scree]
            .map(|k| TextureSet { name: k.name().to_string(), source: TextureSource::Procedural(k) })
            .to_vec();
        let mut table = vec![
            MaterialEntry::on_layer(0, 3.0, 0.0),
            MaterialEntry::on_layer(1, 7.0, 37.0),
            MaterialEntry::on_layer(2, 5.0, 71.0),
            MaterialEntry::on_layer(3, 4.0, 113.0),
        ];
        table.resize(MATERIAL_COUNT, table[0]);
        MaterialSet { textures, table, control: default_control() }
    }
}

/// The control table's defaults at the indices `world::control_textures`
/// names (rock 0, grass 1, snow 2, scree 3, gravel 4: scree's texture,
/// finer, for roads), after seed 004's categories: natural backgrounds
/// damp fully (1), an artificial one (gravel) not at all; snow, grass and
/// gravel blend sharply, scree softly. Indices 5..=31 repeat rock.
fn default_control() -> Vec<ControlTextureEntry> {
    let e = |layer, tiling_m, threshold, sharpness, slope_damp, normal_damp| ControlTextureEntry {
        layer,
        tiling_m,
        threshold,
        sharpness,
        slope_damp,
        normal_damp,
    };
    let mut t = vec![
        e(1, 7.0, 0.375, 0.1, 1.0, 0.8),
        e(0, 3.0, 0.375, 0.06, 0.8, 0.5),
        e(2, 5.0, 0.375, 0.04, 1.0, 0.8),
        e(3, 4.0, 0.3, 0.15, 0.7, 0.6),
        e(3, 1.5, 0.5, 0.04, 0.0, 0.2),
    ];
    t.resize(CONTROL_TEXTURES, t[0]);
    t
}

impl MaterialSet {
    /// Reads a material file; relative texture paths are resolved against
    /// its folder. Every error is one line naming the file and the key.
    pub fn from_file(path: &Path) -> Result<MaterialSet> {
        let origin = path.display().to_string();
        let text = crate::world::require_regular_file(path)
            .and_then(|()| std::fs::read_to_string(path))
            .map_err(|e| Error::Scene(format!("{origin}: cannot read the file: {e}")))?;
        let table: toml::Table = toml::from_str(&text).map_err(|e| {
            // toml's Display spans several lines (a source excerpt); the
            // line number and the message are enough.
            let line = e.span().map(|s| text[..s.start.min(text.len())].lines().count().max(1));
            let at = line.map(|l| format!(":{l}")).unwrap_or_default();
            Error::Scene(format!("{origin}{at}: {}", one_line(e.message())))
        })?;
        let base = path.parent().unwrap_or(Path::new("."));
        MaterialSet::from_toml(&table, base, &origin)
    }

    /// Reads a material table (see the module docs); files are resolved
    /// against `base` and must exist. `origin` (a file or key name) starts
    /// every error message.
    pub fn from_toml(table: &toml::Table, base: &Path, origin: &str) -> Result<MaterialSet> {
        parse(table, base).map_err(|msg| Error::Scene(format!("{origin}: {msg}")))
    }

    /// The layer of the texture set called `name`.
    pub fn layer_of(&self, name: &str) -> Option<u32> {
        self.textures.iter().position(|t| t.name == name).map(|i| i as u32)
    }

    /// The control table as the shader reads it: the code values, then
    /// [`CONTROL_TEXTURES`] entries.
    pub fn control_gpu(&self) -> (ControlTableHead, Vec<ControlGpu>) {
        let mut head = ControlTableHead { uv_scales: [1.0; 8], thresholds: [0.0; 8] };
        head.uv_scales[1..].copy_from_slice(&UV_SCALES);
        head.thresholds[1..].copy_from_slice(&SLOPE_THRESHOLDS);
        let entries = self
            .control
            .iter()
            .map(|c| ControlGpu {
                layers: (c.layer & 0xff) | (c.layer & 0xff) << 8 | (c.layer & 0xff) << 16,
                tiling_m: c.tiling_m,
                threshold: c.threshold,
                sharpness: c.sharpness,
                slope_damp: c.slope_damp,
                normal_damp: c.normal_damp,
                pad: [0.0; 2],
            })
            .collect();
        (head, entries)
    }

    /// What a control-map bake paints far away with each control texture:
    /// its detail texture's mean albedo and smoothness, and its threshold
    /// and sharpness (`images` built from this set).
    pub fn control_looks(
        &self,
        images: &crate::effects::materials::detail_textures::DetailImages,
    ) -> crate::world::ControlLooks {
        let means: Vec<([u8; 3], u8)> = self.control.iter().map(|c| images.mean(c.layer)).collect();
        crate::world::ControlLooks {
            albedo: means.iter().map(|m| m.0).collect(),
            smoothness: means.iter().map(|m| 255 - m.1).collect(),
            threshold: self.control.iter().map(|c| c.threshold).collect(),
            sharpness: self.control.iter().map(|c| c.sharpness).collect(),
        }
    }

    /// The table as the shader reads it ([`MATERIAL_COUNT`] entries).
    pub fn gpu_table(&self) -> Vec<MaterialGpu> {
        self.table
            .iter()
            .map(|e| {
                let (sin_rot, cos_rot) = e.rotation_deg.to_radians().sin_cos();
                MaterialGpu {
                    layers: (e.albedo & 0xff) | (e.normal & 0xff) << 8 | (e.height & 0xff) << 16,
                    tiling_m: e.tiling_m,
                    cos_rot,
                    sin_rot,
                }
            })
            .collect()
    }
}

/// The material set a scene's effects name (its file, or the defaults).
pub fn material_set(fx: &crate::effects::Effects) -> Result<MaterialSet> {
    match &fx.splat_materials {
        Some(path) => MaterialSet::from_file(path),
        None => Ok(MaterialSet::default()),
    }
}

/// What a control-map world's bake needs from its materials: the control
/// words' source (the scene's painted map, or the material rules) and each
/// texture's look. `None` outside control-map mode.
pub fn control_bake(
    fx: &crate::effects::Effects,
    world: &crate::world::WorldDesc,
    rules: crate::world::MaterialRules,
) -> Result<Option<crate::world::ControlBake>> {
    use crate::world::{ControlBake, ControlMap, ControlRules, ControlSource};
    if fx.materials != crate::effects::MaterialsMode::ControlMap {
        return Ok(None);
    }
    let set = material_set(fx)?;
    let images = crate::effects::materials::detail_textures::DetailImages::build(
        &set,
        crate::effects::materials::gpu::DETAIL_SIZE,
    )?;
    let source = match &fx.control_map {
        Some(path) => ControlSource::Map(std::sync::Arc::new(ControlMap::open(path, world.extent_m)?)),
        None => ControlSource::Rules(ControlRules { rules }),
    };
    Ok(Some(ControlBake { source, looks: set.control_looks(&images), stamps: Vec::new() }))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A fresh folder under the system temp dir, unique per test and run.
    pub(crate) fn temp_dir(tag: &str) -> PathBuf {
        use std::sync::atomic::{AtomicU32, Ordering};
        static N: AtomicU32 = AtomicU32::new(0);
        let n = N.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("vista-{tag}-{}-{n}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn parse_str(text: &str, base: &Path) -> Result<MaterialSet> {
        let t: toml::Table = toml::from_str(text).unwrap();
        MaterialSet::from_toml(&t, base, "materials.toml")
    }

    #[test]
    fn default_table_matches_the_bake_ids() {
        let set = MaterialSet::default();
        assert_eq!(set.table.len(), MATERIAL_COUNT);
        let names: Vec<&str> = set.textures.iter().map(|t| t.name.as_str()).collect();
        assert_eq!(names, ["grass", "rock", "snow", "scree"]);
        use crate::world::Material;
        for (m, name) in
            [(Material::Grass, "grass"), (Material::Rock, "rock"), (Material::Snow, "snow"), (Material::Scree, "scree")]
        {
            let e = set.table[m as usize];
            assert_eq!(Some(e.albedo), set.layer_of(name));
            assert_eq!((e.albedo, e.normal), (e.height, e.height));
            assert!(e.tiling_m > 0.0);
        }
        let rotations: std::collections::HashSet<u32> =
            set.table[..4].iter().map(|e| e.rotation_deg.to_bits()).collect();
        assert_eq!(rotations.len(), 4);
        assert!(set.table[4..].iter().all(|e| *e == set.table[0]));
    }

    #[test]
    fn gpu_table_is_16_bytes_per_entry() {
        assert_eq!(std::mem::size_of::<MaterialGpu>(), 16);
        let mut set = MaterialSet::default();
        set.table[7] = MaterialEntry { albedo: 1, normal: 2, height: 3, tiling_m: 2.0, rotation_deg: 90.0 };
        let gpu = set.gpu_table();
        assert_eq!(gpu.len(), MATERIAL_COUNT);
        assert_eq!(gpu[7].layers, 0x03_02_01);
        assert!((gpu[7].sin_rot - 1.0).abs() < 1e-6 && gpu[7].cos_rot.abs() < 1e-6);
        assert_eq!(bytemuck::cast_slice::<MaterialGpu, u8>(&gpu).len(), 16 * MATERIAL_COUNT);
    }

    #[test]
    fn overrides_and_new_sets() {
        let dir = temp_dir("materials-parse");
        for f in ["a.png", "n.png", "h.png"] {
            std::fs::write(dir.join(f), b"not decoded at parse time").unwrap();
        }
        let text = r#"
            [textures]
            snow = "procedural:dirt"
            granite = { albedo = "a.png", normal = "n.png", height = "h.png" }
            [[material]]
            id = 1
            texture = "granite"
            tiling_m = 8
            rotation_deg = 390.0
            [[material]]
            id = 200
            texture = "rock"
        "#;
        let set = parse_str(text, &dir).unwrap();
        assert_eq!(set.textures.len(), 5);
        assert_eq!(set.textures[2].source, TextureSource::Procedural(ProceduralKind::Dirt));
        assert_eq!(set.layer_of("granite"), Some(4));
        assert!(matches!(&set.textures[4].source, TextureSource::Files { albedo, .. } if *albedo == dir.join("a.png")));
        let e = set.table[1];
        assert_eq!((e.albedo, e.tiling_m, e.rotation_deg), (4, 8.0, 30.0));
        assert_eq!(set.table[200].albedo, 1);
        assert_eq!(set.table[200].tiling_m, MaterialSet::default().table[200].tiling_m);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn errors_are_one_line_naming_the_key() {
        let many: String = (0..61).map(|i| format!("t{i} = \"procedural:dirt\"\n")).collect();
        let many = format!("[textures]\n{many}");
        for (text, key) in [
            ("colour = 1", "unknown key colour"),
            ("textures = 1", "textures must be a table"),
            ("[textures]\nx = \"rock\"", "textures.x must be \"procedural:KIND\""),
            ("[textures]\nx = \"procedural:lava\"", "textures.x: unknown procedural texture \"lava\""),
            ("[textures]\nx = { albedo = \"a\", normal = \"n\" }", "textures.x.albedo: file"),
            ("[textures]\nx = { albedo = \"a\", rough = \"r\" }", "unknown key textures.x.rough"),
            ("[textures]\nx = 3", "textures.x must be"),
            (&many, "more than 64 texture sets"),
            ("material = 1", "material must be an array of tables"),
            ("[[material]]\ntexture = \"rock\"", "material[0].id is missing"),
            ("[[material]]\nid = 256", "material[0].id must be a whole number 0..=255, not 256"),
            ("[[material]]\nid = -1", "material[0].id must be a whole number 0..=255, not -1"),
            ("[[material]]\nid = 1.0", "material[0].id must be a whole number"),
            ("[[material]]\nid = 1\n[[material]]\nid = 1", "material[1].id = 1 repeats material[0].id"),
            ("[[material]]\nid = 1\ntexture = \"lava\"", "material[0].texture: unknown texture set \"lava\""),
            ("[[material]]\nid = 1\ntexture = 3", "material[0].texture must be a texture set name, not 3"),
            (
                "[[material]]\nid = 0\n[[material]]\nid = 2\n[[material]]\nid = 3\ntiling_m = -1",
                "material[2].tiling_m must be a finite number > 0, not -1",
            ),
            ("[[material]]\nid = 1\ntiling_m = -0.5", "material[0].tiling_m must be a finite number > 0, not -0.5"),
            ("[[material]]\nid = 1\ntiling_m = nan", "material[0].tiling_m must be a finite number > 0, not NaN"),
            ("[[material]]\nid = 1\ntiling_m = 0", "material[0].tiling_m"),
            ("[[material]]\nid = 1\ntiling_m = \"4\"", "material[0].tiling_m must be a finite number > 0, not \"4\""),
            ("[[material]]\nid = 1\nrotation_deg = inf", "material[0].rotation_deg must be a finite number"),
            ("[[material]]\nid = 1\nscale = 2", "unknown key material[0].scale"),
        ] {
            let e = parse_str(text, Path::new("no/such/dir")).unwrap_err().to_string();
            assert!(e.starts_with("materials.toml: ") && e.contains(key) && !e.contains('\n'), "{text}: {e}");
        }
    }

    #[test]
    fn file_errors_name_the_file() {
        let dir = temp_dir("materials-file");
        let missing = dir.join("missing.toml");
        let e = MaterialSet::from_file(&missing).unwrap_err().to_string();
        assert!(e.contains("missing.toml") && !e.contains('\n'), "{e}");
        let bad = dir.join("bad.toml");
        std::fs::write(&bad, "[textures]\nrock = \n").unwrap();
        let e = MaterialSet::from_file(&bad).unwrap_err().to_string();
        assert!(e.contains("bad.toml:2") && !e.contains('\n'), "{e}");
        let good = dir.join("good.toml");
        std::fs::write(&good, "[[material]]\nid = 5\ntexture = \"snow\"\n").unwrap();
        assert_eq!(MaterialSet::from_file(&good).unwrap().table[5].albedo, 2);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

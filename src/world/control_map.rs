//! REDengine 3's control map (seed 004): a 16-bit word per texel naming two
//! freely picked textures, a background (tri-planar: rock) and an overlay
//! (planar: snow, grass, a road), with a UV scale and a slope threshold.
//!
//! Bits 0-4 overlay texture, 5-9 background texture, 10-12 UV scale code,
//! 13-15 slope threshold code. A 3-bit code of 0 means the background
//! texture's own value (its tiling, its threshold: the material file's);
//! codes 1..=7 pick one of 7 values ([`UV_SCALES`], [`SLOPE_THRESHOLDS`]).
//!
//! A world in control-map mode bakes one word per splat texel (65 x 65 per
//! node) from a 16-bit PNG over the world's extent (nearest texel), or,
//! without one, from the material rules ([`ControlRules`]).

use std::path::Path;

use super::error::{Result, WorldError};
use super::hash::Fnv64;
use super::material_rules::{MaterialRules, Site};
use super::payload::Material;
use super::source::{GridSource, HeightSource as _};
use crate::shaders::consts;

/// UV scale of codes 1..=7 (times the background's and overlay's tiling
/// frequency; code 0 is 1, the textures' own).
pub const UV_SCALES: [f32; 7] = [0.25, 0.5, 0.75, 1.5, 2.0, 3.0, 4.0];

/// Slope threshold of codes 1..=7: the background's slope (0 flat .. 1
/// vertical, its angle over 90 degrees) above which it shows through the
/// overlay (code 0: the background texture's own threshold).
pub const SLOPE_THRESHOLDS: [f32; 7] = [0.0625, 0.125, 0.25, 0.375, 0.5, 0.625, 0.75];

/// Texture indices a control word can name (5 bits).
pub const CONTROL_TEXTURES: usize = consts::CONTROL_TEXTURES as usize;

const _: () = assert!(UV_SCALES.len() == 7 && SLOPE_THRESHOLDS.len() == 7);

/// One control word, decoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ControlCode {
    pub overlay: u8,
    pub background: u8,
    /// 0: the textures' own tiling; 1..=7: [`UV_SCALES`].
    pub uv_scale: u8,
    /// 0: the background's own threshold; 1..=7: [`SLOPE_THRESHOLDS`].
    pub threshold: u8,
}

impl ControlCode {
    /// Panics on a field out of its range (a programmer error: decoded
    /// words and parsed inputs are always in range).
    pub fn encode(self) -> u16 {
        assert!(usize::from(self.overlay) < CONTROL_TEXTURES && usize::from(self.background) < CONTROL_TEXTURES);
        assert!(self.uv_scale < 8 && self.threshold < 8);
        let c = |v: u8, shift: u32| u16::from(v) << shift;
        c(self.overlay, consts::CONTROL_OVERLAY_SHIFT)
            | c(self.background, consts::CONTROL_BACKGROUND_SHIFT)
            | c(self.uv_scale, consts::CONTROL_UV_SCALE_SHIFT)
            | c(self.threshold, consts::CONTROL_THRESHOLD_SHIFT)
    }

    pub fn decode(word: u16) -> ControlCode {
        let f = |shift: u32, mask: u32| ((u32::from(word) >> shift) & mask) as u8;
        ControlCode {
            overlay: f(consts::CONTROL_OVERLAY_SHIFT, consts::CONTROL_TEXTURE_MASK),
            background: f(consts::CONTROL_BACKGROUND_SHIFT, consts::CONTROL_TEXTURE_MASK),
            uv_scale: f(consts::CONTROL_UV_SCALE_SHIFT, consts::CONTROL_CODE_MASK),
            threshold: f(consts::CONTROL_THRESHOLD_SHIFT, consts::CONTROL_CODE_MASK),
        }
    }

    /// The UV scale this word asks for.
    pub fn uv_scale_value(self) -> f32 {
        if self.uv_scale == 0 {
            1.0
        } else {
            UV_SCALES[usize::from(self.uv_scale) - 1]
        }
    }

    /// The slope threshold this word asks for, `own` where it leaves it to
    /// the background texture.
    pub fn threshold_value(self, own: f32) -> f32 {
        if self.threshold == 0 {
            own
        } else {
            SLOPE_THRESHOLDS[usize::from(self.threshold) - 1]
        }
    }
}

/// The default control textures (the material file may retexture any
/// index): what [`ControlRules`] paints with.
pub mod textures {
    pub const ROCK: u8 = 0;
    pub const GRASS: u8 = 1;
    pub const SNOW: u8 = 2;
    pub const SCREE: u8 = 3;
    /// Scree's texture, finer: roads and beaches.
    pub const GRAVEL: u8 = 4;
}

/// Control words from the material rules, for a world without a painted
/// map: rock (or scree) as the background everywhere, the overlay the
/// rules' ground cover (grass, snow above the snow line, gravel for sand),
/// and a threshold that lets the overlay cling to slopes up to about the
/// rules' scree angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ControlRules {
    pub rules: MaterialRules,
}

impl ControlRules {
    pub fn code(&self, site: &Site) -> u16 {
        use textures::*;
        let m = self.rules.material_at(site);
        let snowy = site.altitude_m > self.rules.snow_line_m;
        let (overlay, background) = match m {
            Material::Snow => (SNOW, ROCK),
            Material::Grass => (GRASS, ROCK),
            Material::Sand => (GRAVEL, SCREE),
            Material::Scree => (if snowy { SNOW } else { GRASS }, SCREE),
            Material::Rock => (if snowy { SNOW } else { GRASS }, ROCK),
        };
        // Scree's angle over 90 degrees: the slope measure the shader
        // compares; the nearest of the 7 thresholds.
        let want = self.rules.scree_slope_deg / 90.0;
        let threshold = nearest_threshold(want);
        ControlCode { overlay, background, uv_scale: 0, threshold }.encode()
    }
}

/// The code (1..=7) of the slope threshold nearest `value`.
pub fn nearest_threshold(value: f32) -> u8 {
    let d = |t: f32| (t - value).abs();
    let best = (0..SLOPE_THRESHOLDS.len()).min_by(|&a, &b| d(SLOPE_THRESHOLDS[a]).total_cmp(&d(SLOPE_THRESHOLDS[b])));
    best.map_or(0, |i| i as u8 + 1)
}

/// Refuses a map whose texels the extent would stretch unevenly (a 3 x 5
/// map over a square world): its words would land far from where they
/// were painted. Up to 5 % is a rounding of the map's size, not a shape.
/// Returns the map's texels a side and their size in metres.
pub fn control_map_texels(path: &Path, extent_m: [f64; 2]) -> Result<([u32; 2], [f64; 2])> {
    let (w, h) =
        super::png16::Png16Source::header(path).map_err(|e| WorldError::InvalidDesc(format!("control map: {e}")))?;
    let texel = [extent_m[0] / f64::from(w), extent_m[1] / f64::from(h)];
    if (texel[0] / texel[1]).ln().abs() > 1.05f64.ln() {
        return Err(WorldError::InvalidDesc(format!(
            "control map {}: {w} x {h} texels over {} x {} m would stretch each to {:.1} x {:.1} m; give a map of \
             the area's shape",
            path.display(),
            extent_m[0],
            extent_m[1],
            texel[0],
            texel[1]
        )));
    }
    Ok(([w, h], texel))
}

/// A painted control map over the world's extent: a 16-bit grayscale PNG,
/// row 0 north, looked up by the texel containing a point (codes are not
/// interpolated).
#[derive(Clone, Debug)]
pub struct ControlMap {
    grid: GridSource,
}

impl ControlMap {
    /// Reads `path` (checked like a height map before it is decoded) to
    /// cover `extent_m`.
    pub fn open(path: &Path, extent_m: [f64; 2]) -> Result<ControlMap> {
        control_map_texels(path, extent_m)?;
        let png = super::png16::Png16Source::open(path, extent_m, [0.0, 65535.0])
            .map_err(|e| WorldError::InvalidDesc(format!("control map: {e}")))?;
        Ok(ControlMap { grid: png.into_grid() })
    }

    /// From raw words (row 0 north), for tests and tools.
    pub fn from_words(width: usize, height: usize, words: &[u16], extent_m: [f64; 2]) -> ControlMap {
        ControlMap { grid: GridSource::from_u16(width, height, words.to_vec(), [0.0, 65535.0], extent_m) }
    }

    /// The word of the texel containing (x, y) (clamped to the map).
    pub fn word(&self, x_m: f64, y_m: f64) -> u16 {
        let [dx, dy] = self.grid.pixel_size_m();
        let ey = dy * self.grid.height() as f64;
        let i = ((x_m / dx).floor().max(0.0) as usize).min(self.grid.width() - 1);
        let j = (((ey - y_m) / dy).floor().max(0.0) as usize).min(self.grid.height() - 1);
        self.grid.pixel(i, j).round() as u16
    }

    pub fn id_hash(&self) -> u64 {
        self.grid.id_hash()
    }

    /// Texel columns and rows (inclusive) a lookup anywhere in `bounds_m`
    /// reads: those whose area the bounds touch.
    fn texels_under(&self, b: [f64; 4]) -> [usize; 4] {
        let [dx, dy] = self.grid.pixel_size_m();
        let ey = dy * self.grid.height() as f64;
        let (w, h) = (self.grid.width(), self.grid.height());
        let col = |x: f64| ((x / dx).floor().max(0.0) as usize).min(w - 1);
        let row = |y: f64| (((ey - y) / dy).floor().max(0.0) as usize).min(h - 1);
        [col(b[0]), row(b[3]), col(b[2]), row(b[1])]
    }

    /// A hash of the texels a lookup in `bounds_m` reads, and where they
    /// are: repainting elsewhere leaves it alone.
    pub fn region_hash(&self, bounds_m: [f64; 4]) -> u64 {
        let [i0, j0, i1, j1] = self.texels_under(bounds_m);
        let mut h = [i0, j0, i1, j1].iter().fold(Fnv64::new().u64(self.grid.width() as u64), |h, v| h.u64(*v as u64));
        for j in j0..=j1 {
            for i in i0..=i1 {
                h = h.u64(u64::from(self.grid.pixel(i, j).to_bits()));
            }
        }
        h.finish()
    }
}

/// Where a control-map bake takes its words from.
#[derive(Clone, Debug)]
pub enum ControlSource {
    Map(std::sync::Arc<ControlMap>),
    Rules(ControlRules),
}

impl ControlSource {
    pub fn word(&self, x_m: f64, y_m: f64, site: &Site) -> u16 {
        match self {
            ControlSource::Map(m) => m.word(x_m, y_m),
            ControlSource::Rules(r) => r.code(site),
        }
    }

    /// Part of every node's key: which source, and (a map) its texels over
    /// the node's region.
    pub fn region_hash(&self, bounds_m: [f64; 4]) -> u64 {
        match self {
            ControlSource::Map(m) => Fnv64::new().u64(1).u64(m.region_hash(bounds_m)).finish(),
            ControlSource::Rules(r) => Fnv64::new().u64(2).u64(r.rules.hash()).finish(),
        }
    }
}

/// The far atlas's look of each control texture (its mean albedo and
/// smoothness) and their slope parameters: what the bake blends into a
/// control-map world's baked albedo, so far away it shows what the
/// control-map flavour shows near. The renderer's material set makes it
/// (`effects::materials`), the world module cannot see textures.
#[derive(Clone, Debug, PartialEq)]
pub struct ControlLooks {
    /// Per texture index: mean albedo (sRGB 8-bit) and smoothness (0..255).
    pub albedo: Vec<[u8; 3]>,
    pub smoothness: Vec<u8>,
    /// Per texture index: its own slope threshold and its blend width
    /// ("sharpness" in seed 004: the slope span over which the background
    /// replaces the overlay).
    pub threshold: Vec<f32>,
    pub sharpness: Vec<f32>,
}

impl ControlLooks {
    pub fn hash(&self) -> u64 {
        let mut h = Fnv64::new();
        for k in 0..self.albedo.len() {
            h = h.bytes(&self.albedo[k]).u64(u64::from(self.smoothness[k]));
            h = h.f64(f64::from(self.threshold[k])).f64(f64::from(self.sharpness[k]));
        }
        h.finish()
    }

    /// The baked albedo and smoothness of `word` on ground of slope
    /// `slope01` (0 flat .. 1 vertical): the overlay below the threshold,
    /// the background above it, blended over the overlay's width, as the
    /// flavour blends them without detail normals.
    pub fn look(&self, word: u16, slope01: f32) -> ([u8; 3], u8) {
        let c = ControlCode::decode(word);
        let (o, b) = (usize::from(c.overlay), usize::from(c.background));
        let threshold = c.threshold_value(self.threshold[b]);
        let t = ((slope01 - threshold) / self.sharpness[o].max(1e-3)).clamp(0.0, 1.0);
        let mix = |a: u8, b: u8| (f32::from(a) + (f32::from(b) - f32::from(a)) * t).round() as u8;
        let rgb = [0, 1, 2].map(|i| mix(self.albedo[o][i], self.albedo[b][i]));
        (rgb, mix(self.smoothness[o], self.smoothness[b]))
    }
}

/// A stamp's own control map (seed 004's stamps copy the control map with
/// the elevation): inside the stamp's square, where its blend weight is
/// at least a half, its words replace the world's.
#[derive(Clone, Debug)]
pub struct StampControl {
    pub placement: super::stamps::StampPlacement,
    /// Over the stamp's square (`size_m` a side, its own axes).
    pub map: std::sync::Arc<ControlMap>,
}

impl StampControl {
    fn word(&self, x_m: f64, y_m: f64) -> Option<u16> {
        let ([u, v], w) = self.placement.local(x_m, y_m)?;
        (w >= 0.5).then(|| self.map.word(u, v))
    }

    fn hash(&self) -> u64 {
        Fnv64::new().u64(self.placement.hash()).u64(self.map.id_hash()).finish()
    }
}

/// What a control-map bake needs: the words' source, the looks, and the
/// stamps' own control maps.
#[derive(Clone, Debug)]
pub struct ControlBake {
    pub source: ControlSource,
    pub looks: ControlLooks,
    /// In stamp order; the last one covering a point wins.
    pub stamps: Vec<StampControl>,
}

impl ControlBake {
    /// The word at a point: a stamp's where one covers it, else the
    /// world's (its map's, or the rules' for this site).
    pub fn word(&self, x_m: f64, y_m: f64, site: &Site) -> u16 {
        let stamped = self.stamps.iter().rev().find_map(|s| s.word(x_m, y_m));
        stamped.unwrap_or_else(|| self.source.word(x_m, y_m, site))
    }

    /// Part of a node's key over `bounds_m`: the source's, and the stamps'
    /// control maps touching it.
    pub fn region_hash(&self, bounds_m: [f64; 4]) -> u64 {
        let touching = self.stamps.iter().filter(|s| s.placement.overlaps(bounds_m));
        touching.fold(Fnv64::new().u64(self.source.region_hash(bounds_m)), |h, s| h.u64(s.hash())).finish()
    }

    /// The part of the bake settings' hash that is the same everywhere: a
    /// map's texels are in each node's own key
    /// ([`ControlSource::region_hash`]), so repainting a corner rebakes
    /// only the nodes there.
    pub fn hash(&self) -> u64 {
        let kind = match &self.source {
            ControlSource::Map(_) => 1,
            ControlSource::Rules(r) => r.rules.hash() ^ 2,
        };
        Fnv64::new().u64(kind).u64(self.looks.hash()).finish()
    }
}

/// The slope measure the control-map flavour compares with a threshold:
/// the angle of a normal to the vertical, over 90 degrees.
pub fn slope01(normal_z: f64) -> f32 {
    (normal_z.clamp(-1.0, 1.0).acos() / std::f64::consts::FRAC_PI_2) as f32
}

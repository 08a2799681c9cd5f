//! Where generated vegetation must not grow (seed 004: "users must be able
//! to mask some areas out"): shapes (a scene's `[[vegetation_masks]]`, the
//! footprints of decals with `clear_vegetation`: roads, helipads) and a
//! mask map (a grey image over the world, white keeps out). Water and sun
//! pass through a mask; only what grows there is removed.

use std::path::Path;

use crate::world::error::{Result, WorldError};
use crate::world::hash::Fnv64;
use crate::world::holes::{holes_hash, Hole};

/// A grey image over the whole world: pixel (i, j) covers
/// [i, i + 1) x extent / width east and the same rows down from the north
/// edge (row 0 north, as every image); >= half grey keeps vegetation out.
#[derive(Clone, Debug, PartialEq)]
pub struct MaskMap {
    pub size: [usize; 2],
    pub extent_m: [f64; 2],
    pub out: Vec<bool>,
    hash: u64,
}

impl MaskMap {
    /// Reads a PNG (8 or 16-bit, grey or colour: its luma) over a world of
    /// `extent_m`.
    pub fn load(path: &Path, extent_m: [f64; 2]) -> Result<Self> {
        let bad = |m: String| WorldError::Vegetation(format!("mask_map {}: {m}", path.display()));
        let img = image::open(path).map_err(|e| bad(e.to_string()))?.into_luma16();
        let size = [img.width() as usize, img.height() as usize];
        if size[0] == 0 || size[1] == 0 || size[0] * size[1] > 1 << 28 {
            return Err(bad(format!("{} x {} pixels", size[0], size[1])));
        }
        let out: Vec<bool> = img.pixels().map(|p| p.0[0] >= 32768).collect();
        let bits: Vec<u8> = out.iter().map(|b| u8::from(*b)).collect();
        let hash = Fnv64::new().u64(size[0] as u64).u64(size[1] as u64).bytes(&bits).finish();
        Ok(MaskMap { size, extent_m, out, hash })
    }

    /// Whether `p` (metres from the world's south-west corner) is masked.
    pub fn masked(&self, p: [f64; 2]) -> bool {
        let i = (p[0] / self.extent_m[0] * self.size[0] as f64).floor();
        let j = ((1.0 - p[1] / self.extent_m[1]) * self.size[1] as f64).floor();
        if i < 0.0 || j < 0.0 || i >= self.size[0] as f64 || j >= self.size[1] as f64 {
            return false;
        }
        self.out[j as usize * self.size[0] + i as usize]
    }
}

/// Everything that keeps vegetation out.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Masks {
    pub shapes: Vec<Hole>,
    pub map: Option<MaskMap>,
}

impl Masks {
    pub fn masked(&self, p: [f64; 2]) -> bool {
        self.shapes.iter().any(|s| s.contains(p[0], p[1])) || self.map.as_ref().is_some_and(|m| m.masked(p))
    }

    /// Part of a tile's key: the shapes touching `bounds` (so a mask moved
    /// elsewhere remakes nothing here) and the whole map's pixels.
    pub fn region_hash(&self, bounds: [f64; 4]) -> u64 {
        let touches = |b: [f64; 4]| b[0] <= bounds[2] && b[2] >= bounds[0] && b[1] <= bounds[3] && b[3] >= bounds[1];
        let near: Vec<Hole> = self.shapes.iter().filter(|h| touches(h.bounds())).cloned().collect();
        Fnv64::new().u64(holes_hash(&near)).u64(self.map.as_ref().map_or(0, |m| m.hash)).finish()
    }
}

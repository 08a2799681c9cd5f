//! The virtual texture's shape: regions (each owning a sub-texture), the
//! levels of a sub-texture, the mipped indirection and the physical cache.
//!
//! A region of `region_m` metres owns a sub-texture of 2^K x 2^K pages of
//! `VT_TILE_TEXELS` texels at its finest level K (0..=VT_MAX_LEVEL); level
//! L < K holds 2^L x 2^L pages of the same texel count, so a page of level L
//! covers `region_m / 2^L` metres whatever K is. A page is named by its
//! region, level and coordinates ([`PageKey`]), never by where the
//! sub-texture sits in the indirection, so a sub-texture that changes size
//! keeps every page it can still hold (Nebula's mip copy, without the copy).
//!
//! The indirection is a square of `indirection_side` texels at mip 0 with
//! every mip below it, kept as one buffer (mip m after the mips before it,
//! as in seed 001's page-status buffer). A sub-texture of level K occupies
//! an aligned 2^K square of mip 0 at (ox, oy); its level-L page (x, y) is
//! the texel (ox >> m + x, oy >> m + y) of mip m = K - L.
//!
//! Only regions in a window of `window` x `window` regions around the
//! camera can hold a sub-texture (Nebula keeps a few hundred metres): the
//! per-region state is one slot per window cell, region (x, y) in slot
//! (x mod window, y mod window), so it and the CPU's walk over it per frame
//! stay the window's size however large the world is. A slot names the
//! region it holds; a region whose slot names another has none.

use crate::shaders::consts::{
    VT_MAX_LEVEL, VT_NONE, VT_STATE_HEADER, VT_SUB_COORD_MASK, VT_SUB_K_SHIFT, VT_SUB_Y_SHIFT, VT_TILE_BORDER,
    VT_TILE_TEXELS,
};

/// One page of one region's sub-texture.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PageKey {
    pub region: u32,
    /// 0: the whole region in one page; each level halves the page.
    pub level: u32,
    pub x: u32,
    pub y: u32,
}

impl PageKey {
    /// The page of the next coarser level holding this one.
    pub fn parent(self) -> Option<PageKey> {
        (self.level > 0).then(|| PageKey { level: self.level - 1, x: self.x / 2, y: self.y / 2, ..self })
    }
}

/// Texels per side of a physical tile, its border included.
pub const PADDED_TILE: u32 = VT_TILE_TEXELS + 2 * VT_TILE_BORDER;

/// The virtual texture's dimensions for one world and scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VtLayout {
    pub region_m: f64,
    pub regions: [u32; 2],
    pub indirection_side: u32,
    /// Regions per side of the window that can hold sub-textures (at most
    /// the world's regions per side).
    pub window: u32,
    /// Physical tiles per row and rows of the cache image.
    pub cache_tiles: [u32; 2],
}

impl VtLayout {
    /// Bytes one physical tile takes in the cache (both images, RGBA8).
    pub const TILE_BYTES: u64 = PADDED_TILE as u64 * PADDED_TILE as u64 * 8;

    /// The layout over a world of `extent_m`, with a cache of at most
    /// `cache_mb` MiB (a square grid of tiles) and sub-textures in a
    /// window of at least `window_m` around the camera.
    pub fn new(extent_m: [f64; 2], region_m: f64, indirection_side: u32, cache_mb: u32, window_m: f64) -> VtLayout {
        assert!(region_m > 0.0 && indirection_side.is_power_of_two() && window_m > 0.0);
        let regions = extent_m.map(|e| (e / region_m).ceil().max(1.0) as u32);
        assert!(u64::from(regions[0]) * u64::from(regions[1]) < u64::from(VT_NONE), "region ids fit a word");
        let window = ((window_m / region_m).ceil() as u32 + 1).min(regions[0].max(regions[1]));
        let tiles = (u64::from(cache_mb) << 20) / Self::TILE_BYTES;
        let side = (tiles as f64).sqrt().floor().max(1.0) as u32;
        VtLayout { region_m, regions, indirection_side, window, cache_tiles: [side, side] }
    }

    pub fn region_count(&self) -> u32 {
        self.regions[0] * self.regions[1]
    }

    /// Slots of the window (per-region state words: a sub-texture and the
    /// region it belongs to each).
    pub fn slots(&self) -> u32 {
        self.window * self.window
    }

    /// Region `r`'s column and row.
    pub fn region_xy(&self, r: u32) -> [u32; 2] {
        [r % self.regions[0], r / self.regions[0]]
    }

    /// The slot region `r` takes while it is in the window.
    pub fn slot_of(&self, r: u32) -> u32 {
        let [x, y] = self.region_xy(r);
        x % self.window + (y % self.window) * self.window
    }

    /// The first column and row of the window around `camera_xy`: centred
    /// on the camera's region, kept inside the world.
    pub fn window_origin(&self, camera_xy: [f64; 2]) -> [u32; 2] {
        [0, 1].map(|a| {
            let c = (camera_xy[a] / self.region_m).floor().clamp(0.0, f64::from(self.regions[a] - 1)) as u32;
            c.saturating_sub(self.window / 2).min(self.regions[a].saturating_sub(self.window))
        })
    }

    /// The regions of the window starting at `origin`, row by row.
    pub fn window_regions(&self, origin: [u32; 2]) -> impl Iterator<Item = u32> + '_ {
        let end = [0, 1].map(|a| (origin[a] + self.window).min(self.regions[a]));
        (origin[1]..end[1]).flat_map(move |y| (origin[0]..end[0]).map(move |x| x + y * self.regions[0]))
    }

    /// Regions of the world within `range_m` of `camera_xy` along both
    /// axes that the window at `origin` leaves out (they get no
    /// sub-texture: the window is smaller than the range).
    pub fn beyond_window(&self, origin: [u32; 2], camera_xy: [f64; 2], range_m: f64) -> u32 {
        let span = |a: usize, lo: f64, hi: f64| {
            let f = |v: f64| (v / self.region_m).floor().clamp(0.0, f64::from(self.regions[a])) as u32;
            (f(lo), (f(hi) + 1).min(self.regions[a]))
        };
        let mut cells = [0u64; 2];
        let mut inside = [0u64; 2];
        for a in 0..2 {
            let (lo, hi) = span(a, camera_xy[a] - range_m, camera_xy[a] + range_m);
            cells[a] = u64::from(hi.saturating_sub(lo));
            let (wlo, whi) = (origin[a].max(lo), (origin[a] + self.window).min(hi));
            inside[a] = u64::from(whi.saturating_sub(wlo));
        }
        (cells[0] * cells[1] - inside[0] * inside[1]).min(u64::from(u32::MAX)) as u32
    }

    /// State-buffer words: slot `s`'s sub-texture word, its region word,
    /// and the first indirection word.
    pub fn sub_word(&self, slot: u32) -> u32 {
        VT_STATE_HEADER + slot
    }

    pub fn region_word(&self, slot: u32) -> u32 {
        VT_STATE_HEADER + self.slots() + slot
    }

    pub fn indirection_base(&self) -> u32 {
        VT_STATE_HEADER + 2 * self.slots()
    }

    /// Words of the state buffer.
    pub fn state_words(&self) -> u64 {
        u64::from(self.indirection_base()) + self.indirection_texels()
    }

    pub fn tile_count(&self) -> u32 {
        self.cache_tiles[0] * self.cache_tiles[1]
    }

    /// Texels per side of the cache images.
    pub fn cache_texels(&self) -> [u32; 2] {
        self.cache_tiles.map(|t| t * PADDED_TILE)
    }

    /// Mips of the indirection (down to one texel, at most a K-square's).
    pub fn indirection_mips(&self) -> u32 {
        (VT_MAX_LEVEL + 1).min(self.indirection_side.trailing_zeros() + 1)
    }

    /// Offset of mip `m` in the indirection buffer (texels).
    pub fn mip_offset(&self, m: u32) -> u64 {
        (0..m).map(|i| u64::from(self.indirection_side >> i).pow(2)).sum()
    }

    /// Texels of the whole indirection chain.
    pub fn indirection_texels(&self) -> u64 {
        self.mip_offset(self.indirection_mips())
    }

    /// Index of the indirection texel holding `key` for a sub-texture of
    /// level `k` at mip-0 offset `offset`.
    pub fn indirection_index(&self, key: PageKey, k: u32, offset: [u32; 2]) -> u64 {
        debug_assert!(key.level <= k);
        let m = k - key.level;
        let side = u64::from(self.indirection_side >> m);
        let x = u64::from((offset[0] >> m) + key.x);
        let y = u64::from((offset[1] >> m) + key.y);
        self.mip_offset(m) + y * side + x
    }

    /// South-west corner of region `r` (world metres).
    pub fn region_origin(&self, r: u32) -> [f64; 2] {
        [f64::from(r % self.regions[0]) * self.region_m, f64::from(r / self.regions[0]) * self.region_m]
    }

    /// Metres per texel of a page of `level`.
    pub fn texel_m(&self, level: u32) -> f64 {
        self.region_m / f64::from(VT_TILE_TEXELS << level)
    }

    /// The world rectangle (x0, y0, x1, y1 m) the texels of `key`'s padded
    /// tile cover: the page and its border.
    pub fn padded_rect(&self, key: PageKey) -> [f64; 4] {
        let o = self.region_origin(key.region);
        let page_m = self.region_m / f64::from(1u32 << key.level);
        let border = self.texel_m(key.level) * f64::from(VT_TILE_BORDER);
        let x0 = o[0] + f64::from(key.x) * page_m - border;
        let y0 = o[1] + f64::from(key.y) * page_m - border;
        [x0, y0, x0 + page_m + 2.0 * border, y0 + page_m + 2.0 * border]
    }

    /// Bytes of the indirection, the page statuses and the cache images.
    pub fn memory_bytes(&self) -> [u64; 3] {
        let ind = self.indirection_texels() * 4;
        [ind + u64::from(self.slots()) * 8, ind, u64::from(self.tile_count()) * Self::TILE_BYTES]
    }
}

/// Packs a sub-texture word (`virtual_texture.glsl` `vt_sub_texture`).
pub fn pack_sub_texture(offset: [u32; 2], k: u32) -> u32 {
    debug_assert!(offset.iter().all(|&o| o <= VT_SUB_COORD_MASK) && k <= VT_MAX_LEVEL);
    offset[0] | offset[1] << VT_SUB_Y_SHIFT | k << VT_SUB_K_SHIFT
}

/// The finest level a sub-texture needs at `distance_m` from the camera
/// when a pixel there spans `pixel_rad` radians: the first whose texels are
/// no larger than a pixel's footprint facing the camera (Nebula halves the
/// resolution at fixed distance steps; this is the same series, set by
/// the view instead of a constant), at most VT_MAX_LEVEL.
pub fn wanted_level(region_m: f64, distance_m: f64, pixel_rad: f64) -> u32 {
    let footprint = distance_m.max(region_m * 1e-3) * pixel_rad;
    let level = (region_m / (f64::from(VT_TILE_TEXELS) * footprint)).log2().ceil();
    level.clamp(0.0, f64::from(VT_MAX_LEVEL)) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pages_of_a_sub_texture_fill_its_square_at_every_mip() {
        let l = VtLayout::new([1024.0, 1024.0], 64.0, 256, 16, 1024.0);
        let (k, off) = (3, [8, 16]);
        let mut seen = std::collections::HashSet::new();
        for level in 0..=k {
            for y in 0..1 << level {
                for x in 0..1 << level {
                    let i = l.indirection_index(PageKey { region: 0, level, x, y }, k, off);
                    let m = k - level;
                    assert!(i >= l.mip_offset(m) && i < l.mip_offset(m + 1), "inside mip {m}");
                    assert!(seen.insert(i), "one texel per page");
                }
            }
        }
        assert_eq!(seen.len(), 64 + 16 + 4 + 1);
        // Mips 0..=VT_MAX_LEVEL: a level-7 sub-texture's level 0 is mip 7.
        assert_eq!(l.indirection_mips(), VT_MAX_LEVEL + 1);
        assert_eq!(l.indirection_texels(), (0..=VT_MAX_LEVEL).map(|m| (256u64 >> m).pow(2)).sum::<u64>());
    }

    #[test]
    fn the_wanted_level_halves_with_distance() {
        let rad = 1.0f64.to_radians() / 12.0;
        let near = wanted_level(64.0, 1.0, rad);
        assert_eq!(near, VT_MAX_LEVEL);
        let a = wanted_level(64.0, 50.0, rad);
        let b = wanted_level(64.0, 100.0, rad);
        assert_eq!(a, b + 1, "twice as far, one level coarser");
        assert_eq!(wanted_level(64.0, 1e6, rad), 0);
    }
}

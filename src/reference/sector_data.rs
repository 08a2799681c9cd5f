//! CPU reference of `sector_data` (the per-sector slot of every resident
//! LOD) and of the height lookup `terrain_sample.glsl` makes through it.
//! No Vulkan.

use crate::shaders::consts::{SECTOR_DATA_WORDS, SECTOR_LODS_PER_WORD, SLOT_BITS};
use crate::terrain::quadtree::{QuadtreeShadow, EMPTY, INVALID};
use crate::world::{texel_index, WorldDesc, NODE_QUADS};

/// One sector's words of sector data.
pub type SectorWords = [u32; SECTOR_DATA_WORDS as usize];

/// Sector data: per sector of the padded extent, SLOT_BITS per LOD (LOD k in
/// word k / SECTOR_LODS_PER_WORD) = the slot of the resident node covering it.
pub fn sector_data_cpu(tree: &QuadtreeShadow, world: &WorldDesc) -> Vec<SectorWords> {
    let [w, h] = tree.extent();
    let lods = world.lod_count as u8;
    let mut out = vec![[0u32; SECTOR_DATA_WORDS as usize]; (w * h) as usize];
    for y in 0..h {
        for x in 0..w {
            let e = &mut out[(y * w + x) as usize];
            for k in 0..lods {
                let v = tree.texel(k, x >> k, y >> k);
                let slot = if v == EMPTY || v == INVALID { 0 } else { u32::from(v) };
                let k = u32::from(k);
                e[(k / SECTOR_LODS_PER_WORD) as usize] |= slot << (SLOT_BITS * (k % SECTOR_LODS_PER_WORD));
            }
        }
    }
    out
}

/// Height (m) at `p` from the finest resident node, bilinear over its R16
/// samples (what terrain_sample.glsl computes), or None outside the world
/// extent or where nothing is resident. `heights(slot)` gives a resident
/// node's 132x132 height layer (texel = sample + 2, [`texel_index`]).
pub fn sample_height_cpu<'a>(
    tree: &QuadtreeShadow,
    world: &WorldDesc,
    heights: impl Fn(u32) -> &'a [u16],
    p: [f64; 2],
) -> Option<f32> {
    let inside = |v: f64, e: f64| (0.0..e).contains(&v);
    if !(inside(p[0], world.extent_m[0]) && inside(p[1], world.extent_m[1])) {
        return None;
    }
    let sector = world.sector_size_m();
    // Grid coordinates: metres from LOD-0 sample (0, 0).
    let p = [p[0] - world.grid_origin_m[0], p[1] - world.grid_origin_m[1]];
    if p[0] < 0.0 || p[1] < 0.0 {
        return None;
    }
    let [w, h] = tree.extent();
    let sx = ((p[0] / sector).floor() as u32).min(w - 1);
    let sy = ((p[1] / sector).floor() as u32).min(h - 1);
    let lods = world.lod_count as u8;
    let (k, slot) = (0..lods).find_map(|k| {
        let v = tree.texel(k, sx >> k, sy >> k);
        (v != EMPTY && v != INVALID).then_some((k, u32::from(v)))
    })?;
    let node = sector * f64::from(1u32 << k);
    let spacing = sector / NODE_QUADS as f64 * f64::from(1u32 << k);
    let local = [0, 1].map(|i| ((p[i] - (p[i] / node).floor() * node) / spacing).clamp(0.0, 128.0));
    let i0 = local.map(|l| (l.floor() as usize).min(127));
    let f = [local[0] - i0[0] as f64, local[1] - i0[1] as f64];
    let hs = heights(slot);
    let s = |x: usize, y: usize| f64::from(hs[texel_index(x as isize, y as isize)]) / 65535.0;
    let a = s(i0[0], i0[1]) * (1.0 - f[0]) + s(i0[0] + 1, i0[1]) * f[0];
    let b = s(i0[0], i0[1] + 1) * (1.0 - f[0]) + s(i0[0] + 1, i0[1] + 1) * f[0];
    let [lo, hi] = world.height_range_m;
    Some((f64::from(lo) + (a * (1.0 - f[1]) + b * f[1]) * f64::from(hi - lo)) as f32)
}

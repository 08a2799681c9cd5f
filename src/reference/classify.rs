//! CPU twin of `classify_tiles`: per 8x8 tile, the OR of the
//! classification bits; a tile with any bit is listed under its flavour
//! bits (its variant), and a control-map tile counted by the most
//! tri-planar planes its pixels sample. Lists come out in row-major tile
//! order; the GPU's append order is whatever its atomics gave, so compare
//! sorted.

use crate::shaders::consts::{CLASS_PLANES_2, CLASS_PLANES_3, FLAVOUR_CONTROL_MAP, FLAVOUR_MASK};

/// The OR of each tile's classification (row-major tiles).
fn tile_bits(classification: &[u8], size: [u32; 2], tile: u32) -> impl Iterator<Item = ([u32; 2], u32)> + '_ {
    let [w, h] = size;
    assert_eq!(classification.len(), (w * h) as usize);
    (0..h.div_ceil(tile)).flat_map(move |ty| {
        (0..w.div_ceil(tile)).map(move |tx| {
            let mut bits = 0u32;
            for y in ty * tile..((ty + 1) * tile).min(h) {
                for x in tx * tile..((tx + 1) * tile).min(w) {
                    bits |= u32::from(classification[(y * w + x) as usize]);
                }
            }
            ([tx, ty], bits)
        })
    })
}

/// Tiles (x, y) per variant (index = flavour bits) of a classification
/// image `size[0]` x `size[1]`, row 0 at the top.
pub fn classify_tiles_cpu(classification: &[u8], size: [u32; 2], tile: u32, variants: usize) -> Vec<Vec<[u32; 2]>> {
    let mut out = vec![Vec::new(); variants];
    for (t, bits) in tile_bits(classification, size, tile) {
        if bits != 0 {
            out[(bits & FLAVOUR_MASK) as usize].push(t);
        }
    }
    out
}

/// Control-map tiles whose background samples at most 1, 2 and 3 planes.
pub fn plane_tiles_cpu(classification: &[u8], size: [u32; 2], tile: u32) -> [u32; 3] {
    let mut out = [0; 3];
    for (_, bits) in tile_bits(classification, size, tile) {
        if bits & FLAVOUR_CONTROL_MAP != 0 {
            let planes = if bits & CLASS_PLANES_3 != 0 {
                3
            } else if bits & CLASS_PLANES_2 != 0 {
                2
            } else {
                1
            };
            out[planes - 1] += 1;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn partial_tiles_and_empty_tiles() {
        // 10x3: tiles of 8 -> 2x1; the second tile is 2 pixels wide.
        let mut img = vec![0u8; 30];
        img[3] = 2;
        img[2 * 10 + 1] = 16;
        img[9] = 4;
        let lists = classify_tiles_cpu(&img, [10, 3], 8, 32);
        assert_eq!(lists[18], vec![[0, 0]]);
        assert_eq!(lists[4], vec![[1, 0]]);
        assert_eq!(lists.iter().map(Vec::len).sum::<usize>(), 2);
        assert!(classify_tiles_cpu(&[0; 30], [10, 3], 8, 32).iter().all(Vec::is_empty), "no terrain, no tile");
    }
}

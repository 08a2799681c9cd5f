//! CPU twin of `classify_tiles`: per 8x8 tile, the OR of the
//! classification bits; a tile with any bit is listed under that OR (its
//! variant). Lists come out in row-major tile order; the GPU's append order
//! is whatever its atomics gave, so compare sorted.

/// Tiles (x, y) per variant (index = flavour bits) of a classification
/// image `size[0]` x `size[1]`, row 0 at the top.
pub fn classify_tiles_cpu(classification: &[u8], size: [u32; 2], tile: u32, variants: usize) -> Vec<Vec<[u32; 2]>> {
    let [w, h] = size;
    assert_eq!(classification.len(), (w * h) as usize);
    let mut out = vec![Vec::new(); variants];
    for ty in 0..h.div_ceil(tile) {
        for tx in 0..w.div_ceil(tile) {
            let mut bits = 0u8;
            for y in ty * tile..((ty + 1) * tile).min(h) {
                for x in tx * tile..((tx + 1) * tile).min(w) {
                    bits |= classification[(y * w + x) as usize];
                }
            }
            if bits != 0 {
                out[bits as usize].push([tx, ty]);
            }
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

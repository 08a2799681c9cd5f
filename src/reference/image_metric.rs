//! Perceptual difference of two tonemapped (sRGB, 8-bit) images with NVIDIA
//! FLIP (LDR-FLIP, `nv-flip`): per pixel an error in 0..=1 that models what
//! a viewer notices at the default viewing distance (67 pixels per degree).
//! Golden-image tests and `vista bench shade` compare images with it.

use serde::Serialize;

#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FlipStats {
    pub mean: f32,
    /// The 99th percentile of the per-pixel error.
    pub p99: f32,
    pub max: f32,
    pub pixels: usize,
}

/// Per-pixel FLIP error of `test` against `reference`, both RGBA8 (alpha
/// ignored) of `size`, row by row.
pub fn flip_map(reference: &[u8], test: &[u8], size: [u32; 2]) -> Vec<f32> {
    let n = size[0] as usize * size[1] as usize;
    assert!(reference.len() == n * 4 && test.len() == n * 4, "two RGBA8 images of {size:?}");
    let rgb = |rgba: &[u8]| rgba.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect::<Vec<u8>>();
    let a = nv_flip::FlipImageRgb8::with_data(size[0], size[1], &rgb(reference));
    let b = nv_flip::FlipImageRgb8::with_data(size[0], size[1], &rgb(test));
    nv_flip::flip(a, b, nv_flip::DEFAULT_PIXELS_PER_DEGREE).to_vec()
}

/// Mean, 99th percentile and maximum of some per-pixel errors.
pub fn flip_stats(errors: impl IntoIterator<Item = f32>) -> FlipStats {
    let mut e: Vec<f32> = errors.into_iter().collect();
    if e.is_empty() {
        return FlipStats { mean: 0.0, p99: 0.0, max: 0.0, pixels: 0 };
    }
    e.sort_by(f32::total_cmp);
    let mean = (e.iter().map(|&v| f64::from(v)).sum::<f64>() / e.len() as f64) as f32;
    let p99 = e[((e.len() - 1) as f64 * 0.99).round() as usize];
    FlipStats { mean, p99, max: e[e.len() - 1], pixels: e.len() }
}

/// An error map coloured with FLIP's magma scale (RGB8), for looking at.
pub fn flip_magma(errors: &[f32], size: [u32; 2]) -> Vec<u8> {
    let map = nv_flip::FlipImageFloat::with_data(size[0], size[1], errors);
    map.apply_color_lut(&nv_flip::magma_lut()).to_vec()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_images_have_no_error_and_a_changed_one_has_some() {
        let size = [32, 16];
        let a: Vec<u8> = (0..32 * 16 * 4).map(|i| (i * 7 % 251) as u8).collect();
        assert_eq!(flip_stats(flip_map(&a, &a, size)).max, 0.0);
        let mut b = a.clone();
        for p in b.chunks_exact_mut(4).take(64) {
            p[0] = 255 - p[0];
        }
        let e = flip_map(&a, &b, size);
        let s = flip_stats(e.iter().copied());
        assert!(s.mean > 0.0 && s.max > 0.1 && s.pixels == 512, "{s:?}");
        // Only the changed pixels (and their filter neighbourhood) differ.
        assert!(flip_stats(e[256..].iter().copied()).max < s.max);
        assert_eq!(flip_magma(&e, size).len(), 32 * 16 * 3);
    }
}

//! The display transforms of [`Tonemap`], in f64 from their published
//! definitions: the reference `lighting_resolve`'s output is checked
//! against, and what the reference ray-caster's images are encoded with.

use glam::{DMat3, DVec3};

use crate::scene::tonemap::Tonemap;

/// Linear HDR radiance to display values in [0, 1] (unrounded).
pub fn display(tonemap: Tonemap, exposure_ev: f32, rgb: [f64; 3]) -> [f64; 3] {
    let v = DVec3::from(rgb) * 2f64.powf(f64::from(exposure_ev));
    match tonemap {
        Tonemap::Clip => v.clamp(DVec3::ZERO, DVec3::ONE).powf(1.0 / 2.2).to_array(),
        Tonemap::Aces => aces_fitted(v).to_array().map(srgb_encode),
    }
}

/// [`display`] as 8-bit values.
pub fn display_rgb8(tonemap: Tonemap, exposure_ev: f32, rgb: [f64; 3]) -> [u8; 3] {
    display(tonemap, exposure_ev, rgb).map(|c| (c * 255.0).round() as u8)
}

/// Stephen Hill's fit: linear sRGB into ACES' RRT input space (the sRGB
/// to AP1 matrix with the RRT's saturation folded in), a rational fit of
/// the RRT and ODT per channel, back to linear sRGB, clipped.
pub fn aces_fitted(rgb: DVec3) -> DVec3 {
    // Rows as published; glam takes columns.
    let input =
        DMat3::from_cols_array(&[0.59719, 0.35458, 0.04823, 0.07600, 0.90834, 0.01566, 0.02840, 0.13383, 0.83777])
            .transpose();
    let output = DMat3::from_cols_array(&[
        1.60475, -0.53108, -0.07367, -0.10208, 1.10813, -0.00605, -0.00327, -0.07276, 1.07602,
    ])
    .transpose();
    let v = input * rgb;
    let fit = (v * (v + 0.0245786) - 0.000090537) / (v * (0.983729 * v + 0.4329510) + 0.238081);
    (output * fit).clamp(DVec3::ZERO, DVec3::ONE)
}

/// The sRGB transfer function (IEC 61966-2-1) of a value in [0, 1].
pub fn srgb_encode(c: f64) -> f64 {
    if c <= 0.0031308 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aces_rolls_highlights_off_and_keeps_black() {
        assert_eq!(aces_fitted(DVec3::ZERO), DVec3::ZERO);
        // Monotone, below 1 at 1 and approaching 1 far above it.
        let grey = |x: f64| aces_fitted(DVec3::splat(x)).x;
        let mut last = 0.0;
        for i in 1..200 {
            let y = grey(f64::from(i) * 0.1);
            assert!(y >= last, "{i}");
            last = y;
        }
        // White maps to the fit at 1 (the matrices keep greys grey):
        // (1.0245786 - 0.000090537) / (1.416680 + 0.238081) = 0.61911.
        assert!((grey(1.0) - 0.61911).abs() < 1e-4, "{}", grey(1.0));
        assert!(grey(16.0) > 0.97 && grey(16.0) <= 1.0);
        // A grey stays grey (the matrices map white to white).
        let g = aces_fitted(DVec3::splat(0.5));
        assert!((g.x - g.y).abs() < 2e-3 && (g.y - g.z).abs() < 2e-3, "{g}");
    }

    #[test]
    fn srgb_meets_its_linear_segment_and_its_end_points() {
        assert_eq!(srgb_encode(0.0), 0.0);
        assert!((srgb_encode(1.0) - 1.0).abs() < 1e-12);
        let k = 0.0031308;
        assert!((12.92 * k - (1.055 * f64::powf(k, 1.0 / 2.4) - 0.055)).abs() < 1e-6);
    }
}

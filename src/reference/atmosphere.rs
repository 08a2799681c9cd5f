//! The atmosphere model of [`crate::effects::atmosphere`] in f64: what
//! `lighting_resolve` (atmosphere.glsl) must reproduce, and what the
//! reference ray-caster applies.

use crate::effects::atmosphere::AtmosphereParams;
use crate::scene::view::Lighting;
use glam::DVec3;

/// Optical depth of the segment from `a` to `b` (world metres) through the
/// height fog over a world whose lowest height is `z_low`.
pub fn optical_depth(p: &AtmosphereParams, z_low: f64, a: DVec3, b: DVec3) -> f64 {
    let sigma0 = f64::from(p.sigma0());
    let h = f64::from(p.scale_height_m);
    let d = (b - a).length();
    let x = (b.z - a.z) / h;
    // (1 - e^-x) / x, its series near 0 (no 0 / 0 on level rays).
    let shape = if x.abs() < 1e-4 { 1.0 - 0.5 * x } else { -(-x).exp_m1() / x };
    sigma0 * (-(a.z - z_low) / h).exp() * d * shape
}

/// Transmittance between the eye `a` and the point `b`.
pub fn transmittance(p: &AtmosphereParams, z_low: f64, a: DVec3, b: DVec3) -> f64 {
    (-optical_depth(p, z_low, a, b)).exp()
}

/// Radiance the haze scatters towards the eye along the unit direction
/// `view` (from the eye), per channel.
pub fn inscatter(p: &AtmosphereParams, light: &Lighting, view: DVec3) -> [f64; 3] {
    let g = f64::from(p.sun_g);
    let mu = view.dot(light.sun_dir());
    // Henyey-Greenstein over the isotropic phase (so g = 0 gives 1).
    let phase = (1.0 - g * g) / (1.0 + g * g - 2.0 * g * mu).powf(1.5);
    [0, 1, 2]
        .map(|i| f64::from(p.haze_color[i]) * (f64::from(light.sky_color[i]) + f64::from(light.sun_color[i]) * phase))
}

/// A surface's radiance `surface` at `b`, seen from `a` through the haze.
pub fn apply(p: &AtmosphereParams, light: &Lighting, z_low: f64, a: DVec3, b: DVec3, surface: [f64; 3]) -> [f64; 3] {
    let t = transmittance(p, z_low, a, b);
    let s = inscatter(p, light, (b - a).normalize());
    [0, 1, 2].map(|i| surface[i] * t + s[i] * (1.0 - t))
}

/// The sky seen from `eye` along the unit direction `view`: the zenith
/// colour through the haze above and the clear air (all haze at or below
/// the horizon).
pub fn sky(p: &AtmosphereParams, light: &Lighting, z_low: f64, eye: DVec3, view: DVec3) -> [f64; 3] {
    let sigma = f64::from(p.sigma0()) * (-(eye.z - z_low) / f64::from(p.scale_height_m)).exp();
    let depth = sigma * f64::from(p.scale_height_m) + f64::from(p.air_depth);
    let t = if view.z > 1e-6 { (-depth / view.z).exp() } else { 0.0 };
    let s = inscatter(p, light, view);
    [0, 1, 2].map(|i| f64::from(p.zenith_color[i]) * t + s[i] * (1.0 - t))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn level_rays_follow_koschmieder_and_rising_rays_thin_out() {
        let p = AtmosphereParams { visibility_km: 10.0, ..AtmosphereParams::default() };
        // At the visibility distance, on a level ray at the low height, 2 % is left.
        let t = transmittance(&p, 0.0, DVec3::ZERO, DVec3::new(10_000.0, 0.0, 0.0));
        assert!((t - 0.02).abs() < 1e-3, "{t}");
        let up = transmittance(&p, 0.0, DVec3::ZERO, DVec3::new(10_000.0, 0.0, 2000.0));
        assert!(up > 4.0 * t, "rising rays cross thinner haze: {up}");
        // Either direction gives the same transmittance.
        let down = transmittance(&p, 0.0, DVec3::new(10_000.0, 0.0, 2000.0), DVec3::ZERO);
        assert!((up - down).abs() < 1e-12);
    }
}

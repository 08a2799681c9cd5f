//! The `atmosphere` effect's parameters: exponential height fog with single
//! scattering, integrated in closed form along each view ray (the model of
//! Wenzel, "Real-time atmospheric effects in games", 2006, and Quílez's
//! "better fog"). Extinction falls off with height,
//! sigma(z) = sigma0 exp(-(z - z_low) / H), sigma0 from the meteorological
//! visibility at the world's lowest height (Koschmieder: 3.912 / V). A
//! surface seen through it keeps the transmittance T of its ray and gains
//! (1 - T) of the light the haze scatters towards the eye, the same all
//! along the ray (single scattering of sun and sky, no shadowing of the
//! haze): haze_color x (sky_color + sun_color x 4 pi p_HG(cos angle to the
//! sun, g)). The background is the same model to infinity in front of the
//! zenith colour: a gradient from zenith to hazy horizon, brightest towards
//! the sun. `atmosphere.glsl` evaluates it on the GPU,
//! `reference::atmosphere` in f64.

pub mod frame;
pub mod kind;

/// Parameters of the `atmosphere` effect (scene keys of the same names).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AtmosphereParams {
    /// Meteorological visibility (km) at the world's lowest height.
    pub visibility_km: f32,
    /// Height (m) over which the haze's density falls by e.
    pub scale_height_m: f32,
    /// Share of each channel the haze scatters (linear RGB, 0..=1).
    pub haze_color: [f32; 3],
    /// Henyey-Greenstein asymmetry: 0 scatters evenly, towards 1 mostly
    /// forwards (a glow around the sun).
    pub sun_g: f32,
    /// Radiance of the sky beyond the haze, straight up (linear RGB).
    pub zenith_color: [f32; 3],
    /// Optical depth of the clear air above the haze, straight up (the
    /// sky's gradient only).
    pub air_depth: f32,
}

impl Default for AtmosphereParams {
    fn default() -> Self {
        AtmosphereParams {
            visibility_km: 60.0,
            scale_height_m: 1500.0,
            haze_color: [0.55, 0.62, 0.75],
            sun_g: 0.6,
            zenith_color: [0.10, 0.22, 0.55],
            air_depth: 0.12,
        }
    }
}

impl AtmosphereParams {
    /// Extinction (1/m) at the world's lowest height.
    pub fn sigma0(&self) -> f32 {
        3.912 / (self.visibility_km * 1000.0)
    }

    /// `LightingPush`'s three fog vectors: (sigma0, 1 / H, z_low, g),
    /// (haze rgb, unused), (zenith rgb, air depth).
    pub fn gpu(&self, z_low_m: f32) -> [[f32; 4]; 3] {
        let [hr, hg, hb] = self.haze_color;
        let [zr, zg, zb] = self.zenith_color;
        [
            [self.sigma0(), 1.0 / self.scale_height_m, z_low_m, self.sun_g],
            [hr, hg, hb, 0.0],
            [zr, zg, zb, self.air_depth],
        ]
    }
}

//! How the display image (`image.png`) is made from the linear HDR image
//! (`lit.exr`): an exposure, then a named tonemapper. A scene picks both
//! (`lighting = { tonemap = "aces", exposure_ev = 0.5 }`); the CPU reference
//! (`reference::tonemap`, feature `reference`) applies the same curve from its
//! published definition, so a test can compare the two.

use std::fmt;

/// A display transform of linear scene radiance.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Tonemap {
    /// Stephen Hill's fit of the ACES reference rendering and sRGB output
    /// transforms (the "ACES fitted" curve of MJP's BakingLab): a filmic
    /// shoulder that rolls highlights off instead of clipping them, and a
    /// toe; sRGB-encoded.
    #[default]
    Aces,
    /// Clipped to [0, 1] and gamma-2.2 encoded: vista's display image
    /// before filmic tonemapping, kept for comparison.
    Clip,
}

impl Tonemap {
    pub const ALL: [Tonemap; 2] = [Tonemap::Aces, Tonemap::Clip];

    /// The scene file's name.
    pub fn name(self) -> &'static str {
        match self {
            Tonemap::Aces => "aces",
            Tonemap::Clip => "clip",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|t| t.name() == name)
    }

    /// The exposure a scene gets unless it gives one. ACES maps mid-tones
    /// darker than a clip: +0.5 EV gives the default world's terrain the
    /// clipped image's mean brightness (151 against 148 of 255 at 960x540,
    /// default camera), with values above 1 rolled off instead of clipped.
    /// The clip keeps 0, so it reproduces vista's earlier image exactly.
    pub fn default_exposure_ev(self) -> f32 {
        match self {
            Tonemap::Aces => 0.5,
            Tonemap::Clip => 0.0,
        }
    }

    /// The number `lighting_resolve` switches on (`TerrainView.image.y`).
    pub fn gpu_id(self) -> u32 {
        match self {
            Tonemap::Clip => 0,
            Tonemap::Aces => 1,
        }
    }
}

impl fmt::Display for Tonemap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

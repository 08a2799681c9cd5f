//! How the display image (`image.png`) is made from the linear HDR image
//! (`lit.exr`): an exposure, then a named tonemapper. A scene picks both
//! (`lighting = { tonemap = "aces", exposure_ev = 0 }`); the CPU reference
//! ([`crate::reference::tonemap`]) applies the same curve from its
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

//! What a frame renders into, on the floor below the passes and the
//! renderer (both use it): the output an engine chooses ([`Output`]), the
//! images of one frame ([`RenderTargets`]), the depth target's contract
//! ([`DepthOptions`]) and the engine's G-buffer ([`GbufferLayout`]).

pub mod gbuffer;
pub mod gbuffer_layout;

use crate::gpu::{depth_layout, has_stencil, vk, Image};
pub use gbuffer_layout::{Channel, GbufferAttachment, GbufferLayout, NormalEncoding};

/// The default colour target of output `lit` (the shader encodes sRGB).
pub const COLOR_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;
/// The default target of output `hdr`.
pub const HDR_TARGET_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
/// The default depth format: reversed-Z, infinite far plane, with a
/// stencil aspect for the engine's terrain bit ([`DepthOptions`]).
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT_S8_UINT;
/// The default depth target's layout on entry to and exit from a frame
/// (`DepthOptions::layout` for another format).
pub const DEPTH_LAYOUT: vk::ImageLayout = vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL;

/// The depth test of the passes that shade terrain pixels only
/// (`gbuffer_tiles`, `lighting_resolve`): their fragments lie at depth 0,
/// the far plane, so LESS passes exactly where something was drawn
/// (reversed-Z: every finite distance is above 0). With the engine's depth
/// loaded that includes the engine's pixels, which those passes then tell
/// apart by vista's own classification. Needs no stencil, so any depth
/// format of [`DepthOptions`] works.
pub const TERRAIN_ONLY: vk::CompareOp = vk::CompareOp::LESS;

/// What a frame writes for the engine (`RendererOptions::output`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Output {
    /// vista's own picture: the terrain lit by sun and sky (effect
    /// `lighting`, with `shadows` and `atmosphere`), exposed and
    /// tonemapped for display into an 8-bit target: R8G8B8A8 or B8G8R8A8,
    /// UNORM (the shader encodes sRGB) or SRGB (the target does).
    Lit { format: vk::Format },
    /// Linear radiance (not exposed, not tonemapped) into the engine's
    /// float target, R16G16B16A16_SFLOAT or B10G11R11_UFLOAT, for the
    /// engine's own post-processing. `sky`: the atmosphere's sky fills the
    /// background (needs effect `atmosphere`); else the background keeps
    /// what the target holds.
    Hdr { format: vk::Format, sky: bool },
    /// No lighting at all: the terrain's surface (base colour, normal,
    /// roughness, material) into the engine's G-buffer images, laid out as
    /// the layout says; the engine lights them.
    Gbuffer(GbufferLayout),
}

impl Default for Output {
    fn default() -> Self {
        Output::Lit { format: COLOR_FORMAT }
    }
}

impl Output {
    /// The colour formats output `lit` takes.
    pub const LIT_FORMATS: [vk::Format; 4] =
        [vk::Format::R8G8B8A8_UNORM, vk::Format::R8G8B8A8_SRGB, vk::Format::B8G8R8A8_UNORM, vk::Format::B8G8R8A8_SRGB];
    /// The formats output `hdr` takes.
    pub const HDR_FORMATS: [vk::Format; 2] = [vk::Format::R16G16B16A16_SFLOAT, vk::Format::B10G11R11_UFLOAT_PACK32];

    /// Output `hdr` into the default format, with the sky.
    pub fn hdr() -> Output {
        Output::Hdr { format: HDR_TARGET_FORMAT, sky: true }
    }

    /// The name `vista render --output` takes.
    pub fn name(&self) -> &'static str {
        match self {
            Output::Lit { .. } => "lit",
            Output::Hdr { .. } => "hdr",
            Output::Gbuffer(_) => "gbuffer",
        }
    }

    /// Refuses a format or layout vista cannot write, in one line.
    pub fn check(&self) -> Result<(), String> {
        match self {
            Output::Lit { format } if !Self::LIT_FORMATS.contains(format) => Err(format!(
                "output lit writes an 8-bit display target (R8G8B8A8 or B8G8R8A8, UNORM or SRGB), not {format:?}"
            )),
            Output::Hdr { format, .. } if !Self::HDR_FORMATS.contains(format) => Err(format!(
                "output hdr writes linear radiance into R16G16B16A16_SFLOAT or B10G11R11_UFLOAT_PACK32, not {format:?}"
            )),
            Output::Gbuffer(layout) => layout.check(),
            _ => Ok(()),
        }
    }

    /// The colour target's format (lit, hdr), None for `gbuffer`.
    pub fn color_format(&self) -> Option<vk::Format> {
        match self {
            Output::Lit { format } | Output::Hdr { format, .. } => Some(*format),
            Output::Gbuffer(_) => None,
        }
    }

    /// The engine's G-buffer layout (output `gbuffer`).
    pub fn gbuffer(&self) -> Option<&GbufferLayout> {
        match self {
            Output::Gbuffer(l) => Some(l),
            _ => None,
        }
    }

    /// vista lights the frame itself (`lit`, `hdr`).
    pub fn lights(&self) -> bool {
        !matches!(self, Output::Gbuffer(_))
    }
}

/// The images a frame renders into. Layouts on entry and exit:
/// COLOR_ATTACHMENT_OPTIMAL for colour and G-buffer images, the
/// [`DepthOptions::layout`] for depth.
pub struct RenderTargets<'a> {
    /// Outputs `lit` and `hdr`: the colour target, in the output's format.
    pub color: Option<&'a Image>,
    /// Output `gbuffer`: the engine's images in the layout's order.
    pub gbuffer: &'a [&'a Image],
    pub depth: &'a Image,
    /// The colour target (or every G-buffer image) is cleared to this
    /// first; None keeps what they hold (the engine drew into them).
    pub clear: Option<[f32; 4]>,
}

impl<'a> RenderTargets<'a> {
    /// Outputs `lit` and `hdr`: a colour target cleared to `clear`.
    pub fn color(color: &'a Image, depth: &'a Image, clear: [f32; 4]) -> Self {
        RenderTargets { color: Some(color), gbuffer: &[], depth, clear: Some(clear) }
    }

    /// Output `gbuffer`: the engine's images, kept or cleared.
    pub fn gbuffer(images: &'a [&'a Image], depth: &'a Image, clear: Option<[f32; 4]>) -> Self {
        RenderTargets { color: None, gbuffer: images, depth, clear }
    }

    /// The colour target, for outputs that have one (checked by the
    /// renderer before any pass records).
    pub fn required_color(&self) -> &'a Image {
        self.color.expect("the output writes a colour target (checked by the renderer)")
    }
}

/// The engine's depth target: its format, the stencil bit vista sets where
/// there is terrain, and whether vista keeps what the engine drew
/// (`RendererOptions::depth`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DepthOptions {
    /// `D32_SFLOAT_S8_UINT` (the default) or `D32_SFLOAT`.
    pub format: vk::Format,
    /// The stencil bit (0-7) set on terrain pixels; `None`: the stencil is
    /// not touched (and must be `None` for a format without stencil).
    pub terrain_stencil_bit: Option<u32>,
    /// false: vista clears depth (and, where it writes a bit, the stencil)
    /// each frame, so the terrain is drawn first. true: the engine's depth
    /// is kept (loaded, not cleared): the terrain depth-tests against what
    /// the engine drew with the same projection (reversed-Z, infinite far
    /// plane, the view's `view_proj`), the depth pyramid is built from the
    /// combined depth, so the engine's occluders cull terrain patches and
    /// grass, and the stencil is kept as well (vista sets its terrain bit
    /// where terrain is drawn: the engine clears that bit before).
    pub load: bool,
}

impl Default for DepthOptions {
    fn default() -> Self {
        DepthOptions { format: DEPTH_FORMAT, terrain_stencil_bit: Some(0), load: false }
    }
}

impl DepthOptions {
    /// The formats vista draws reversed-Z depth into (32-bit float: a
    /// 24-bit integer depth would lose the far field's precision).
    pub const FORMATS: [vk::Format; 2] = [vk::Format::D32_SFLOAT_S8_UINT, vk::Format::D32_SFLOAT];

    /// Refuses a format vista cannot use or a bit the format cannot hold.
    pub fn check(&self) -> std::result::Result<(), String> {
        if !Self::FORMATS.contains(&self.format) {
            return Err(format!(
                "depth format {:?} is not one vista draws into (D32_SFLOAT_S8_UINT or D32_SFLOAT)",
                self.format
            ));
        }
        match self.terrain_stencil_bit {
            Some(b) if !has_stencil(self.format) => {
                Err(format!("terrain stencil bit {b} asked for, but depth format {:?} has no stencil", self.format))
            }
            Some(b) if b > 7 => Err(format!("terrain stencil bit {b} is not a bit of an 8-bit stencil (0-7)")),
            _ => Ok(()),
        }
    }

    /// The layout the target is in on entry to and exit from a frame.
    pub fn layout(&self) -> vk::ImageLayout {
        depth_layout(self.format, false)
    }

    /// The stencil mask vista writes (0: none).
    pub fn stencil_mask(&self) -> u32 {
        self.terrain_stencil_bit.map_or(0, |b| 1 << b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outputs_refuse_formats_they_cannot_write() {
        assert!(Output::default().check().is_ok());
        assert!(Output::hdr().check().is_ok());
        let e = Output::Lit { format: vk::Format::R16G16B16A16_SFLOAT }.check().unwrap_err();
        assert!(e.contains("8-bit display target"), "{e}");
        let e = Output::Hdr { format: vk::Format::R8G8B8A8_UNORM, sky: false }.check().unwrap_err();
        assert!(e.contains("linear radiance"), "{e}");
        assert!(Output::Gbuffer(GbufferLayout::default()).check().is_ok());
        assert_eq!(Output::Gbuffer(GbufferLayout::default()).color_format(), None);
    }
}

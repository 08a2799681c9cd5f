//! The engine's G-buffer as output `gbuffer` writes it: which of its
//! attachments holds base colour, the shading normal, roughness and the
//! material id, in which channel, format and normal encoding. The layout
//! is compiled into the tile passes (and the grass and asset draws) as
//! specialization constants, so a frame writes the engine's images
//! directly, with no copy pass and no 8-bit detour of the normal.
//!
//! Encodings, by the attachment's numeric format:
//! - base colour: linear in `_SRGB` and float formats (an `_SRGB` target
//!   encodes on store), sRGB-encoded in UNORM formats (as a colour texture
//!   of the engine would hold it);
//! - normal (world space, z up, unit length): in UNORM formats mapped from
//!   [-1, 1] to [0, 1]; signed as is in SNORM and float formats;
//!   `Octahedral` stores the octahedral map's two coordinates in the
//!   channels `NormalX` and `NormalY` (`NormalZ` then holds 0);
//! - roughness in [0, 1]; material: the splat palette id / 255 (exact in an
//!   8-bit UNORM channel).

use ash::vk;
use glam::{DVec3, Vec3};

/// Most attachments a layout may have (the tile passes' outputs).
pub const MAX_ATTACHMENTS: usize = 4;

/// What one channel of an attachment holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Channel {
    Zero,
    One,
    BaseR,
    BaseG,
    BaseB,
    NormalX,
    NormalY,
    NormalZ,
    Roughness,
    /// The splat palette id of the dominant material, / 255.
    Material,
}

impl Channel {
    /// The code the shaders switch on (`engine_gbuffer.glsl`).
    fn code(self) -> u32 {
        self as u32
    }
}

/// How the shading normal is stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum NormalEncoding {
    /// The unit vector's three components.
    #[default]
    Vector,
    /// The octahedral map's two coordinates (Cigolle et al. 2014), the
    /// same map vista's own 8-bit normal codes use.
    Octahedral,
}

/// Whether a format stores signed values, and whether the shader encodes
/// base colour to sRGB itself.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Numeric {
    Unorm,
    Snorm,
    Srgb,
    Float,
}

/// The formats a layout may use: colour-renderable, read back and decoded
/// by the tools (`decode`), and covered by the tests.
pub const FORMATS: [(vk::Format, Numeric, usize); 12] = [
    (vk::Format::R8G8B8A8_UNORM, Numeric::Unorm, 4),
    (vk::Format::R8G8B8A8_SRGB, Numeric::Srgb, 4),
    (vk::Format::B8G8R8A8_UNORM, Numeric::Unorm, 4),
    (vk::Format::B8G8R8A8_SRGB, Numeric::Srgb, 4),
    (vk::Format::A2B10G10R10_UNORM_PACK32, Numeric::Unorm, 4),
    (vk::Format::R16G16_UNORM, Numeric::Unorm, 2),
    (vk::Format::R16G16_SNORM, Numeric::Snorm, 2),
    (vk::Format::R16G16_SFLOAT, Numeric::Float, 2),
    (vk::Format::R16G16B16A16_SFLOAT, Numeric::Float, 4),
    (vk::Format::R8G8_UNORM, Numeric::Unorm, 2),
    (vk::Format::R8_UNORM, Numeric::Unorm, 1),
    (vk::Format::R16_SFLOAT, Numeric::Float, 1),
];

/// The numeric kind and channel count of a supported format.
pub fn format_info(format: vk::Format) -> Option<(Numeric, usize)> {
    FORMATS.iter().find(|(f, _, _)| *f == format).map(|&(_, n, c)| (n, c))
}

/// One of the engine's G-buffer images.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GbufferAttachment {
    /// For messages and debug names (e.g. "base_colour").
    pub name: String,
    pub format: vk::Format,
    /// What channels r, g, b, a hold; channels past the format's count
    /// must be `Zero`.
    pub channels: [Channel; 4],
}

/// The engine's G-buffer: its attachments in the order the frame's
/// `RenderTargets` lists their images.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GbufferLayout {
    pub attachments: Vec<GbufferAttachment>,
    pub normal: NormalEncoding,
}

impl Default for GbufferLayout {
    /// Base colour (sRGB) with roughness in alpha, and the normal as a
    /// 10-bit vector: a common deferred layout.
    fn default() -> Self {
        use Channel::*;
        GbufferLayout {
            attachments: vec![
                attachment("base_colour_roughness", vk::Format::R8G8B8A8_SRGB, [BaseR, BaseG, BaseB, Roughness]),
                attachment("normal", vk::Format::A2B10G10R10_UNORM_PACK32, [NormalX, NormalY, NormalZ, Zero]),
            ],
            normal: NormalEncoding::Vector,
        }
    }
}

fn attachment(name: &str, format: vk::Format, channels: [Channel; 4]) -> GbufferAttachment {
    GbufferAttachment { name: name.to_string(), format, channels }
}

/// The specialization constants of `engine_gbuffer.glsl`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GbufferSpec {
    /// Per attachment, its four channel codes, a nibble each (r lowest).
    pub channels: [u32; MAX_ATTACHMENTS],
    /// Per attachment a byte: bit 0 signed (normal not remapped), bit 1
    /// encode base colour to sRGB in the shader; bit 31: octahedral normal.
    pub flags: u32,
}

/// Bit of [`GbufferSpec::flags`]: the normal is stored octahedral.
pub const OCTAHEDRAL_FLAG: u32 = 1 << 31;

impl GbufferLayout {
    /// Base colour (sRGB, alpha 1), octahedral normal in RG16 UNORM,
    /// roughness and material id in RG8: a compact layout.
    pub fn octahedral() -> Self {
        use Channel::*;
        GbufferLayout {
            attachments: vec![
                attachment("base_colour", vk::Format::R8G8B8A8_SRGB, [BaseR, BaseG, BaseB, One]),
                attachment("normal", vk::Format::R16G16_UNORM, [NormalX, NormalY, Zero, Zero]),
                attachment("roughness_material", vk::Format::R8G8_UNORM, [Roughness, Material, Zero, Zero]),
            ],
            normal: NormalEncoding::Octahedral,
        }
    }

    /// Refuses a layout vista cannot write, in one line.
    pub fn check(&self) -> Result<(), String> {
        let n = self.attachments.len();
        if !(1..=MAX_ATTACHMENTS).contains(&n) {
            return Err(format!("a G-buffer layout has 1 to {MAX_ATTACHMENTS} attachments, this one {n}"));
        }
        for a in &self.attachments {
            let Some((_, count)) = format_info(a.format) else {
                let names: Vec<String> = FORMATS.iter().map(|(f, _, _)| format!("{f:?}")).collect();
                return Err(format!(
                    "G-buffer attachment {:?}: format {:?} is not one vista writes ({})",
                    a.name,
                    a.format,
                    names.join(", ")
                ));
            };
            if let Some(c) = a.channels[count..].iter().find(|c| **c != Channel::Zero) {
                return Err(format!(
                    "G-buffer attachment {:?}: {c:?} in a channel {:?} does not have ({count} channel(s))",
                    a.name, a.format
                ));
            }
        }
        let holds = |c: Channel| self.attachments.iter().any(|a| a.channels.contains(&c));
        let needed: &[Channel] = match self.normal {
            NormalEncoding::Vector => &[Channel::NormalX, Channel::NormalY, Channel::NormalZ],
            NormalEncoding::Octahedral => &[Channel::NormalX, Channel::NormalY],
        };
        if let Some(c) = [Channel::BaseR, Channel::BaseG, Channel::BaseB].iter().chain(needed).find(|c| !holds(**c)) {
            return Err(format!("the G-buffer layout has no channel for {c:?} (base colour and normal are required)"));
        }
        if self.normal == NormalEncoding::Octahedral && holds(Channel::NormalZ) {
            return Err("an octahedral normal has two coordinates: NormalZ is not one of them".into());
        }
        Ok(())
    }

    /// The formats of the attachments, in order.
    pub fn formats(&self) -> Vec<vk::Format> {
        self.attachments.iter().map(|a| a.format).collect()
    }

    /// The specialization constants (`check` first).
    pub fn spec(&self) -> GbufferSpec {
        let mut spec = GbufferSpec { channels: [0; MAX_ATTACHMENTS], flags: 0 };
        for (i, a) in self.attachments.iter().enumerate() {
            spec.channels[i] = a.channels.iter().enumerate().fold(0, |w, (k, c)| w | (c.code() << (4 * k)));
            let (numeric, _) = format_info(a.format).expect("checked");
            let signed = matches!(numeric, Numeric::Snorm | Numeric::Float);
            let encode = numeric == Numeric::Unorm;
            spec.flags |= (u32::from(signed) | u32::from(encode) << 1) << (8 * i);
        }
        if self.normal == NormalEncoding::Octahedral {
            spec.flags |= OCTAHEDRAL_FLAG;
        }
        spec
    }
}

/// A pixel of the engine's G-buffer decoded back into the terrain's
/// surface (tools and tests): what an engine reading the layout sees.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DecodedSurface {
    /// Linear base colour.
    pub base: Vec3,
    /// The shading normal as stored (unit length up to the encoding step).
    pub normal: Vec3,
    pub roughness: f32,
    /// Palette id (0 where the layout holds none).
    pub material: u32,
}

/// The channel values of one texel of `format` (bytes of one texel),
/// as the shader wrote them (before the per-kind remapping).
pub fn texel_values(format: vk::Format, bytes: &[u8]) -> [f32; 4] {
    let u8n = |b: u8| f32::from(b) / 255.0;
    let u16n = |i: usize| f32::from(u16::from_le_bytes([bytes[i], bytes[i + 1]])) / 65535.0;
    let s16n = |i: usize| (f32::from(i16::from_le_bytes([bytes[i], bytes[i + 1]])) / 32767.0).max(-1.0);
    let f16 = |i: usize| half::f16::from_bits(u16::from_le_bytes([bytes[i], bytes[i + 1]])).to_f32();
    let srgb = |b: u8| srgb_to_linear(u8n(b));
    match format {
        vk::Format::R8G8B8A8_UNORM => [u8n(bytes[0]), u8n(bytes[1]), u8n(bytes[2]), u8n(bytes[3])],
        vk::Format::B8G8R8A8_UNORM => [u8n(bytes[2]), u8n(bytes[1]), u8n(bytes[0]), u8n(bytes[3])],
        vk::Format::R8G8B8A8_SRGB => [srgb(bytes[0]), srgb(bytes[1]), srgb(bytes[2]), u8n(bytes[3])],
        vk::Format::B8G8R8A8_SRGB => [srgb(bytes[2]), srgb(bytes[1]), srgb(bytes[0]), u8n(bytes[3])],
        vk::Format::A2B10G10R10_UNORM_PACK32 => {
            let v = u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]);
            let c = |shift: u32| ((v >> shift) & 0x3FF) as f32 / 1023.0;
            [c(0), c(10), c(20), (v >> 30) as f32 / 3.0]
        }
        vk::Format::R16G16_UNORM => [u16n(0), u16n(2), 0.0, 1.0],
        vk::Format::R16G16_SNORM => [s16n(0), s16n(2), 0.0, 1.0],
        vk::Format::R16G16_SFLOAT => [f16(0), f16(2), 0.0, 1.0],
        vk::Format::R16G16B16A16_SFLOAT => [f16(0), f16(2), f16(4), f16(6)],
        vk::Format::R8G8_UNORM => [u8n(bytes[0]), u8n(bytes[1]), 0.0, 1.0],
        vk::Format::R8_UNORM => [u8n(bytes[0]), 0.0, 0.0, 1.0],
        vk::Format::R16_SFLOAT => [f16(0), 0.0, 0.0, 1.0],
        other => panic!("{other:?} is not a G-buffer layout format"),
    }
}

/// Bytes of one texel of a supported format.
pub fn texel_bytes(format: vk::Format) -> usize {
    match format {
        vk::Format::R8_UNORM => 1,
        vk::Format::R8G8_UNORM | vk::Format::R16_SFLOAT => 2,
        vk::Format::R16G16B16A16_SFLOAT => 8,
        f if format_info(f).is_some() => 4,
        other => panic!("{other:?} is not a G-buffer layout format"),
    }
}

pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The octahedral map's inverse from signed coordinates in [-1, 1] (as
/// `oct_decode` in octahedral.glsl): the one CPU decoder, which the
/// reference's code decoders call too.
pub fn oct_decode(e: [f64; 2]) -> DVec3 {
    let mut n = DVec3::new(e[0], e[1], 1.0 - e[0].abs() - e[1].abs());
    let t = (-n.z).max(0.0);
    n.x += if n.x >= 0.0 { -t } else { t };
    n.y += if n.y >= 0.0 { -t } else { t };
    n.normalize()
}

impl GbufferLayout {
    /// Decodes one pixel from the texels of each attachment (bytes of one
    /// texel per attachment, in order).
    pub fn decode(&self, texels: &[&[u8]]) -> DecodedSurface {
        let mut s = DecodedSurface { base: Vec3::ZERO, normal: Vec3::ZERO, roughness: 0.0, material: 0 };
        let mut enc = [0.0f32; 3];
        for (a, bytes) in self.attachments.iter().zip(texels) {
            let v = texel_values(a.format, bytes);
            let (numeric, _) = format_info(a.format).expect("a checked layout");
            for (k, c) in a.channels.iter().enumerate() {
                let x = v[k];
                let signed = |x: f32| if numeric == Numeric::Unorm { x * 2.0 - 1.0 } else { x };
                let base = |x: f32| if numeric == Numeric::Unorm { srgb_to_linear(x) } else { x };
                match c {
                    Channel::BaseR => s.base.x = base(x),
                    Channel::BaseG => s.base.y = base(x),
                    Channel::BaseB => s.base.z = base(x),
                    Channel::NormalX => enc[0] = signed(x),
                    Channel::NormalY => enc[1] = signed(x),
                    Channel::NormalZ => enc[2] = signed(x),
                    Channel::Roughness => s.roughness = x,
                    Channel::Material => s.material = (x * 255.0).round() as u32,
                    Channel::Zero | Channel::One => {}
                }
            }
        }
        s.normal = match self.normal {
            NormalEncoding::Vector => Vec3::from(enc),
            NormalEncoding::Octahedral => oct_decode([f64::from(enc[0]), f64::from(enc[1])]).as_vec3(),
        };
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_presets_are_valid_and_pack_their_channels() {
        for layout in [GbufferLayout::default(), GbufferLayout::octahedral()] {
            layout.check().unwrap();
        }
        let spec = GbufferLayout::default().spec();
        // r = BaseR (2), g = BaseG (3), b = BaseB (4), a = Roughness (8).
        assert_eq!(spec.channels[0], 2 | 3 << 4 | 4 << 8 | 8 << 12);
        // sRGB: neither signed nor shader-encoded; A2B10G10R10 UNORM: encoded.
        assert_eq!(spec.flags & 0xFFFF, 0b10 << 8);
        assert_eq!(GbufferLayout::octahedral().spec().flags & OCTAHEDRAL_FLAG, OCTAHEDRAL_FLAG);
    }

    #[test]
    fn bad_layouts_are_refused_in_one_line() {
        let mut l = GbufferLayout::default();
        l.attachments[1].format = vk::Format::R32G32B32A32_UINT;
        assert!(l.check().unwrap_err().contains("is not one vista writes"));
        let mut l = GbufferLayout::octahedral();
        l.attachments[2].channels[2] = Channel::Roughness;
        assert!(l.check().unwrap_err().contains("does not have (2 channel(s))"));
        let mut l = GbufferLayout::default();
        l.attachments[1].channels[2] = Channel::Zero;
        assert!(l.check().unwrap_err().contains("no channel for NormalZ"));
        let l = GbufferLayout { attachments: vec![], normal: NormalEncoding::Vector };
        assert!(l.check().unwrap_err().contains("1 to 4 attachments, this one 0"));
        for e in [GbufferLayout::default().check(), GbufferLayout::octahedral().check()] {
            assert!(e.is_ok());
        }
    }

    #[test]
    fn texels_decode_per_format() {
        // A2B10G10R10: r in the low bits.
        let v: u32 = 1023 | 512 << 10 | 1 << 30;
        let d = texel_values(vk::Format::A2B10G10R10_UNORM_PACK32, &v.to_le_bytes());
        assert_eq!(d[0], 1.0);
        assert!((d[1] - 512.0 / 1023.0).abs() < 1e-6);
        assert_eq!(d[3], 1.0 / 3.0);
        let s = texel_values(vk::Format::R16G16_SNORM, &[0x01, 0x80, 0xFF, 0x7F]);
        assert_eq!(s[0], -1.0);
        assert_eq!(s[1], 1.0);
        let b = texel_values(vk::Format::B8G8R8A8_UNORM, &[10, 20, 30, 40]);
        assert_eq!(b[0], 30.0 / 255.0);
        assert_eq!(texel_bytes(vk::Format::R16G16B16A16_SFLOAT), 8);
        assert_eq!(texel_bytes(vk::Format::R8_UNORM), 1);
    }

    #[test]
    fn octahedral_decode_inverts_the_corners() {
        assert!((oct_decode([0.0, 0.0]) - DVec3::Z).length() < 1e-12);
        assert!((oct_decode([1.0, 0.0]) - DVec3::X).length() < 1e-12);
        assert!((oct_decode([1.0, 1.0]) + DVec3::Z).length() < 1e-12);
    }
}

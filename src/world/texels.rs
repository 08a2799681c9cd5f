//! The normal and albedo payloads: 132x132 texels per node in Far Cry 5's
//! block-compressed formats, normal + smoothness BC3 and albedo BC1 with a
//! 1-bit hole alpha (or RGBA8, kept to measure what compression costs).
//!
//! Texel (t, u) of a layer holds node sample (t - 2, u - 2), so a layer
//! covers samples -2..=129: bilinear filtering anywhere inside the node
//! reads only its own layer, and 132 is a whole number of 4x4 blocks.
//!
//! Encoder: texpresso, a pure-Rust port of libsquish that both encodes and
//! decodes BC1-BC5, honours BC1's 1-bit alpha (a texel with alpha < 128
//! becomes the transparent index), and needs no C toolchain or prebuilt
//! kernels. Range fit, not cluster fit: measured on a default-world node it
//! is 12x faster, which keeps the full-world bake inside its time budget.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::shaders::consts;

/// Texels per side of a normal or albedo layer.
pub const ATLAS_SIDE: usize = consts::ATLAS_TEXTURE_SIDE as usize;
/// Texels before sample 0 on each axis.
pub const ATLAS_BORDER: usize = consts::ATLAS_BORDER as usize;
/// Texels of one layer.
pub const ATLAS_TEXELS: usize = ATLAS_SIDE * ATLAS_SIDE;
const BLOCKS: usize = (ATLAS_SIDE / 4) * (ATLAS_SIDE / 4);
const _: () = assert!(ATLAS_SIDE.is_multiple_of(4) && ATLAS_SIDE > super::layout::NODE_SAMPLES + ATLAS_BORDER);

/// Channels of a normal texel. Normal x sits in alpha, BC3's best channel
/// (8-bit endpoints, 8 levels per block), y in green (6-bit endpoints):
/// the usual "DXT5nm" arrangement. z is positive and implied.
pub const NORMAL_SMOOTHNESS: usize = 0;
pub const NORMAL_Y: usize = 1;
pub const NORMAL_OCCLUSION: usize = 2;
pub const NORMAL_X: usize = 3;

/// How the normal and albedo layers are stored, on disk and on the GPU.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PayloadFormat {
    /// Normal + smoothness BC3 (16 B per block), albedo BC1 (8 B).
    #[default]
    Bc,
    /// Both RGBA8: about 5x the bytes. The reference the compressed path
    /// is measured against.
    Rgba8,
}

/// Which layer a texel array is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TexelKind {
    Normal,
    Albedo,
}

impl PayloadFormat {
    /// Bytes of one layer of `kind`.
    pub fn layer_bytes(self, kind: TexelKind) -> usize {
        match (self, kind) {
            (PayloadFormat::Rgba8, _) => ATLAS_TEXELS * 4,
            (PayloadFormat::Bc, TexelKind::Normal) => BLOCKS * 16,
            (PayloadFormat::Bc, TexelKind::Albedo) => BLOCKS * 8,
        }
    }

    /// Byte stored in node files.
    pub fn tag(self) -> u8 {
        match self {
            PayloadFormat::Bc => 1,
            PayloadFormat::Rgba8 => 2,
        }
    }

    pub fn from_tag(tag: u8) -> Option<Self> {
        [PayloadFormat::Bc, PayloadFormat::Rgba8].into_iter().find(|f| f.tag() == tag)
    }

    /// Human-readable layer format, for memory reports.
    pub fn describe(self, kind: TexelKind) -> &'static str {
        match (self, kind) {
            (PayloadFormat::Rgba8, _) => "RGBA8 132x132",
            (PayloadFormat::Bc, TexelKind::Normal) => "BC3 132x132",
            (PayloadFormat::Bc, TexelKind::Albedo) => "BC1 132x132",
        }
    }

    fn codec(self, kind: TexelKind) -> Option<(texpresso::Format, texpresso::Params)> {
        let params = |weights| texpresso::Params {
            algorithm: texpresso::Algorithm::RangeFit,
            weights,
            weigh_colour_by_alpha: false,
        };
        match (self, kind) {
            (PayloadFormat::Rgba8, _) => None,
            // Green carries normal y; red (smoothness) matters less, blue
            // (occlusion) is constant today.
            (PayloadFormat::Bc, TexelKind::Normal) => Some((texpresso::Format::Bc3, params([0.02, 1.0, 0.02]))),
            (PayloadFormat::Bc, TexelKind::Albedo) => {
                Some((texpresso::Format::Bc1, params(texpresso::COLOUR_WEIGHTS_PERCEPTUAL)))
            }
        }
    }

    /// `ATLAS_TEXELS` RGBA8 texels, row 0 south, to this format's bytes.
    pub fn encode(self, kind: TexelKind, rgba: &[[u8; 4]]) -> Vec<u8> {
        assert_eq!(rgba.len(), ATLAS_TEXELS, "a layer is {ATLAS_SIDE}x{ATLAS_SIDE} texels");
        let flat: &[u8] = bytemuck::cast_slice(rgba);
        match self.codec(kind) {
            None => flat.to_vec(),
            Some((format, params)) => {
                let mut out = vec![0u8; self.layer_bytes(kind)];
                format.compress(flat, ATLAS_SIDE, ATLAS_SIDE, params, &mut out);
                out
            }
        }
    }

    /// Inverse of [`Self::encode`], as the GPU decodes it.
    pub fn decode(self, kind: TexelKind, bytes: &[u8]) -> Vec<[u8; 4]> {
        assert_eq!(bytes.len(), self.layer_bytes(kind), "{kind:?} layer size");
        let mut out = vec![[0u8; 4]; ATLAS_TEXELS];
        match self.codec(kind) {
            None => bytemuck::cast_slice_mut(&mut out).copy_from_slice(bytes),
            Some((format, _)) => format.decompress(bytes, ATLAS_SIDE, ATLAS_SIDE, bytemuck::cast_slice_mut(&mut out)),
        }
        out
    }
}

impl fmt::Display for PayloadFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            PayloadFormat::Bc => "bc",
            PayloadFormat::Rgba8 => "rgba8",
        })
    }
}

impl FromStr for PayloadFormat {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "bc" => Ok(PayloadFormat::Bc),
            "rgba8" => Ok(PayloadFormat::Rgba8),
            _ => Err(format!("unknown payload format {s:?} (expected bc or rgba8)")),
        }
    }
}

/// Index of node sample (i, j) in a layer; i, j may be -2..=129.
pub fn texel_index(i: isize, j: isize) -> usize {
    let (t, u) = (i + ATLAS_BORDER as isize, j + ATLAS_BORDER as isize);
    assert!((0..ATLAS_SIDE as isize).contains(&t) && (0..ATLAS_SIDE as isize).contains(&u), "sample ({i}, {j})");
    u as usize * ATLAS_SIDE + t as usize
}

/// A unit normal (z > 0) with specular occlusion and smoothness, as a
/// normal texel.
pub fn pack_normal(n: [f64; 3], occlusion: u8, smoothness: u8) -> [u8; 4] {
    let unorm = |v: f64| (v * 127.5 + 127.5).round().clamp(0.0, 255.0) as u8;
    let mut t = [0u8; 4];
    t[NORMAL_X] = unorm(n[0]);
    t[NORMAL_Y] = unorm(n[1]);
    t[NORMAL_OCCLUSION] = occlusion;
    t[NORMAL_SMOOTHNESS] = smoothness;
    t
}

/// The unit normal of a normal texel, as the shaders rebuild it.
pub fn unpack_normal(t: [u8; 4]) -> [f32; 3] {
    let x = f32::from(t[NORMAL_X]) / 127.5 - 1.0;
    let y = f32::from(t[NORMAL_Y]) / 127.5 - 1.0;
    [x, y, (1.0 - x * x - y * y).max(0.0).sqrt()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_and_tags() {
        assert_eq!(PayloadFormat::Bc.layer_bytes(TexelKind::Normal), 33 * 33 * 16);
        assert_eq!(PayloadFormat::Bc.layer_bytes(TexelKind::Albedo), 33 * 33 * 8);
        assert_eq!(PayloadFormat::Rgba8.layer_bytes(TexelKind::Albedo), 132 * 132 * 4);
        for f in [PayloadFormat::Bc, PayloadFormat::Rgba8] {
            assert_eq!(PayloadFormat::from_tag(f.tag()), Some(f));
            assert_eq!(f.to_string().parse::<PayloadFormat>(), Ok(f));
        }
        assert_eq!(PayloadFormat::from_tag(0), None);
        assert_eq!(texel_index(-2, -2), 0);
        assert_eq!(texel_index(0, 0), 2 * 132 + 2);
        assert_eq!(texel_index(129, 129), 132 * 132 - 1);
    }

    #[test]
    fn rgba8_round_trips_exactly() {
        let rgba: Vec<[u8; 4]> = (0..ATLAS_TEXELS).map(|k| [k as u8, (k >> 8) as u8, 7, 255]).collect();
        let f = PayloadFormat::Rgba8;
        assert_eq!(f.decode(TexelKind::Albedo, &f.encode(TexelKind::Albedo, &rgba)), rgba);
    }
}

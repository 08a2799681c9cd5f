//! CPU twin of octahedral.glsl: `oct_encode8` step for step in f32 (the
//! shader marks every step `precise`, so an IEEE device gives the same
//! codes), and the decoder in f64 for measuring the codes' angular error.

use crate::targets::gbuffer_layout::oct_decode;
use glam::DVec3;

/// The largest code (octahedral.glsl's OCT_CODE_MAX): 255 codes per axis,
/// so the square's centre and edges are exact.
pub const OCT_CODE_MAX: f32 = crate::shaders::consts::OCT_CODE_LAST as f32;

fn oct_sign(v: f32) -> f32 {
    if v >= 0.0 {
        1.0
    } else {
        -1.0
    }
}

/// Unit vector -> two codes 0..=254, as `oct_encode8` in octahedral.glsl.
pub fn oct_encode8(n: [f32; 3]) -> [u32; 2] {
    let l1 = n[0].abs() + n[1].abs() + n[2].abs();
    let mut p = [n[0] / l1, n[1] / l1];
    if n[2] < 0.0 {
        p = [(1.0 - p[1].abs()) * oct_sign(p[0]), (1.0 - p[0].abs()) * oct_sign(p[1])];
    }
    p.map(|v| {
        let e = v * 0.5 + 0.5;
        let scaled = e * OCT_CODE_MAX + 0.5;
        scaled.floor().clamp(0.0, OCT_CODE_MAX) as u32
    })
}

/// Codes -> unit vector, in f64 (the exact value the codes stand for).
pub fn oct_decode8(code: [u32; 2]) -> [f64; 3] {
    let f = code.map(|c| f64::from(c) / f64::from(OCT_CODE_MAX) * 2.0 - 1.0);
    oct_decode(f).to_array()
}

/// An octahedral code stored as two UNORM8 channels (the G-buffer's
/// shading normal: `oct_encode` written to RGBA8) -> unit vector, as
/// `oct_decode` reads it.
pub fn oct_decode_unorm8(code: [u8; 2]) -> DVec3 {
    oct_decode(code.map(|c| f64::from(c) / 255.0 * 2.0 - 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes_and_the_centre_are_exact() {
        assert_eq!(oct_encode8([0.0, 0.0, 1.0]), [127, 127]);
        for (v, back) in [
            ([1.0, 0.0, 0.0], [1.0, 0.0, 0.0]),
            ([0.0, -1.0, 0.0], [0.0, -1.0, 0.0]),
            ([0.0, 0.0, -1.0], [0.0, 0.0, -1.0]),
        ] {
            let d = oct_decode8(oct_encode8(v));
            assert!(d.iter().zip(back).all(|(a, b)| (a - b).abs() < 1e-12), "{v:?} -> {d:?}");
        }
    }
}

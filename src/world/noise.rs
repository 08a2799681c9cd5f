//! Gradient noise and its fractal sums: the procedural generator's raw
//! material, evaluated per point so no world-sized grid ever exists.

use std::f64::consts::FRAC_1_SQRT_2 as R2;

/// Unit gradients for the gradient noise (16 evenly spaced directions).
const GRADIENTS: [[f64; 2]; 16] = {
    let mut g = [[0.0; 2]; 16];
    // cos/sin of k*22.5 degrees, written out because const fn trig is absent.
    let c = [
        1.0,
        0.923_879_5,
        R2,
        0.382_683_4,
        0.0,
        -0.382_683_4,
        -R2,
        -0.923_879_5,
        -1.0,
        -0.923_879_5,
        -R2,
        -0.382_683_4,
        0.0,
        0.382_683_4,
        R2,
        0.923_879_5,
    ];
    let mut k = 0;
    while k < 16 {
        g[k] = [c[k], c[(k + 12) % 16]];
        k += 1;
    }
    g
};

/// `f64::floor` for the noise's coordinates (|v| far below 2^52): the same
/// value, without the library call that baseline x86-64 makes of it (7 % of
/// a bake's time).
#[inline(always)]
pub(super) fn floor(v: f64) -> f64 {
    let t = v as i64 as f64;
    if t > v {
        t - 1.0
    } else {
        t
    }
}

pub(super) fn smoothstep(e0: f64, e1: f64, x: f64) -> f64 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Integer lattice hash (splitmix64 finaliser over the mixed coordinates).
#[inline(always)]
pub(super) fn hash2(ix: i64, iy: i64, seed: u64) -> u64 {
    let mut z =
        seed ^ (ix as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ (iy as u64).wrapping_mul(0xc2b2_ae3d_27d4_eb4f);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The last lattice cell one noise evaluated and its corner gradients:
/// points along a row mostly fall in the cell before.
#[derive(Clone, Copy, Default)]
pub(super) struct Lattice {
    cell: Option<(i64, i64, u64)>,
    gradients: [[f64; 2]; 4],
}

/// Perlin-style gradient noise, roughly in -0.7..0.7. Inlined into the
/// octave loops: the bake spends most of its time here.
#[inline(always)]
pub(super) fn gradient_noise(x: f64, y: f64, seed: u64, l: &mut Lattice) -> f64 {
    let (x0, y0) = (floor(x), floor(y));
    let (fx, fy) = (x - x0, y - y0);
    let (ix, iy) = (x0 as i64, y0 as i64);
    if l.cell != Some((ix, iy, seed)) {
        let g = |dx: i64, dy: i64| GRADIENTS[(hash2(ix + dx, iy + dy, seed) & 15) as usize];
        l.gradients = [g(0, 0), g(1, 0), g(0, 1), g(1, 1)];
        l.cell = Some((ix, iy, seed));
    }
    let gr = l.gradients;
    let dot = |dx: i64, dy: i64| {
        let g = gr[(dy * 2 + dx) as usize];
        g[0] * (fx - dx as f64) + g[1] * (fy - dy as f64)
    };
    let fade = |t: f64| t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
    let (u, v) = (fade(fx), fade(fy));
    let (d00, d10, d01, d11) = (dot(0, 0), dot(1, 0), dot(0, 1), dot(1, 1));
    let a = d00 + u * (d10 - d00);
    let b = d01 + u * (d11 - d01);
    a + v * (b - a)
}

/// Fractal sum of gradient noise (one octave per lattice), roughly in -1..1.
pub(super) fn fbm(x: f64, y: f64, seed: u64, lattices: &mut [Lattice]) -> f64 {
    let (mut sum, mut amp, mut f) = (0.0, 1.0, 1.0);
    for (o, l) in lattices.iter_mut().enumerate() {
        sum += amp * gradient_noise(x * f, y * f, seed.wrapping_add(o as u64), l);
        amp *= 0.5;
        f *= 2.0;
    }
    sum
}

/// Where a ridged sum resumes: its first octave and the weight the octaves
/// before it left.
#[derive(Clone, Copy, Debug)]
pub(super) struct Octaves {
    pub first: u32,
    pub weight: f64,
}

/// Octaves `from.first ..` of a ridged multifractal (Musgrave: sharp
/// crests, detail concentrated on ridges because each octave is weighted by
/// the previous one; the whole sum roughly 0..1), one per lattice, starting from
/// the weight the earlier ones left: the sum of those octaves and the weight
/// they leave for the next. Split at any octave, the two parts add up to
/// the whole sum.
pub(super) fn ridged_from(x: f64, y: f64, seed: u64, from: Octaves, lattices: &mut [Lattice]) -> (f64, f64) {
    let scale = f64::from(1u32 << from.first.min(31));
    let (mut sum, mut amp, mut f, mut weight) = (0.0, 0.5 / scale, scale, from.weight);
    for (o, l) in lattices.iter_mut().enumerate() {
        if weight <= 0.0 {
            // Every further octave would be scaled by zero.
            break;
        }
        let octave = seed.wrapping_add(u64::from(from.first) + o as u64);
        let n = 1.0 - (gradient_noise(x * f, y * f, octave, l) * 1.4).abs();
        let n = n * n * weight;
        weight = (n * 1.8).clamp(0.0, 1.0);
        sum += n * amp;
        amp *= 0.5;
        f *= 2.0;
    }
    (sum, weight)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ridged(x: f64, y: f64, seed: u64, lattices: &mut [Lattice]) -> f64 {
        ridged_from(x, y, seed, Octaves { first: 0, weight: 1.0 }, lattices).0
    }

    #[test]
    fn a_ridged_sum_split_at_an_octave_adds_up_to_the_whole() {
        for (x, y) in [(0.3, 0.7), (12.25, -3.5), (101.9, 55.1)] {
            let whole = ridged(x, y, 9, &mut [Lattice::default(); 12]);
            let (head, w) = ridged_from(x, y, 9, Octaves { first: 0, weight: 1.0 }, &mut [Lattice::default(); 5]);
            let (tail, _) = ridged_from(x, y, 9, Octaves { first: 5, weight: w }, &mut [Lattice::default(); 7]);
            assert!((whole - (head + tail)).abs() < 1e-12, "{whole} against {head} + {tail}");
        }
    }
}

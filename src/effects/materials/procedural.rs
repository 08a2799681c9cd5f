//! The procedural detail textures (`ProceduralKind`): tileable albedo,
//! normal, roughness and height from value and cellular noise, made once
//! per renderer when a material names no files.

use super::detail_textures::{encode_normal, normalize, Layer};
use super::ProceduralKind;
use rayon::prelude::*;
use std::f32::consts::TAU;

/// What a kind's function gives at one point of the tile.
pub(super) struct Sample {
    /// sRGB-encoded 0..1.
    pub(super) rgb: [f32; 3],
    /// 0..1.
    pub(super) height: f32,
    /// 0..1.
    pub(super) roughness: f32,
}

/// Height range of a kind in units of the tile's width: how strongly its
/// height field bends the normals.
pub(super) fn relief(kind: ProceduralKind) -> f32 {
    match kind {
        ProceduralKind::Grass => 0.012,
        ProceduralKind::Rock => 0.03,
        ProceduralKind::Snow => 0.006,
        ProceduralKind::Scree => 0.025,
        ProceduralKind::Dirt => 0.02,
    }
}

pub(super) fn procedural(kind: ProceduralKind, size: u32) -> Layer {
    let noise = Noise { seed: hash(kind as u32, 0x5eed, 0x7e57), nyquist: size / 2 };
    let n = size as usize;
    let mut samples: Vec<Sample> = Vec::with_capacity(n * n);
    (0..n * n)
        .into_par_iter()
        .map(|i| {
            let (u, v) = (((i % n) as f32 + 0.5) / size as f32, ((i / n) as f32 + 0.5) / size as f32);
            sample(kind, u, v, &noise)
        })
        .collect_into_vec(&mut samples);
    let mut albedo = vec![0u8; n * n * 4];
    let mut normal = vec![0u8; n * n * 4];
    // Central differences in tile units, wrapping: the slope across the
    // edge is the slope inside.
    let scale = relief(kind) * size as f32 * 0.5;
    albedo.par_chunks_mut(4).zip(normal.par_chunks_mut(4)).enumerate().for_each(|(i, (a, nrm))| {
        let (x, y) = (i % n, i / n);
        let h = |x: usize, y: usize| samples[(y % n) * n + x % n].height;
        let dhdu = (h(x + 1, y) - h(x + n - 1, y)) * scale;
        let dhdv = (h(x, y + 1) - h(x, y + n - 1)) * scale;
        let s = &samples[i];
        let srgb8 = |c: f32| (c.clamp(0.0, 1.0) * 255.0).round() as u8;
        a.copy_from_slice(&[srgb8(s.rgb[0]), srgb8(s.rgb[1]), srgb8(s.rgb[2]), 255]);
        nrm.copy_from_slice(&encode_normal(normalize([-dhdu, -dhdv, 1.0]), srgb8(s.roughness)));
    });
    let height = samples.iter().map(|s| (s.height.clamp(0.0, 1.0) * 255.0).round() as u8).collect();
    Layer { albedo, normal, height }
}

pub(super) fn sample(kind: ProceduralKind, u: f32, v: f32, n: &Noise) -> Sample {
    match kind {
        ProceduralKind::Grass => {
            let patch = 0.5 + 0.5 * n.fbm(u, v, [4, 4], 4, 0.5, 1);
            // Blades: thin ridges of noise stretched along v and the two
            // diagonals (whole periods along each keep it tileable).
            let ridge = |x: f32| (1.0 - x.abs() * 2.5).max(0.0).powi(3);
            let b1 = ridge(n.fbm(u, v, [48, 8], 2, 0.5, 2));
            let b2 = ridge(n.fbm(u + v, u - v, [32, 6], 2, 0.5, 3));
            let b3 = ridge(n.fbm(u - v, u + v, [32, 6], 2, 0.5, 4));
            let blades = b1.max(b2).max(b3);
            let mut rgb = mix([0.14, 0.24, 0.06], [0.36, 0.50, 0.15], blades);
            rgb = mix(rgb, [0.50, 0.48, 0.24], 0.4 * smoothstep(0.55, 0.9, patch));
            Sample { rgb, height: 0.3 * patch + 0.7 * blades, roughness: 0.9 - 0.15 * blades }
        }
        ProceduralKind::Rock => rock(u, v, n),
        ProceduralKind::Snow => {
            let dunes = n.fbm(u, v, [2, 2], 5, 0.45, 20);
            let fine = n.fbm(u, v, [32, 32], 2, 0.5, 21);
            let height = 0.5 + 0.45 * dunes + 0.04 * fine;
            let rgb = mix([0.82, 0.86, 0.93], [0.95, 0.96, 0.98], smoothstep(0.2, 0.75, height));
            Sample { rgb, height, roughness: 0.45 + 0.1 * fine }
        }
        ProceduralKind::Scree => {
            // Two sizes of stones, domed cells of cellular noise; the higher
            // one shows, the gaps between them are dark grit.
            let stones = |cells: u32, salt: u32, top: f32| {
                let (f1, f2, id) = worley(u, v, cells, n.seed ^ salt);
                let dome = smoothstep(0.0, 0.3, f2 - f1).sqrt();
                (dome * top * (0.75 + 0.25 * unit(id)), unit(hash(id, salt, 1)), dome)
            };
            let (h1, tone1, d1) = stones(10, 30, 0.8);
            let (h2, tone2, d2) = stones(23, 31, 0.55);
            let (h, tone, dome) = if h1 >= h2 { (h1, tone1, d1) } else { (h2, tone2, d2) };
            let grit = n.fbm(u, v, [32, 32], 3, 0.5, 32);
            let stone = mix([0.42, 0.36, 0.29], [0.56, 0.52, 0.46], tone);
            let rgb = mix([0.18, 0.15, 0.11], stone, smoothstep(0.0, 0.35, dome));
            Sample { rgb, height: h + 0.05 * grit, roughness: 0.95 - 0.25 * dome * (0.5 + 0.5 * tone) }
        }
        ProceduralKind::Dirt => {
            let soil = n.fbm(u, v, [4, 4], 6, 0.55, 40);
            let clods = n.fbm(u, v, [16, 16], 3, 0.5, 41);
            let grit = n.fbm(u, v, [64, 64], 1, 0.5, 43);
            // A few small stones in the soil, in a third of the cells.
            let (f1, _, id) = worley(u, v, 10, n.seed ^ 42);
            let pebble = if unit(id) < 0.35 { smoothstep(0.35, 0.15, f1) } else { 0.0 };
            let height = 0.4 + 0.2 * soil + 0.15 * clods + 0.05 * grit + 0.3 * pebble;
            let earth = mix([0.28, 0.20, 0.13], [0.46, 0.35, 0.24], 0.5 + 0.7 * soil + 0.2 * clods + 0.15 * grit);
            let stone = [0.44, 0.40, 0.34].map(|c| c * (0.8 + 0.4 * unit(hash(id, 3, 4))));
            let rgb = mix(earth, stone, 0.8 * pebble);
            Sample { rgb, height, roughness: 0.92 - 0.2 * pebble }
        }
    }
}

/// Rock: strata, grain and cracks.
fn rock(u: f32, v: f32, n: &Noise) -> Sample {
    let warp = n.fbm(u, v, [3, 3], 3, 0.5, 10);
    let warp2 = n.fbm(u, v, [6, 6], 3, 0.5, 14);
    // Strata: bands along v bent by the warp, each with its own
    // tone and a sharp ledge at its base. Band indices wrap with
    // the tile (15 per repeat). Warped hard along both axes, so that
    // far cliffs (the coarse tiling) show bands that swell and pinch
    // out rather than a regular ruling of parallel lines.
    let t = (v * 5.0 + 0.8 * warp + 0.45 * warp2) * 3.0;
    let stratum = unit(hash((t.floor() as i64).rem_euclid(15) as u32, 7, n.seed));
    let band = 0.5 + 0.5 * (t * TAU / 3.0).sin();
    let ledge = smoothstep(0.0, 0.25, t.rem_euclid(1.0));
    let grain = n.fbm(u, v, [8, 8], 5, 0.55, 11);
    // Cracks: warped cell borders, only where a mask lets them
    // through (all borders would read as paving), plus finer ones.
    let (f1, f2, _) = worley(u + 0.08 * warp2, v + 0.08 * warp, 4, n.seed ^ 12);
    let major = (1.0 - smoothstep(0.0, 0.04, f2 - f1)) * smoothstep(-0.15, 0.2, n.fbm(u, v, [5, 5], 2, 0.5, 15));
    let (g1, g2, _) = worley(u + 0.05 * warp, v + 0.05 * warp2, 12, n.seed ^ 16);
    let minor = (1.0 - smoothstep(0.0, 0.05, g2 - g1)) * smoothstep(0.1, 0.4, n.fbm(u, v, [7, 7], 2, 0.5, 17));
    let crack = major.max(0.6 * minor);
    let height = 0.45 + 0.2 * grain + 0.05 * band + 0.03 * ledge - 0.35 * crack;
    let mut rgb = mix([0.33, 0.32, 0.30], [0.60, 0.58, 0.54], 0.5 + 0.6 * grain + 0.3 * (stratum - 0.5));
    rgb = add(rgb, [0.03 * band, 0.02 * band, 0.0]);
    rgb = rgb.map(|c| c * (1.0 - 0.55 * crack));
    let roughness = 0.62 + 0.15 * (0.5 + 0.5 * n.fbm(u, v, [16, 16], 2, 0.5, 13)) + 0.2 * crack;
    Sample { rgb, height, roughness }
}

pub(super) fn mix(a: [f32; 3], b: [f32; 3], t: f32) -> [f32; 3] {
    let t = t.clamp(0.0, 1.0);
    [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t]
}

pub(super) fn add(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// Hermite step from `e0` to `e1` (either order).
pub(super) fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

pub(super) fn hash(x: u32, y: u32, seed: u32) -> u32 {
    let mut h = x.wrapping_mul(0x8da6_b343) ^ y.wrapping_mul(0xd816_3841) ^ seed.wrapping_mul(0xcb1a_b31f);
    h ^= h >> 16;
    h = h.wrapping_mul(0x7feb_352d);
    h ^= h >> 15;
    h = h.wrapping_mul(0x846c_a68b);
    h ^ (h >> 16)
}

/// 0..1 from the high bits.
pub(super) fn unit(h: u32) -> f32 {
    (h >> 8) as f32 / (1u32 << 24) as f32
}

/// Periodic noise: every lattice has a whole number of cells across the
/// tile, and lattices finer than `nyquist` cells are left out (they would
/// only alias at this size).
pub(super) struct Noise {
    pub(super) seed: u32,
    pub(super) nyquist: u32,
}

pub(super) const GRADIENTS: [[f32; 2]; 8] = [
    [1.0, 0.0],
    [-1.0, 0.0],
    [0.0, 1.0],
    [0.0, -1.0],
    [std::f32::consts::FRAC_1_SQRT_2, std::f32::consts::FRAC_1_SQRT_2],
    [-std::f32::consts::FRAC_1_SQRT_2, std::f32::consts::FRAC_1_SQRT_2],
    [std::f32::consts::FRAC_1_SQRT_2, -std::f32::consts::FRAC_1_SQRT_2],
    [-std::f32::consts::FRAC_1_SQRT_2, -std::f32::consts::FRAC_1_SQRT_2],
];

impl Noise {
    /// Fractal gradient noise, about -1..1: `octaves` lattices from
    /// `cells` up, doubling, each `gain` times weaker.
    fn fbm(&self, u: f32, v: f32, cells: [u32; 2], octaves: u32, gain: f32, salt: u32) -> f32 {
        let (mut sum, mut norm, mut amp) = (0.0, 0.0, 1.0);
        for o in 0..octaves {
            let (px, py) = (cells[0] << o, cells[1] << o);
            if px.max(py) <= self.nyquist {
                sum += amp * gradient(u, v, px, py, hash(self.seed, salt, o));
            }
            norm += amp;
            amp *= gain;
        }
        sum / norm
    }
}

/// Gradient noise with `px` x `py` cells over the unit torus, about -1..1.
pub(super) fn gradient(u: f32, v: f32, px: u32, py: u32, seed: u32) -> f32 {
    let (x, y) = (u * px as f32, v * py as f32);
    let (xf, yf) = (x.floor(), y.floor());
    let (fx, fy) = (x - xf, y - yf);
    let (x0, y0) = (wrap(xf as i64, px), wrap(yf as i64, py));
    let (x1, y1) = (wrap(x0 as i64 + 1, px), wrap(y0 as i64 + 1, py));
    let dot = |cx: u32, cy: u32, dx: f32, dy: f32| {
        let g = GRADIENTS[(hash(cx, cy, seed) & 7) as usize];
        g[0] * dx + g[1] * dy
    };
    let fade = |t: f32| t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
    let (sx, sy) = (fade(fx), fade(fy));
    let (n00, n10) = (dot(x0, y0, fx, fy), dot(x1, y0, fx - 1.0, fy));
    let (n01, n11) = (dot(x0, y1, fx, fy - 1.0), dot(x1, y1, fx - 1.0, fy - 1.0));
    let (a, b) = (n00 + sx * (n10 - n00), n01 + sx * (n11 - n01));
    (a + sy * (b - a)) * 1.4
}

/// `i` modulo `n` in 0..n; lattice indices are nearly always within one
/// period of the tile, where this needs no division (half the noise cost).
pub(super) fn wrap(i: i64, n: u32) -> u32 {
    let n = n as i64;
    let w = if i < 0 {
        i + n
    } else if i >= n {
        i - n
    } else {
        i
    };
    if (0..n).contains(&w) {
        w as u32
    } else {
        i.rem_euclid(n) as u32
    }
}

/// Cellular noise with `cells` x `cells` jittered points over the unit
/// torus: distances (in cells) to the nearest and second nearest point, and
/// the nearest point's hash.
pub(super) fn worley(u: f32, v: f32, cells: u32, seed: u32) -> (f32, f32, u32) {
    let (x, y) = (u * cells as f32, v * cells as f32);
    let (cx, cy) = (x.floor(), y.floor());
    let (fx, fy) = (x - cx, y - cy);
    let (cx, cy) = (cx as i64, cy as i64);
    let (mut f1, mut f2, mut id) = (f32::MAX, f32::MAX, 0);
    for dy in -1..=1i64 {
        for dx in -1..=1i64 {
            let (wx, wy) = (wrap(cx + dx, cells), wrap(cy + dy, cells));
            let h = hash(wx, wy, seed);
            let px = dx as f32 + unit(h) - fx;
            let py = dy as f32 + unit(hash(h, 0x9e37_79b9, seed)) - fy;
            let d = px * px + py * py;
            if d < f1 {
                (f2, f1, id) = (f1, d, h);
            } else if d < f2 {
                f2 = d;
            }
        }
    }
    (f1.sqrt(), f2.sqrt(), id)
}

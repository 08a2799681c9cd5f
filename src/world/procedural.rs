//! A deterministic procedural terrain: ridged mountains, carved valleys and
//! terraced cliffs, evaluated per sample so no world-sized grid ever exists.

use std::f64::consts::FRAC_1_SQRT_2 as R2;

use super::error::Result;
use super::hash::Fnv64;
use super::layout::WorldDesc;
use super::png16::check_params;
use super::source::HeightSource;

/// Bumped whenever the generator's output changes, so caches rebake.
const GENERATOR_VERSION: u64 = 1;
/// Wavelength of the largest mountain features, metres.
const MOUNTAIN_WAVELENGTH_M: f64 = 4096.0;
/// Ridged octaves: 4096 m down to 2 m, enough detail for 0.5 m sampling.
const MOUNTAIN_OCTAVES: u32 = 12;
/// Wavelength of the mountain/lowland mask, metres.
const CONTINENT_WAVELENGTH_M: f64 = 9000.0;
/// Wavelength of the valley network, metres.
const VALLEY_WAVELENGTH_M: f64 = 3000.0;
/// Wavelength of the mask choosing where terraces (cliffs) appear, metres.
const CLIFF_MASK_WAVELENGTH_M: f64 = 1800.0;
/// Height of one terrace step as a fraction of the height range.
const TERRACE_STEP: f64 = 0.025;
/// Terrace profile exponent: the step face is this many times steeper than
/// the underlying slope, which turns 20-30 degree slopes into >60 degree cliffs.
const TERRACE_SHARPNESS: i32 = 8;
/// Domain warp amplitude, metres: bends ridges so they do not look gridded.
const WARP_M: f64 = 600.0;

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

/// Procedural height field; output always lies in the height range.
#[derive(Clone, Debug)]
pub struct ProceduralSource {
    seed: u64,
    extent_m: [f64; 2],
    height_range_m: [f32; 2],
}

impl ProceduralSource {
    /// Fails on a non-finite or empty extent or height range.
    pub fn new(seed: u64, extent_m: [f64; 2], height_range_m: [f32; 2]) -> Result<Self> {
        check_params(extent_m, height_range_m)?;
        Ok(ProceduralSource { seed, extent_m, height_range_m })
    }

    /// The default 10 km world and its generator.
    pub fn default_world(seed: u64) -> (WorldDesc, Self) {
        let w = WorldDesc::default();
        let source = ProceduralSource { seed, extent_m: w.extent_m, height_range_m: w.height_range_m };
        (w, source)
    }

    /// Normalised height in 0..1 before mapping to the height range.
    fn height01(&self, x: f64, y: f64, c: &mut Lattices) -> f64 {
        let s = self.seed;
        let warp = [
            fbm(x / 2500.0, y / 2500.0, s ^ 0x11, &mut c.warp_x),
            fbm(x / 2500.0 + 17.3, y / 2500.0 - 9.1, s ^ 0x22, &mut c.warp_y),
        ];
        let (wx, wy) = (x + WARP_M * warp[0], y + WARP_M * warp[1]);
        let continent = fbm(x / CONTINENT_WAVELENGTH_M, y / CONTINENT_WAVELENGTH_M, s ^ 0x33, &mut c.continent);
        let mountain_mask = smoothstep(-0.35, 0.45, continent);
        // Lowlands have no mountains: skipping their ridges changes nothing.
        let ridges = if mountain_mask > 0.0 {
            ridged(wx / MOUNTAIN_WAVELENGTH_M, wy / MOUNTAIN_WAVELENGTH_M, s ^ 0x44, &mut c.ridges)
        } else {
            0.0
        };
        let mut h = 0.12 + 0.08 * continent + mountain_mask * 0.85 * ridges;
        // Valleys: where a warped noise crosses zero, carve a smooth trough.
        let v = fbm(wx / VALLEY_WAVELENGTH_M, wy / VALLEY_WAVELENGTH_M, s ^ 0x55, &mut c.valley).abs();
        let carve = smoothstep(0.0, 0.15, v);
        h = 0.05 + (h - 0.05) * (0.35 + 0.65 * carve);
        // Terraces: flat treads and near-vertical risers where the mask is on.
        let mask = gradient_noise(x / CLIFF_MASK_WAVELENGTH_M, y / CLIFF_MASK_WAVELENGTH_M, s ^ 0x66, &mut c.cliff);
        let cliff = smoothstep(0.05, 0.3, mask);
        if cliff > 0.0 {
            let t = h / TERRACE_STEP;
            let terraced = (t.floor() + t.fract().powi(TERRACE_SHARPNESS)) * TERRACE_STEP;
            h += cliff * (terraced - h);
        }
        h.clamp(0.0, 1.0)
    }
}

impl ProceduralSource {
    fn sample_with(&self, x_m: f64, y_m: f64, c: &mut Lattices) -> f32 {
        let x = x_m.clamp(0.0, self.extent_m[0]);
        let y = y_m.clamp(0.0, self.extent_m[1]);
        let h = if x.is_finite() && y.is_finite() { self.height01(x, y, c) } else { 0.0 };
        let [lo, hi] = self.height_range_m;
        (f64::from(lo) + h * f64::from(hi - lo)) as f32
    }
}

impl HeightSource for ProceduralSource {
    fn sample(&self, x_m: f64, y_m: f64) -> f32 {
        self.sample_with(x_m, y_m, &mut Lattices::default())
    }

    /// Neighbouring points share most lattice cells, so the row keeps each
    /// noise's last cell and its gradients: the same values, without the
    /// hashing (half a sample's cost).
    /// Heights are a 0..1 field (clamped) over the source's range.
    fn range_in(&self, _bounds_m: [f64; 4]) -> Option<[f32; 2]> {
        Some(self.height_range_m)
    }

    fn sample_row(&self, xs: &[f64], y_m: f64, out: &mut [f32]) {
        let mut c = Lattices::default();
        for (x, o) in xs.iter().zip(out) {
            *o = self.sample_with(*x, y_m, &mut c);
        }
    }

    fn id_hash(&self) -> u64 {
        Fnv64::new()
            .u64(GENERATOR_VERSION)
            .u64(self.seed)
            .f64(self.extent_m[0])
            .f64(self.extent_m[1])
            .f64(f64::from(self.height_range_m[0]))
            .f64(f64::from(self.height_range_m[1]))
            .finish()
    }
}

/// `f64::floor` for the noise's coordinates (|v| far below 2^52): the same
/// value, without the library call that baseline x86-64 makes of it (7 % of
/// a bake's time).
#[inline(always)]
fn floor(v: f64) -> f64 {
    let t = v as i64 as f64;
    if t > v {
        t - 1.0
    } else {
        t
    }
}

fn smoothstep(e0: f64, e1: f64, x: f64) -> f64 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Integer lattice hash (splitmix64 finaliser over the mixed coordinates).
#[inline(always)]
fn hash2(ix: i64, iy: i64, seed: u64) -> u64 {
    let mut z =
        seed ^ (ix as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ (iy as u64).wrapping_mul(0xc2b2_ae3d_27d4_eb4f);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The last lattice cell one noise evaluated and its corner gradients:
/// points along a row mostly fall in the cell before.
#[derive(Clone, Copy, Default)]
struct Lattice {
    cell: Option<(i64, i64, u64)>,
    gradients: [[f64; 2]; 4],
}

/// One [`Lattice`] per noise octave of the generator.
#[derive(Default)]
struct Lattices {
    warp_x: [Lattice; 3],
    warp_y: [Lattice; 3],
    continent: [Lattice; 3],
    ridges: [Lattice; MOUNTAIN_OCTAVES as usize],
    valley: [Lattice; 2],
    cliff: Lattice,
}

/// Perlin-style gradient noise, roughly in -0.7..0.7. Inlined into the
/// octave loops: the bake spends most of its time here.
#[inline(always)]
fn gradient_noise(x: f64, y: f64, seed: u64, l: &mut Lattice) -> f64 {
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
fn fbm(x: f64, y: f64, seed: u64, lattices: &mut [Lattice]) -> f64 {
    let (mut sum, mut amp, mut f) = (0.0, 1.0, 1.0);
    for (o, l) in lattices.iter_mut().enumerate() {
        sum += amp * gradient_noise(x * f, y * f, seed.wrapping_add(o as u64), l);
        amp *= 0.5;
        f *= 2.0;
    }
    sum
}

/// Ridged multifractal (Musgrave): sharp crests, detail concentrated on
/// ridges because each octave is weighted by the previous one. Roughly 0..1.
fn ridged(x: f64, y: f64, seed: u64, lattices: &mut [Lattice]) -> f64 {
    let (mut sum, mut amp, mut f, mut weight) = (0.0, 0.5, 1.0, 1.0);
    for (o, l) in lattices.iter_mut().enumerate() {
        if weight <= 0.0 {
            // Every further octave would be scaled by zero.
            break;
        }
        let n = 1.0 - (gradient_noise(x * f, y * f, seed.wrapping_add(o as u64), l) * 1.4).abs();
        let n = n * n * weight;
        weight = (n * 1.8).clamp(0.0, 1.0);
        sum += n * amp;
        amp *= 0.5;
        f *= 2.0;
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_row_samples_bit_for_bit_as_points_do() {
        let (_, src) = ProceduralSource::default_world(3);
        // Rows through mountains, terraces and lowlands, at bake spacings.
        for (y, step) in [(4000.25, 0.5), (700.0, 0.125), (9000.5, 3.0), (5120.0, 0.5)] {
            let xs: Vec<f64> = (0..600).map(|i| 2500.0 + i as f64 * step).collect();
            let mut row = vec![0f32; xs.len()];
            src.sample_row(&xs, y, &mut row);
            for (x, r) in xs.iter().zip(&row) {
                assert_eq!(r.to_bits(), src.sample(*x, y).to_bits(), "at ({x}, {y})");
            }
        }
    }
}

//! A deterministic procedural terrain shaped the way water and gravity
//! shape ground: ridged mountains, valleys and lowlands evaluated on a
//! coarse grid of the world, eroded there (drainage that branches to the
//! border, flat floors where basins filled, talus under steep faces), then
//! per sample the fine ridged octaves on top, calmer where water runs.
//! Terraced cliffs are an option. No world-sized grid ever exists: the
//! coarse grid has at most [`SHAPE_NODES`] nodes a side.

use std::sync::Arc;

use rayon::prelude::*;

use super::erosion::Terrain;
use super::error::Result;
use super::hash::Fnv64;
use super::layout::WorldDesc;
use super::noise::{fbm, gradient_noise, ridged_from, smoothstep, Lattice, Octaves};
use super::png16::check_params;
use super::source::{catmull_rom, Ground, HeightSource};

/// Bumped whenever the generator's output changes, so caches rebake.
const GENERATOR_VERSION: u64 = 2;
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
/// Nodes of the coarse (eroded) grid along the world's longer side, at most.
pub const SHAPE_NODES: usize = 513;
/// The coarse grid's finest spacing, metres: water and gravity shape forms
/// this size and larger (20 m: a 10 km world's grid has 513 nodes a side).
const SHAPE_MIN_SPACING_M: f64 = 20.0;
/// Ridged octaves shorter than this many grid spacings are not on the grid:
/// each sample adds them on top.
const FINE_BELOW_SPACINGS: f64 = 4.0;
/// Drained area (m^2) where ground starts to be wet, and where it is fully:
/// a gully's head, and a valley's floor.
const WET_AREA_M2: [f64; 2] = [2.0e4, 2.0e6];
/// Talus (metres of slid rock) from which ground is fully scree.
const TALUS_FULL_M: f64 = 3.0;
/// Basin fill (metres) from which a floor is flat: no fine octaves there.
const FLAT_FILL_M: f64 = 2.0;

/// The coarse grid's channels per node (bicubic between nodes).
const H: usize = 0;
const WARP_X: usize = 1;
const WARP_Y: usize = 2;
const WEIGHT: usize = 3;
const DETAIL: usize = 4;
const WET: usize = 5;
const TALUS: usize = 6;
const CHANNELS: usize = 8;

/// Procedural height field; output always lies in the height range.
#[derive(Clone, Debug)]
pub struct ProceduralSource {
    seed: u64,
    extent_m: [f64; 2],
    height_range_m: [f32; 2],
    terraces: bool,
    shape: Arc<Shape>,
}

/// The eroded coarse grid and what the samples need of it.
struct Shape {
    nx: usize,
    ny: usize,
    spacing_m: f64,
    /// The ridged octaves on the grid; the rest are per sample.
    coarse_octaves: u32,
    nodes: Vec<[f32; CHANNELS]>,
    receivers: Vec<u32>,
}

impl std::fmt::Debug for Shape {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Shape({} x {} nodes, {} m)", self.nx, self.ny, self.spacing_m)
    }
}

/// The drainage the generator's erosion left on its coarse grid: node
/// (i, j) lies at (i, j) times the spacing, its water flows to
/// `receivers[j * nodes[0] + i]` (border nodes name themselves).
#[derive(Clone, Debug)]
pub struct FlowNetwork {
    pub nodes: [usize; 2],
    pub spacing_m: f64,
    /// The eroded heights, metres (before the fine octaves).
    pub heights_m: Vec<f32>,
    pub receivers: Vec<u32>,
}

impl ProceduralSource {
    /// Fails on a non-finite or empty extent or height range. Erodes the
    /// coarse grid first (about 2 s for 513 x 513 nodes on 2 cores).
    pub fn new(seed: u64, extent_m: [f64; 2], height_range_m: [f32; 2]) -> Result<Self> {
        check_params(extent_m, height_range_m)?;
        Ok(Self::build(seed, extent_m, height_range_m))
    }

    /// The default 10 km world and its generator.
    pub fn default_world(seed: u64) -> (WorldDesc, Self) {
        let w = WorldDesc::default();
        (w, Self::build(seed, w.extent_m, w.height_range_m))
    }

    /// Terraced cliffs (flat treads, near-vertical risers) where a mask is
    /// on, over the eroded ground: a scene option, off by default.
    pub fn with_terraces(mut self, on: bool) -> Self {
        self.terraces = on;
        self
    }

    /// The erosion's drainage, for tests and tools that check it.
    pub fn flow_network(&self) -> FlowNetwork {
        let s = &self.shape;
        let [lo, hi] = self.height_range_m;
        let heights_m = s.nodes.iter().map(|n| lo + n[H] * (hi - lo)).collect();
        FlowNetwork { nodes: [s.nx, s.ny], spacing_m: s.spacing_m, heights_m, receivers: s.receivers.clone() }
    }

    fn build(seed: u64, extent_m: [f64; 2], height_range_m: [f32; 2]) -> Self {
        let shape = Arc::new(Shape::build(seed, extent_m, height_range_m));
        ProceduralSource { seed, extent_m, height_range_m, terraces: false, shape }
    }

    /// Normalised height in 0..1 before mapping to the height range.
    fn height01(&self, x: f64, y: f64, c: &mut Lattices) -> f64 {
        let g = self.shape.at::<{ DETAIL + 1 }>(x, y);
        let (weight, detail) = (g[WEIGHT].clamp(0.0, 1.0), g[DETAIL].max(0.0));
        let mut h = g[H];
        let fine_octaves = (MOUNTAIN_OCTAVES - self.shape.coarse_octaves) as usize;
        if detail > 0.0 && weight > 0.0 && fine_octaves > 0 {
            let (wx, wy) = ((x + g[WARP_X]) / MOUNTAIN_WAVELENGTH_M, (y + g[WARP_Y]) / MOUNTAIN_WAVELENGTH_M);
            let from = Octaves { first: self.shape.coarse_octaves, weight };
            h += detail * ridged_from(wx, wy, self.seed ^ 0x44, from, &mut c.fine[..fine_octaves]).0;
        }
        if self.terraces {
            let mask = gradient_noise(
                x / CLIFF_MASK_WAVELENGTH_M,
                y / CLIFF_MASK_WAVELENGTH_M,
                self.seed ^ 0x66,
                &mut c.cliff,
            );
            let cliff = smoothstep(0.05, 0.3, mask);
            if cliff > 0.0 {
                let t = h / TERRACE_STEP;
                let terraced = (t.floor() + t.fract().powi(TERRACE_SHARPNESS)) * TERRACE_STEP;
                h += cliff * (terraced - h);
            }
        }
        h.clamp(0.0, 1.0)
    }

    fn sample_with(&self, x_m: f64, y_m: f64, c: &mut Lattices) -> f32 {
        let x = x_m.clamp(0.0, self.extent_m[0]);
        let y = y_m.clamp(0.0, self.extent_m[1]);
        let h = if x.is_finite() && y.is_finite() { self.height01(x, y, c) } else { 0.0 };
        let [lo, hi] = self.height_range_m;
        (f64::from(lo) + h * f64::from(hi - lo)) as f32
    }
}

impl Shape {
    fn build(seed: u64, extent_m: [f64; 2], height_range_m: [f32; 2]) -> Shape {
        let longer = extent_m[0].max(extent_m[1]);
        let spacing_m = (longer / (SHAPE_NODES - 1) as f64).max(SHAPE_MIN_SPACING_M);
        let count = |e: f64| ((e / spacing_m).ceil() as usize + 1).clamp(2, SHAPE_NODES);
        let (nx, ny) = (count(extent_m[0]), count(extent_m[1]));
        let coarse_octaves = (0..MOUNTAIN_OCTAVES)
            .take_while(|&o| MOUNTAIN_WAVELENGTH_M / f64::from(1u32 << o) >= FINE_BELOW_SPACINGS * spacing_m)
            .count() as u32;
        let mut nodes: Vec<[f32; CHANNELS]> = (0..nx * ny)
            .into_par_iter()
            .map_init(Lattices::default, |c, k| {
                let (x, y) = ((k % nx) as f64 * spacing_m, (k / nx) as f64 * spacing_m);
                large_forms(seed, coarse_octaves, x, y, c)
            })
            .collect();
        let relief_m = f64::from(height_range_m[1] - height_range_m[0]);
        let heights_m = nodes.iter().map(|n| f64::from(n[H]) * relief_m).collect();
        let mut terrain = Terrain { nx, ny, spacing_m, heights_m };
        let shaped = terrain.erode();
        let cell_m2 = spacing_m * spacing_m;
        let [wet_from, wet_full] = WET_AREA_M2.map(f64::ln);
        for (k, n) in nodes.iter_mut().enumerate() {
            let wet = smoothstep(wet_from, wet_full, (shaped.drained_cells[k] * cell_m2).ln());
            let talus = (shaped.talus_m[k] / TALUS_FULL_M).min(1.0);
            let flat = smoothstep(0.0, FLAT_FILL_M, shaped.filled_m[k]);
            let calm = (1.0 - 0.75 * wet) * (1.0 - flat) * (1.0 - 0.5 * talus);
            n[H] = (terrain.heights_m[k] / relief_m) as f32;
            n[DETAIL] *= calm as f32;
            n[WET] = wet as f32;
            n[TALUS] = talus as f32;
        }
        Shape { nx, ny, spacing_m, coarse_octaves, nodes, receivers: shaped.receivers }
    }

    /// The first `N` channels at a point, Catmull-Rom between the nodes
    /// (indices clamp at the grid's edge): a height needs those up to
    /// [`DETAIL`], the materials also [`WET`] and [`TALUS`].
    fn at<const N: usize>(&self, x: f64, y: f64) -> [f64; N] {
        let (u, v) = (x / self.spacing_m, y / self.spacing_m);
        let (u0, v0) = (u.floor(), v.floor());
        let (wu, wv) = (catmull_rom(u - u0), catmull_rom(v - v0));
        let (iu, iv) = (u0 as isize, v0 as isize);
        let clamp = |i: isize, n: usize| i.clamp(0, n as isize - 1) as usize;
        let mut out = [0.0; N];
        for (b, wy) in wv.iter().enumerate() {
            let row = clamp(iv + b as isize - 1, self.ny) * self.nx;
            for (a, wx) in wu.iter().enumerate() {
                let node = &self.nodes[row + clamp(iu + a as isize - 1, self.nx)];
                let w = wx * wy;
                for (o, n) in out.iter_mut().zip(node) {
                    *o += w * f64::from(*n);
                }
            }
        }
        out
    }
}

/// The large forms at a grid node, before erosion: continents, ridged
/// mountains down to the grid's octaves, carved valleys. Also what the fine
/// octaves need there: the warp, the ridged weight the coarse octaves
/// left, and the amplitude they get.
fn large_forms(seed: u64, coarse_octaves: u32, x: f64, y: f64, c: &mut Lattices) -> [f32; CHANNELS] {
    let s = seed;
    let warp = [
        fbm(x / 2500.0, y / 2500.0, s ^ 0x11, &mut c.warp_x),
        fbm(x / 2500.0 + 17.3, y / 2500.0 - 9.1, s ^ 0x22, &mut c.warp_y),
    ];
    let (wx, wy) = (x + WARP_M * warp[0], y + WARP_M * warp[1]);
    let continent = fbm(x / CONTINENT_WAVELENGTH_M, y / CONTINENT_WAVELENGTH_M, s ^ 0x33, &mut c.continent);
    let mountain_mask = smoothstep(-0.35, 0.45, continent);
    // Lowlands have no mountains: skipping their ridges changes nothing.
    let (ridges, weight) = if mountain_mask > 0.0 {
        let from = Octaves { first: 0, weight: 1.0 };
        let lattices = &mut c.fine[..coarse_octaves as usize];
        ridged_from(wx / MOUNTAIN_WAVELENGTH_M, wy / MOUNTAIN_WAVELENGTH_M, s ^ 0x44, from, lattices)
    } else {
        (0.0, 0.0)
    };
    let h = 0.12 + 0.08 * continent + mountain_mask * 0.85 * ridges;
    // Valleys: where a warped noise crosses zero, carve a smooth trough.
    let v = fbm(wx / VALLEY_WAVELENGTH_M, wy / VALLEY_WAVELENGTH_M, s ^ 0x55, &mut c.valley).abs();
    let keep = 0.75 + 0.25 * smoothstep(0.0, 0.15, v);
    let mut n = [0.0; CHANNELS];
    n[H] = (0.05 + (h - 0.05) * keep).clamp(0.0, 1.0) as f32;
    n[WARP_X] = (wx - x) as f32;
    n[WARP_Y] = (wy - y) as f32;
    n[WEIGHT] = weight as f32;
    n[DETAIL] = (mountain_mask * 0.85 * keep) as f32;
    n
}

impl HeightSource for ProceduralSource {
    fn sample(&self, x_m: f64, y_m: f64) -> f32 {
        self.sample_with(x_m, y_m, &mut Lattices::default())
    }

    /// Heights are a 0..1 field (clamped) over the source's range.
    fn range_in(&self, _bounds_m: [f64; 4]) -> Option<[f32; 2]> {
        Some(self.height_range_m)
    }

    /// Neighbouring points share most lattice cells, so the row keeps each
    /// noise's last cell and its gradients: the same values, without the
    /// hashing.
    fn sample_row(&self, xs: &[f64], y_m: f64, out: &mut [f32]) {
        let mut c = Lattices::default();
        for (x, o) in xs.iter().zip(out) {
            *o = self.sample_with(*x, y_m, &mut c);
        }
    }

    /// Wet where much ground drains through, talus where rock slid to.
    fn ground(&self, x_m: f64, y_m: f64) -> Ground {
        let x = x_m.clamp(0.0, self.extent_m[0]);
        let y = y_m.clamp(0.0, self.extent_m[1]);
        if !(x.is_finite() && y.is_finite()) {
            return Ground::default();
        }
        let g = self.shape.at::<{ TALUS + 1 }>(x, y);
        Ground { wet: g[WET].clamp(0.0, 1.0) as f32, talus: g[TALUS].clamp(0.0, 1.0) as f32 }
    }

    fn id_hash(&self) -> u64 {
        Fnv64::new()
            .u64(GENERATOR_VERSION)
            .u64(self.seed)
            .u64(u64::from(self.terraces))
            .f64(self.extent_m[0])
            .f64(self.extent_m[1])
            .f64(f64::from(self.height_range_m[0]))
            .f64(f64::from(self.height_range_m[1]))
            .finish()
    }
}

/// One [`Lattice`] per noise octave of the generator.
#[derive(Default)]
struct Lattices {
    warp_x: [Lattice; 3],
    warp_y: [Lattice; 3],
    continent: [Lattice; 3],
    fine: [Lattice; MOUNTAIN_OCTAVES as usize],
    valley: [Lattice; 2],
    cliff: Lattice,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_row_samples_bit_for_bit_as_points_do() {
        let (_, src) = ProceduralSource::default_world(3);
        let src = src.with_terraces(true);
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

//! The finest surface vista can draw, on the CPU: the Catmull-Rom surface
//! of the world's R16-rounded LOD-0 samples, evaluated on the lattice of the
//! deepest refinement below LOD 0 (`REFINE_LEVELS`: a quarter of a sample
//! apart) and drawn there as the diamond-split triangles the refined
//! patches use. It is what the error tree measures a node's triangles
//! against (`world::ErrorTree`), so `vista bench accuracy` splits a frame's
//! error with it: drawn surface against this one (the LOD part, which the
//! target error bounds) and this one against the source (the
//! representation part, which no LOD choice removes).
//!
//! Shares only the sample positions and the R16 rounding with the bake.

use crate::shaders::consts::REFINE_LEVELS;
use crate::world::{HeightSource, WorldDesc};
use std::collections::HashMap;
use std::sync::Mutex;

/// Catmull-Rom weights of the four taps at t in [0, 1].
fn catmull_rom(t: f64) -> [f64; 4] {
    let (t2, t3) = (t * t, t * t * t);
    [0.5 * (-t3 + 2.0 * t2 - t), 0.5 * (3.0 * t3 - 5.0 * t2 + 2.0), 0.5 * (-3.0 * t3 + 4.0 * t2 + t), 0.5 * (t3 - t2)]
}

/// LOD-0 sample (i, j) of `world` as the bake stores it: its position
/// clamped to the extent, rounded to R16.
pub fn stored_post(world: &WorldDesc, source: &dyn HeightSource, i: i64, j: i64) -> f64 {
    let [x, y] = world.sample_pos(i, j);
    let [ex, ey] = world.extent_m;
    let v = source.sample(x.clamp(0.0, ex), y.clamp(0.0, ey));
    f64::from(world.decode_height(world.encode_height(v)))
}

/// [`HeightSource`] of the finest surface of `world` sampled from `source`.
pub struct FinestSurface<'a> {
    world: WorldDesc,
    source: &'a dyn HeightSource,
    /// Decoded LOD-0 samples by index, as the bake rounds them.
    samples: Mutex<HashMap<(i64, i64), f64>>,
}

impl<'a> FinestSurface<'a> {
    pub fn new(world: &WorldDesc, source: &'a dyn HeightSource) -> Self {
        FinestSurface { world: *world, source, samples: Mutex::new(HashMap::new()) }
    }

    /// LOD-0 sample (i, j) as the bake stores it (position clamped to the
    /// extent, rounded to R16), from `cache` or the source.
    fn sample_at(&self, cache: &mut HashMap<(i64, i64), f64>, i: i64, j: i64) -> f64 {
        *cache.entry((i, j)).or_insert_with(|| stored_post(&self.world, self.source, i, j))
    }

    /// The Catmull-Rom surface at lattice point (u, v) of the finest
    /// refinement (units of 2^-REFINE_LEVELS samples): along x over four
    /// rows, then along y.
    fn lattice(&self, u: i64, v: i64) -> f64 {
        let r = REFINE_LEVELS;
        let (ci, cj) = (u >> r, v >> r);
        let mask = (1i64 << r) - 1;
        if u & mask == 0 && v & mask == 0 {
            // On a post every weight but one is 0: the sample itself.
            let mut cache = self.samples.lock().unwrap_or_else(|e| e.into_inner());
            return self.sample_at(&mut cache, ci, cj);
        }
        let scale = f64::from(1u32 << r);
        let wx = catmull_rom((u - (ci << r)) as f64 / scale);
        let wy = catmull_rom((v - (cj << r)) as f64 / scale);
        let mut cache = self.samples.lock().unwrap_or_else(|e| e.into_inner());
        (0..4)
            .map(|b| {
                let row: f64 =
                    (0..4).map(|a| wx[a] * self.sample_at(&mut cache, ci + a as i64 - 1, cj + b as i64 - 1)).sum();
                wy[b] * row
            })
            .sum()
    }

    /// The finest surface at lattice point (u, v) of the deepest refinement
    /// (units of 2^-REFINE_LEVELS samples from the grid origin).
    pub fn at_lattice(&self, u: i64, v: i64) -> f64 {
        self.lattice(u, v)
    }

    /// Height at (x, y) of the diamond-split triangles of level `level`'s
    /// grid: its vertices 2^level samples apart (0 = LOD 0, negative = the
    /// refinements below it, down to -REFINE_LEVELS, the finest surface
    /// itself), each quad split as the level draws it.
    pub fn level(&self, level: i32, x_m: f64, y_m: f64) -> f64 {
        let r = REFINE_LEVELS as i32;
        assert!(level >= -r, "level {level} is finer than the finest surface");
        let step = 1i64 << (level + r);
        let scale = f64::from(1u32 << r) / step as f64;
        let [ox, oy] = self.world.grid_origin_m;
        let u = (x_m - ox) / self.world.spacing_m * scale;
        let v = (y_m - oy) / self.world.spacing_m * scale;
        let (qx, qy) = (u.floor() as i64, v.floor() as i64);
        let (fu, fv) = (u - qx as f64, v - qy as f64);
        let at = |a: i64, b: i64| self.lattice(a * step, b * step);
        let h = [at(qx, qy), at(qx + 1, qy), at(qx, qy + 1), at(qx + 1, qy + 1)];
        crate::world::diamond(h, fu, fv, (qx + qy).rem_euclid(2) == 0)
    }
}

impl HeightSource for FinestSurface<'_> {
    fn sample(&self, x_m: f64, y_m: f64) -> f32 {
        self.level(-(REFINE_LEVELS as i32), x_m, y_m) as f32
    }

    fn id_hash(&self) -> u64 {
        self.source.id_hash() ^ self.world.hash() ^ 0xf1e5
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::GridSource;

    #[test]
    fn the_finest_surface_passes_through_every_sample() {
        // 4 x 3 pixels at their own size (2 m): the samples are the pixels.
        let heights = vec![1.0, 7.0, -3.0, 4.0, 2.5, 0.0, 9.0, -1.0, 5.0, 6.0, 2.0, 3.0];
        let world = WorldDesc {
            extent_m: [8.0, 6.0],
            height_range_m: [-10.0, 10.0],
            spacing_m: 2.0,
            lod_count: 1,
            ..WorldDesc::default()
        }
        .with_posts([2.0, 2.0]);
        let src = GridSource::new(4, 3, heights.clone(), [8.0, 6.0]);
        let f = FinestSurface::new(&world, &src);
        let step = 20.0 / 65535.0;
        for j in 0..3 {
            for i in 0..4 {
                let [x, y] = world.sample_pos(i, j);
                let px = heights[((2 - j) * 4 + i) as usize];
                assert!((f64::from(f.sample(x, y)) - f64::from(px)).abs() <= step, "({i}, {j})");
            }
        }
    }
}

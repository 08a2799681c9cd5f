//! The canopy: over a grid of the world, how high the trees' and bushes'
//! tops stand above their feet (the meshes' tops, `meshes::canopy_top`).
//! With effect `shadows` on, the sun's march adds it to the terrain's
//! heights (sun_shadows.comp, variant CANOPY), so trees and bushes cast
//! into the terrain's shadows the way seed 004's terrain casts: as a
//! height field, not as meshes. A cell holds the highest top at its centre
//! and between centres the march interpolates bilinearly: on a crown's
//! flank (a cone's) that is the flank itself, so a crown's sunlit side
//! does not shade itself (a cell's highest point would stand cells above
//! it). Crowns narrower than half a cell (Mont Blanc's 14.6 m cells) may
//! miss every centre: their cell holds at least their mean height over
//! it (the volume under their tops over its area), so a forest on coarse
//! cells is a canopy of its mean height. Beyond the grid (a border of empty cells) there is none. Heights are above the instance's
//! foot: on a slope a crown's downhill edge casts a little high and its
//! uphill edge a little low, by the slope over its radius.

use super::{meshes::canopy_top, VegetationSet, VegetationTypeGpu};
use crate::world::vegetation::VegetationKind;

/// Most cells along a side: the cells grow past `canopy_cell_m` to keep
/// the grid within this (Mont Blanc's 60 km at 14.6 m).
pub const MAX_SIDE: u32 = 4096;

/// The canopy's grid.
#[derive(Debug, Clone, PartialEq)]
pub struct CanopyGrid {
    /// World metres of cell (0, 0)'s south-west corner.
    pub origin_m: [f32; 2],
    pub cell_m: f32,
    pub size: [u32; 2],
    /// Row-major, south row first: metres above the foot of the instance
    /// that stands highest over the cell.
    pub heights: Vec<f32>,
    /// The tallest of them.
    pub top_m: f32,
}

/// A mesh's widest radius and the volume under its top, over its height
/// (and its cube).
fn shape(kind: VegetationKind) -> (f32, f32) {
    let (mut r, mut volume) = (0.0, 0.0);
    while let Some(top) = canopy_top(kind, r + 5e-4) {
        volume += top * std::f32::consts::TAU * (r + 5e-4) * 1e-3;
        r += 1e-3;
    }
    (r, volume)
}

impl CanopyGrid {
    /// The canopy of `set`'s instances with their types' heights, in cells
    /// of `cell_m` or larger; None without an instance.
    pub fn raster(set: &VegetationSet, types: &[VegetationTypeGpu], cell_m: f32) -> Option<CanopyGrid> {
        let kinds: Vec<VegetationKind> = set.types.iter().map(|t| t.1).collect();
        let shapes: Vec<(f32, f32)> = kinds.iter().map(|k| shape(*k)).collect();
        let size_of = |i: &crate::world::vegetation::Instance| types[i.ty as usize].height_m * i.scale;
        let reach = |i| size_of(i) * shapes[i.ty as usize].0;
        let (mut lo, mut hi) = ([f32::MAX; 2], [f32::MIN; 2]);
        for i in &set.instances {
            for a in 0..2 {
                lo[a] = lo[a].min(i.position[a] - reach(i));
                hi[a] = hi[a].max(i.position[a] + reach(i));
            }
        }
        if set.instances.is_empty() {
            return None;
        }
        // One empty cell on every side: beyond the grid there is nothing.
        let span = (hi[0] - lo[0]).max(hi[1] - lo[1]);
        let cell = cell_m.max(span / (MAX_SIDE - 3) as f32);
        let origin_m = [lo[0] - cell, lo[1] - cell];
        let size = [0, 1].map(|a| (((hi[a] - origin_m[a]) / cell).ceil() as u32 + 1).min(MAX_SIDE));
        let mut g =
            CanopyGrid { origin_m, cell_m: cell, size, heights: vec![0.0; (size[0] * size[1]) as usize], top_m: 0.0 };
        // Crowns within a cell's half: each cell's mean top over them,
        // no higher than the tallest (a forest's canopy on coarse cells).
        let mut mean = vec![(0.0f32, 0.0f32); g.heights.len()];
        for i in &set.instances {
            let h = size_of(i);
            if reach(i) < 0.5 * cell {
                let k = g.index(i.position);
                mean[k] = (mean[k].0 + shapes[i.ty as usize].1 * h.powi(3) / (cell * cell), mean[k].1.max(h));
            }
            g.stamp(i.position, h, kinds[i.ty as usize], reach(i));
        }
        for (h, (sum, tallest)) in g.heights.iter_mut().zip(mean) {
            *h = h.max(sum.min(tallest));
        }
        g.top_m = g.heights.iter().copied().fold(0.0, f32::max);
        Some(g)
    }

    /// The cell holding `p`.
    fn index(&self, p: [f32; 3]) -> usize {
        let c = [0, 1]
            .map(|a| ((p[a] - self.origin_m[a]) / self.cell_m).floor().clamp(0.0, (self.size[a] - 1) as f32) as u32);
        (c[1] * self.size[0] + c[0]) as usize
    }

    /// Raises the cells whose centre lies within `reach` of `foot` to the
    /// mesh's top there.
    fn stamp(&mut self, foot: [f32; 3], height: f32, kind: VegetationKind, reach: f32) {
        let cell = |v: f32, a: usize| {
            ((v - self.origin_m[a]) / self.cell_m).floor().clamp(0.0, (self.size[a] - 1) as f32) as u32
        };
        for y in cell(foot[1] - reach, 1)..=cell(foot[1] + reach, 1) {
            for x in cell(foot[0] - reach, 0)..=cell(foot[0] + reach, 0) {
                let centre = [x, y].map(|c| (c as f32 + 0.5) * self.cell_m);
                let d = [0, 1].map(|a| centre[a] - (foot[a] - self.origin_m[a]));
                let rho = d[0].hypot(d[1]);
                if let Some(top) = canopy_top(kind, rho / height) {
                    let k = (y * self.size[0] + x) as usize;
                    self.heights[k] = self.heights[k].max(top * height);
                }
            }
        }
    }

    /// The heights as the GPU reads them: f16 pairs, the first in the low bits.
    pub fn packed(&self) -> Vec<u32> {
        self.heights
            .chunks(2)
            .map(|c| {
                let h = |k: usize| u32::from(half::f16::from_f32(c.get(k).copied().unwrap_or(0.0)).to_bits());
                h(0) | h(1) << 16
            })
            .collect()
    }

    /// (corner x, corner y, cells per metre, tallest top): the march's
    /// `canopy` constants.
    pub fn map(&self) -> [f32; 4] {
        [self.origin_m[0], self.origin_m[1], 1.0 / self.cell_m, self.top_m]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::vegetation::Instance;

    fn set(instances: Vec<Instance>) -> VegetationSet {
        let types = vec![("spruce".into(), VegetationKind::Tree), ("juniper".into(), VegetationKind::Bush)];
        VegetationSet { folder: "t".into(), types, instances }
    }

    fn one(ty: u32, at: [f32; 3], scale: f32) -> Instance {
        Instance { position: at, yaw_rad: 0.0, scale, ty, tint: 0, cell: 0 }
    }

    /// A 16 m tree: a cell whose centre is r out holds the cone there
    /// (16 - 12.8 r / 4.8 m), cells past its 4.8 m radius nothing, and the
    /// border is empty.
    #[test]
    fn a_tree_raises_the_cells_under_its_crown_to_its_cone() {
        let p = super::super::VegetationDrawParams::default();
        let s = set(vec![one(0, [100.5, 200.5, 50.0], 1.0), one(1, [140.5, 200.5, 50.0], 1.0)]);
        let g = CanopyGrid::raster(&s, &p.types_gpu(&s), 1.0).unwrap();
        assert_eq!(g.cell_m, 1.0);
        let at = |x: f32, y: f32| {
            let c = [(x - g.origin_m[0]) / g.cell_m, (y - g.origin_m[1]) / g.cell_m].map(|v| v.floor() as u32);
            g.heights[(c[1] * g.size[0] + c[0]) as usize]
        };
        // Cell centres: the grid's corner is the crowns' corner less a
        // cell, not a whole metre.
        let centre = |v: f32, a: usize| g.origin_m[a] + (((v - g.origin_m[a]) / g.cell_m).floor() + 0.5) * g.cell_m;
        let cone = |x: f32, y: f32| {
            let r = (centre(x, 0) - 100.5).hypot(centre(y, 1) - 200.5);
            if r <= 4.8 {
                16.0 - 12.8 * r / 4.8
            } else {
                0.0
            }
        };
        for (x, y) in [(100.5, 200.5), (103.5, 200.5), (102.2, 198.0), (104.9, 201.0), (106.5, 200.5)] {
            assert!((at(x, y) - cone(x, y)).abs() < 1e-3, "({x}, {y}): {} against {}", at(x, y), cone(x, y));
        }
        assert!(at(106.5, 200.5) == 0.0 && at(100.5, 200.5) > 14.0);
        let r = (centre(140.5, 0) - 140.5).hypot(centre(200.5, 1) - 200.5) / 2.0;
        let bush = 2.0 * (0.45 + 0.5 * (1.0 - (r / 0.55).powi(2)).sqrt());
        assert!((at(140.5, 200.5) - bush).abs() < 1e-4, "the bush's top: {} against {bush}", at(140.5, 200.5));
        assert_eq!(g.top_m, at(100.5, 200.5));
        let w = g.size[0] as usize;
        assert!(g.heights[..w].iter().chain(&g.heights[g.heights.len() - w..]).all(|h| *h == 0.0), "border");
        assert!(g.heights.chunks(w).all(|row| row[0] == 0.0 && row[w - 1] == 0.0), "border");
        let packed = g.packed();
        let k = g.heights.iter().position(|h| *h == g.top_m).unwrap();
        assert_eq!(packed[k / 2] >> (16 * (k % 2)) & 0xffff, u32::from(half::f16::from_f32(g.top_m).to_bits()));
    }

    #[test]
    fn the_grid_stays_within_its_side_and_none_without_instances() {
        let p = super::super::VegetationDrawParams::default();
        let s = set(vec![one(0, [0.0, 0.0, 0.0], 1.0), one(0, [60_000.0, 100.0, 0.0], 1.0)]);
        let g = CanopyGrid::raster(&s, &p.types_gpu(&s), 1.0).unwrap();
        assert!(g.size[0] <= MAX_SIDE && g.cell_m > 14.0, "{:?} cells of {} m", g.size, g.cell_m);
        // Too narrow for a 14.6 m cell: its volume over the cell's area.
        let (_, volume) = shape(VegetationKind::Tree);
        let want = volume * 16f32.powi(3) / (g.cell_m * g.cell_m);
        let k = g.index([0.0, 0.0, 0.0]);
        let centre =
            [0, 1].map(|a| g.origin_m[a] + ((k as u32 / [1, g.size[0]][a] % g.size[0]) as f32 + 0.5) * g.cell_m);
        let r = centre[0].hypot(centre[1]);
        let at_centre = if r <= 4.8 { 16.0 - 12.8 * r / 4.8 } else { 0.0 };
        let got = g.heights[k];
        assert!((got - want.max(at_centre)).abs() < 0.01 * want, "{got} m against {want} (mean), {at_centre} (centre)");
        // The cone's volume: pi r^2 (base + (1 - base) / 3) in unit heights.
        let cone = std::f32::consts::PI * 0.09 * (0.2 + 0.8 / 3.0);
        assert!((volume - cone).abs() < 1e-3 * cone, "{volume} against {cone}");
        assert_eq!(CanopyGrid::raster(&set(vec![]), &[], 1.0), None);
    }
}

//! The generator's grid over the world: a cell's height (the source at its
//! centre), slope and normal from its neighbours, material (the bake's
//! rules), and whether it is a hole.

use glam::DVec3;
use rayon::prelude::*;

use crate::world::bake::is_hole_at;
use crate::world::holes::Hole;
use crate::world::layout::WorldDesc;
use crate::world::material_rules::{MaterialRules, Site};
use crate::world::source::HeightSource;

/// The cells over a world: `size` cells of `cell_m`, cell (i, j)'s centre
/// at ((i + 0.5) cell, (j + 0.5) cell), row 0 the south edge.
#[derive(Clone, Debug)]
pub struct HeightField {
    pub cell_m: f64,
    pub size: [usize; 2],
    pub z: Vec<f32>,
    pub hole: Vec<bool>,
    /// The material the bake's rules give the cell ([`crate::world::Material`] id).
    pub material: Vec<u8>,
    /// Highest cell (m): a march above it can stop.
    pub z_max: f32,
}

impl HeightField {
    /// Samples `source` at every cell's centre of a grid of `cell_m` over
    /// `world` (the last row and column may reach past the extent: their
    /// centres inside it are kept, the rest are holes).
    pub fn sample(
        world: &WorldDesc,
        source: &dyn HeightSource,
        holes: &[Hole],
        rules: &MaterialRules,
        cell_m: f64,
    ) -> Self {
        let size = world.extent_m.map(|e| (e / cell_m).ceil().max(1.0) as usize);
        let n = size[0] * size[1];
        let (mut z, mut hole) = (vec![0f32; n], vec![false; n]);
        let xs: Vec<f64> = (0..size[0]).map(|i| (i as f64 + 0.5) * cell_m).collect();
        z.par_chunks_mut(size[0]).zip(hole.par_chunks_mut(size[0])).enumerate().for_each(|(j, (zr, hr))| {
            let y = (j as f64 + 0.5) * cell_m;
            let clamped: Vec<f64> = xs.iter().map(|x| x.min(world.extent_m[0])).collect();
            source.sample_row(&clamped, y.min(world.extent_m[1]), zr);
            for (i, h) in hr.iter_mut().enumerate() {
                *h = is_hole_at(world, source, holes, [xs[i], y], cell_m) || !zr[i].is_finite();
            }
        });
        // Holes' heights too: a march reads them, and must not stop below one.
        let z_max = z.iter().filter(|z| z.is_finite()).copied().fold(f32::MIN, f32::max);
        let mut field = HeightField { cell_m, size, z, hole, material: vec![0; n], z_max };
        field.material = (0..n)
            .into_par_iter()
            .map(|k| {
                let (i, j) = (k % size[0], k / size[0]);
                let n = field.normal(i, j);
                let slope_deg = n.z.clamp(-1.0, 1.0).acos().to_degrees() as f32;
                let ground = source.ground(xs[i], (j as f64 + 0.5) * cell_m);
                rules.material_at(&Site { slope_deg, altitude_m: field.z[k], ground }) as u8
            })
            .collect();
        field
    }

    /// A field from given heights (tests: analytic surfaces).
    pub fn from_heights(cell_m: f64, size: [usize; 2], z: Vec<f32>) -> Self {
        let n = size[0] * size[1];
        assert_eq!(z.len(), n);
        let z_max = z.iter().copied().fold(f32::MIN, f32::max);
        HeightField { cell_m, size, z, hole: vec![false; n], material: vec![0; n], z_max }
    }

    pub fn index(&self, i: usize, j: usize) -> usize {
        j * self.size[0] + i
    }

    /// Height of cell (i, j) with indices clamped to the grid; a hole
    /// reads as its own stored value (vegetation never grows there).
    pub fn at(&self, i: isize, j: isize) -> f64 {
        let i = i.clamp(0, self.size[0] as isize - 1) as usize;
        let j = j.clamp(0, self.size[1] as isize - 1) as usize;
        f64::from(self.z[self.index(i, j)])
    }

    /// Height at a point (m from the world's corner), bilinear between
    /// cell centres, clamped at the grid's edge.
    pub fn bilinear(&self, x_m: f64, y_m: f64) -> f64 {
        let (u, v) = (x_m / self.cell_m - 0.5, y_m / self.cell_m - 0.5);
        let (i, j) = (u.floor(), v.floor());
        let (fu, fv) = (u - i, v - j);
        let (i, j) = (i as isize, j as isize);
        let lo = self.at(i, j) * (1.0 - fu) + self.at(i + 1, j) * fu;
        let hi = self.at(i, j + 1) * (1.0 - fu) + self.at(i + 1, j + 1) * fu;
        lo * (1.0 - fv) + hi * fv
    }

    /// Unit normal of cell (i, j): central differences (one-sided at the
    /// grid's edge).
    pub fn normal(&self, i: usize, j: usize) -> DVec3 {
        let (i, j) = (i as isize, j as isize);
        let span = |lo: isize, hi: isize, n: usize| ((hi.min(n as isize - 1) - lo.max(0)) as f64).max(1.0);
        let dx = (self.at(i + 1, j) - self.at(i - 1, j)) / (span(i - 1, i + 1, self.size[0]) * self.cell_m);
        let dy = (self.at(i, j + 1) - self.at(i, j - 1)) / (span(j - 1, j + 1, self.size[1]) * self.cell_m);
        DVec3::new(-dx, -dy, 1.0).normalize()
    }

    /// Slope of cell (i, j) in degrees.
    pub fn slope_deg(&self, i: usize, j: usize) -> f64 {
        self.normal(i, j).z.clamp(-1.0, 1.0).acos().to_degrees()
    }
}

//! The sun's share of a cell: the day's trajectory for a latitude and a
//! day of the year, sampled at equal times between sunrise and sunset, and
//! for each sample whether the cell faces the sun and no ground lies
//! between (a march towards the sun over the field's heights, bilinear
//! between cell centres, as the shadow pass marches node heights).
//! Seed 004: "for each cell compute the percentage of the sun's
//! trajectory in which it is in shadow".

use glam::DVec3;

use super::field::HeightField;
use super::resource::Window;
use crate::world::error::Result;

/// Marches the sun elsewhere than this CPU (the GPU: effect vegetation's
/// `vegetation_sun`): for each window, its cells' lit share row-major, as
/// [`lit_share`] gives them to the marcher's rounding.
pub trait SunMarch {
    /// Names the marcher (and its device) in the tiles' key: a tile one
    /// marched is not reused by a run with another.
    fn name(&self) -> String;
    fn march(&self, field: &HeightField, windows: &[Window], path: &[DVec3], reach_m: f64) -> Result<Vec<Vec<f32>>>;
}

/// Unit vectors towards the sun (x east, y north, z up) at `samples`
/// equal steps of the hour angle between sunrise and sunset, each at its
/// step's middle; none in a polar night, the whole day round in a polar day.
pub fn trajectory(latitude_deg: f64, day_of_year: u32, samples: u32) -> Vec<DVec3> {
    // Declination: Cooper's approximation (the solstices at +-23.44 deg).
    let decl = (-23.44f64).to_radians() * (std::f64::consts::TAU * (f64::from(day_of_year) + 10.0) / 365.0).cos();
    let lat = latitude_deg.to_radians();
    let cos_h0 = -(lat.tan() * decl.tan());
    let h0 = if cos_h0 >= 1.0 {
        return Vec::new();
    } else if cos_h0 <= -1.0 {
        std::f64::consts::PI
    } else {
        cos_h0.acos()
    };
    (0..samples)
        .map(|s| {
            let h = -h0 + (f64::from(s) + 0.5) * 2.0 * h0 / f64::from(samples);
            let east = -decl.cos() * h.sin();
            let north = lat.cos() * decl.sin() - lat.sin() * decl.cos() * h.cos();
            let up = lat.sin() * decl.sin() + lat.cos() * decl.cos() * h.cos();
            DVec3::new(east, north, up).normalize()
        })
        .filter(|d| d.z > 0.0)
        .collect()
}

/// Whether cell (i, j) sees the sun in direction `sun` (unit, z > 0):
/// it faces it, and a march towards it over the field finds no ground
/// above the ray within `reach_m` (nor before the ray clears the highest
/// cell).
pub fn lit(field: &HeightField, i: usize, j: usize, sun: DVec3, reach_m: f64) -> bool {
    if field.normal(i, j).dot(sun) <= 0.0 {
        return false;
    }
    let c = field.cell_m;
    let (x0, y0) = ((i as f64 + 0.5) * c, (j as f64 + 0.5) * c);
    let flat = (sun.x * sun.x + sun.y * sun.y).sqrt();
    if flat < 1e-9 {
        return true;
    }
    let (dx, dy, rise) = (sun.x / flat, sun.y / flat, sun.z / flat);
    // The ray leaves a little above the ground so a plane facing the sun
    // never shadows itself through rounding.
    let z0 = field.at(i as isize, j as isize) + 1e-3 * c;
    let extent = [field.size[0] as f64 * c, field.size[1] as f64 * c];
    let mut t = 0.5 * c;
    while t <= reach_m {
        let (x, y) = (x0 + dx * t, y0 + dy * t);
        let ray = z0 + rise * t;
        if ray > f64::from(field.z_max) || x < 0.0 || y < 0.0 || x > extent[0] || y > extent[1] {
            return true;
        }
        if field.bilinear(x, y) > ray {
            return false;
        }
        // A cell at a time near the cell, then growing by an eighth: the
        // farther the occluder, the larger it must be to matter.
        t += (0.5 * c).max(t * 0.125);
    }
    true
}

/// Share (0..1) of `path`'s samples in which cell (i, j) is lit; 0 when
/// the sun never rises.
pub fn lit_share(field: &HeightField, i: usize, j: usize, path: &[DVec3], reach_m: f64) -> f32 {
    if path.is_empty() {
        return 0.0;
    }
    let n = path.iter().filter(|s| lit(field, i, j, **s, reach_m)).count();
    n as f32 / path.len() as f32
}

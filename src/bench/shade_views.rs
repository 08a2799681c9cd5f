//! The views of `vista bench shade`, found on the CPU from the height
//! source among candidate views that are mostly terrain: "cliff wall" (the
//! most cliff pixels: the worst case for tiling, every tile needs cliff
//! shading), "mixed cliffs" (the share of cliff pixels nearest
//! `MIXED_CLIFFS`, as in a typical mountain view; absent when no candidate
//! has 10 to 60 %) and "no cliffs" (the fewest; ties: the most terrain). A coarse grid of eye rays is
//! marched through the height field; a hit is a cliff where the slope,
//! measured over the pixel's footprint, passes where the classification
//! starts giving cliff shading. It is an estimate for choosing views: the
//! benchmark reports the tile counts the GPU classification measured.

use crate::scene::shading::ShadeRules;
use crate::scene::view::Camera;
use crate::world::{HeightSource, WorldDesc};
use glam::DVec3;
use rayon::prelude::*;

/// Rays per candidate view (columns, rows).
const RAYS: [u32; 2] = [24, 14];
/// Candidate positions per world axis; each looks in four directions.
const GRID: u32 = 4;
/// The cliff share of terrain pixels the "mixed cliffs" view aims for.
const MIXED_CLIFFS: f64 = 0.3;

#[derive(Debug, Clone, serde::Serialize)]
pub struct ShadeView {
    pub name: String,
    pub camera: Camera,
    /// Estimated fraction of the view's rays that hit terrain, and of those
    /// the fraction that hit a slope shaded as cliff.
    pub terrain_fraction: f64,
    pub cliff_fraction: f64,
}

/// The views of a world for `rules`' cliff slope, named as above.
pub fn shade_views(world: &WorldDesc, source: &dyn HeightSource, rules: &ShadeRules, fov_y_deg: f64) -> Vec<ShadeView> {
    let [ex, ey] = world.extent_m;
    let up = (0.01 * ex.min(ey)).max(40.0);
    let candidates: Vec<Camera> = (0..GRID * GRID * 4)
        .map(|k| {
            let (cell, dir) = (k / 4, k % 4);
            let x = (f64::from(cell % GRID) + 0.5) * ex / f64::from(GRID);
            let y = (f64::from(cell / GRID) + 0.5) * ey / f64::from(GRID);
            let ground = f64::from(source.sample(x, y));
            Camera { position_m: [x, y, ground + up], yaw_deg: f64::from(dir) * 90.0, pitch_deg: -15.0 }
        })
        .collect();
    // A slope is cliff where the normal's z falls below where the band starts.
    let cliff_z = f64::from(rules.slope_normal_z()[0]);
    let scores: Vec<(f64, f64)> = candidates.par_iter().map(|c| score(world, source, c, fov_y_deg, cliff_z)).collect();
    let view = |name: &str, i: usize| ShadeView {
        name: name.into(),
        camera: candidates[i],
        terrain_fraction: scores[i].0,
        cliff_fraction: scores[i].1,
    };
    // Views that are mostly terrain (the sky shades nothing).
    let usable: Vec<usize> = (0..candidates.len()).filter(|&i| scores[i].0 >= 0.5).collect();
    let pool = if usable.is_empty() { (0..candidates.len()).collect() } else { usable };
    let by = |f: &dyn Fn(usize) -> f64| {
        pool.iter().copied().max_by(|&a, &b| f(a).total_cmp(&f(b))).expect("candidates are never empty")
    };
    let mut views = vec![view("cliff wall", by(&|i| scores[i].1))];
    let mixed = by(&|i| -(scores[i].1 - MIXED_CLIFFS).abs());
    if (0.1..=0.6).contains(&scores[mixed].1) {
        views.push(view("mixed cliffs", mixed));
    }
    views.push(view("no cliffs", by(&|i| -scores[i].1 + 1e-3 * scores[i].0)));
    views
}

/// (terrain fraction, cliff fraction of terrain hits) of one view.
fn score(world: &WorldDesc, source: &dyn HeightSource, camera: &Camera, fov_y_deg: f64, cliff_z: f64) -> (f64, f64) {
    let [forward, right, up] = camera.basis();
    let tan = (fov_y_deg.to_radians() * 0.5).tan();
    let aspect = 16.0 / 9.0;
    let origin = DVec3::from(camera.position_m);
    let far = 0.5 * world.extent_m[0].max(world.extent_m[1]);
    let pixel_angle = 2.0 * tan / f64::from(RAYS[1]);
    let ground = |x: f64, y: f64| f64::from(source.sample(x, y));
    let (mut hits, mut cliffs) = (0u32, 0u32);
    for j in 0..RAYS[1] {
        for i in 0..RAYS[0] {
            let u = ((f64::from(i) + 0.5) / f64::from(RAYS[0]) * 2.0 - 1.0) * tan * aspect;
            let v = (1.0 - (f64::from(j) + 0.5) / f64::from(RAYS[1]) * 2.0) * tan;
            let d = (forward + right * u + up * v).normalize();
            let mut t = 1.0;
            while t < far {
                let p = origin + d * t;
                if p.x < 0.0 || p.y < 0.0 || p.x > world.extent_m[0] || p.y > world.extent_m[1] {
                    break;
                }
                if p.z <= ground(p.x, p.y) {
                    hits += 1;
                    // The slope over the pixel's footprint (at least a sample).
                    let h = (t * pixel_angle).max(world.spacing_m);
                    let gx = (ground(p.x + h, p.y) - ground(p.x - h, p.y)) / (2.0 * h);
                    let gy = (ground(p.x, p.y + h) - ground(p.x, p.y - h)) / (2.0 * h);
                    let nz = 1.0 / (1.0 + gx * gx + gy * gy).sqrt();
                    cliffs += u32::from(nz < cliff_z);
                    break;
                }
                t += (0.02 * t).max(world.spacing_m);
            }
        }
    }
    let total = f64::from(RAYS[0] * RAYS[1]);
    (f64::from(hits) / total, f64::from(cliffs) / f64::from(hits.max(1)))
}

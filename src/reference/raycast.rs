//! The independent reference of `vista bench accuracy`: camera rays cast
//! on the CPU against the height source itself (the bicubic surface of an
//! image, the procedural function, an analytic surface), not the baked
//! nodes or the GPU's triangles. It shares only the camera conventions
//! ([`View::ray`], [`View::camera`]) and the lighting formula's inputs
//! ([`Lighting`]) with the renderer.
//!
//! How a ray is traced, and how accurate that is:
//! - The world is covered by a grid of bound cells. Each holds an upper
//!   bound of the height in the cell and a bound of the surface's slope,
//!   both from samples on a lattice (plus central differences at half the
//!   world spacing at each lattice point) with the sampled slope times
//!   `slope_safety`. A cell the ray crosses entirely above its bound is
//!   skipped.
//! - Inside a cell the ray advances by sphere tracing: the vertical gap g
//!   over the slope bound L gives a step that cannot cross the surface,
//!   g / (L |d_xy| - d_z). The step never falls below `min_step_px` of the
//!   pixel footprint, so a feature thinner than that along the ray may be
//!   missed: a sub-pixel error the metric counts like any other.
//! - A crossing found is refined by bisection until the bracket is below
//!   `refine_rel` of the distance (1e-7: finer than D32 depth resolves).
//! - The normal comes from central differences of the source at half the
//!   world spacing: the surface at the detail the world is baked at.
//! - Colour averages 4 rays per pixel (rotated grid): the filtered picture;
//!   depth, position and normal are the pixel centre's.
//! - With `shadow_rays`, each hit facing the sun casts a ray towards it
//!   (traced the same way, from just above the surface): if it meets the
//!   surface, the point gets no sun (exact shadows, no penumbra).
//!
//! The bounds rest on sampled slopes: a surface steeper between lattice
//! points than `slope_safety` times what was sampled could be tunnelled.
//! Tests check it against closed-form intersections (tests/accuracy.rs)
//! and against brute-force fine marching on the procedural world (here).

use crate::effects::atmosphere::AtmosphereParams;
use crate::scene::view::{Lighting, View};
use crate::world::{HeightSource, WorldDesc};
use glam::DVec3;
use rayon::prelude::*;

#[derive(Debug, Clone, Copy)]
pub struct RaycastConfig {
    /// Bound cells along the world's longer side.
    pub bound_cells: u32,
    /// Lattice points per cell side used to bound it.
    pub lattice: u32,
    /// Multiplies the largest sampled slope of a cell.
    pub slope_safety: f64,
    /// Smallest step, in pixel footprints at the current distance.
    pub min_step_px: f64,
    /// Bisection stops when the bracket is this fraction of the distance.
    pub refine_rel: f64,
    /// Rays per pixel for the colour: 1 (the pixel centre) or 4 (a rotated
    /// grid, averaged): the filtered picture a renderer's point samples
    /// approach. Depth, position and normal always come from the centre.
    pub colour_samples: u32,
    /// Cast a shadow ray from every lit hit (the `shadows` effect's reference).
    pub shadow_rays: bool,
    /// See every hit through this height fog and the sky behind it (the
    /// `atmosphere` effect's reference, `reference::atmosphere`).
    pub atmosphere: Option<AtmosphereParams>,
}

impl Default for RaycastConfig {
    fn default() -> Self {
        RaycastConfig {
            bound_cells: 128,
            lattice: 9,
            slope_safety: 2.0,
            min_step_px: 0.25,
            refine_rel: 1e-7,
            colour_samples: 4,
            shadow_rays: false,
            atmosphere: None,
        }
    }
}

/// Per-cell height and slope bounds of a source over a world.
pub struct HeightBounds {
    extent_m: [f64; 2],
    cells: [usize; 2],
    cell_m: [f64; 2],
    max: Vec<f64>,
    slope: Vec<f64>,
    top: f64,
    bottom: f64,
    spacing_m: f64,
}

impl HeightBounds {
    pub fn new(source: &dyn HeightSource, world: &WorldDesc, cfg: &RaycastConfig) -> Self {
        let [ex, ey] = world.extent_m;
        let n = f64::from(cfg.bound_cells.max(1));
        let side = ex.max(ey) / n;
        let cells = [(ex / side).ceil().max(1.0) as usize, (ey / side).ceil().max(1.0) as usize];
        let cell_m = [ex / cells[0] as f64, ey / cells[1] as f64];
        let m = cfg.lattice.max(2) as usize;
        let h = 0.5 * world.spacing_m;
        let bounds: Vec<(f64, f64, f64)> = (0..cells[0] * cells[1])
            .into_par_iter()
            .map(|c| {
                let (x0, y0) = ((c % cells[0]) as f64 * cell_m[0], (c / cells[0]) as f64 * cell_m[1]);
                let step = [cell_m[0] / (m - 1) as f64, cell_m[1] / (m - 1) as f64];
                let (mut hi, mut lo, mut slope) = (f64::MIN, f64::MAX, 0f64);
                let mut z = vec![0.0; m * m];
                for j in 0..m {
                    for i in 0..m {
                        let (x, y) = (x0 + i as f64 * step[0], y0 + j as f64 * step[1]);
                        let s = |x: f64, y: f64| f64::from(source.sample(x, y));
                        let v = s(x, y);
                        z[j * m + i] = v;
                        let gx = (s(x + h, y) - s(x - h, y)) / (2.0 * h);
                        let gy = (s(x, y + h) - s(x, y - h)) / (2.0 * h);
                        slope = slope.max(gx.hypot(gy));
                        (hi, lo) = (hi.max(v), lo.min(v));
                    }
                }
                for j in 0..m {
                    for i in 0..m {
                        if i + 1 < m {
                            slope = slope.max((z[j * m + i + 1] - z[j * m + i]).abs() / step[0]);
                        }
                        if j + 1 < m {
                            slope = slope.max((z[(j + 1) * m + i] - z[j * m + i]).abs() / step[1]);
                        }
                    }
                }
                let l = slope * cfg.slope_safety + 1e-3;
                // Every point of the cell is within half a lattice diagonal of a lattice point.
                let reach = 0.5 * step[0].hypot(step[1]) * l;
                (hi + reach, lo - reach, l)
            })
            .collect();
        let top = bounds.iter().map(|b| b.0).fold(f64::MIN, f64::max);
        let bottom = bounds.iter().map(|b| b.1).fold(f64::MAX, f64::min);
        HeightBounds {
            extent_m: world.extent_m,
            cells,
            cell_m,
            max: bounds.iter().map(|b| b.0).collect(),
            slope: bounds.iter().map(|b| b.2).collect(),
            top,
            bottom,
            spacing_m: world.spacing_m,
        }
    }

    fn cell(&self, p: DVec3) -> (usize, usize) {
        let c = |v: f64, s: f64, n: usize| ((v / s).floor().max(0.0) as usize).min(n - 1);
        (c(p.x, self.cell_m[0], self.cells[0]), c(p.y, self.cell_m[1], self.cells[1]))
    }
}

/// One traced ray: distance along it and the samples it took.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Trace {
    pub t: Option<f64>,
    pub samples: u32,
}

/// A source with its bounds, ready to cast rays.
pub struct RayCaster<'a> {
    pub source: &'a dyn HeightSource,
    pub bounds: HeightBounds,
    pub cfg: RaycastConfig,
    /// The world's lowest height (where the fog's density is given).
    pub z_low_m: f64,
}

impl<'a> RayCaster<'a> {
    /// Bounds the source over the world (samples every cell's lattice).
    pub fn new(source: &'a dyn HeightSource, world: &WorldDesc, cfg: RaycastConfig) -> Self {
        RayCaster {
            source,
            bounds: HeightBounds::new(source, world, &cfg),
            cfg,
            z_low_m: f64::from(world.height_range_m[0]),
        }
    }

    /// Distance to where the ray (unit `d`) first meets the surface inside
    /// the world. `footprint_per_m`: pixel footprint per metre of distance.
    pub fn trace(&self, o: DVec3, d: DVec3, footprint_per_m: f64) -> Trace {
        trace(self.source, &self.bounds, o, d, footprint_per_m, &self.cfg)
    }

    /// Casts one ray through every pixel centre of `view`. The lit colour
    /// is `clay_albedo` lit by `light` (sun plus sky ambient, as the lit
    /// output), exposed and tonemapped like the display image.
    pub fn image(&self, view: &View, light: &Lighting, clay_albedo: f32, clear: [f32; 4]) -> ReferenceImage {
        image(self, view, light, clay_albedo, clear)
    }
}

/// The stretch of the ray o + t d (t >= 0) inside the box the surface can
/// be in (None: it misses the box).
fn clip_to_box(b: &HeightBounds, o: DVec3, d: DVec3) -> Option<(f64, f64)> {
    let (mut t0, mut t1) = (0f64, f64::INFINITY);
    for (o, d, lo, hi) in [(o.x, d.x, 0.0, b.extent_m[0]), (o.y, d.y, 0.0, b.extent_m[1]), (o.z, d.z, b.bottom, b.top)]
    {
        if d.abs() < 1e-300 {
            if o < lo || o > hi {
                return None;
            }
            continue;
        }
        let (a, c) = ((lo - o) / d, (hi - o) / d);
        t0 = t0.max(a.min(c));
        t1 = t1.min(a.max(c));
    }
    (t0 <= t1).then_some((t0, t1))
}

fn trace(
    source: &dyn HeightSource,
    b: &HeightBounds,
    o: DVec3,
    d: DVec3,
    footprint_per_m: f64,
    cfg: &RaycastConfig,
) -> Trace {
    let mut samples = 0u32;
    let mut h = |p: DVec3| {
        samples += 1;
        f64::from(source.sample(p.x, p.y))
    };
    let Some((t0, t1)) = clip_to_box(b, o, d) else { return Trace { t: None, samples: 0 } };
    let dxy = d.x.hypot(d.y);
    let mut t = t0;
    let mut above: Option<f64> = None;
    while t <= t1 {
        let p = o + d * t;
        let (ci, cj) = b.cell(p);
        // Where the ray leaves this cell (in xy).
        let exit = |v: f64, dv: f64, i: usize, s: f64| {
            if dv > 0.0 {
                ((i + 1) as f64 * s - v) / dv
            } else if dv < 0.0 {
                (i as f64 * s - v) / dv
            } else {
                f64::INFINITY
            }
        };
        let t_exit = t + exit(p.x, d.x, ci, b.cell_m[0]).min(exit(p.y, d.y, cj, b.cell_m[1])).max(0.0);
        let nudge = 1e-6 + 1e-9 * t;
        let k = cj * b.cells[0] + ci;
        if p.z > b.max[k] && o.z + d.z * t_exit.min(t1) > b.max[k] {
            above = Some(t_exit.min(t1));
            t = t_exit + nudge;
            continue;
        }
        let g = p.z - h(p);
        if g <= 0.0 {
            let Some(mut lo) = above else {
                // Entered the box below the surface: not seen from above.
                return Trace { t: None, samples };
            };
            let mut hi = t;
            while hi - lo > cfg.refine_rel * hi + 1e-9 {
                let mid = 0.5 * (lo + hi);
                let q = o + d * mid;
                if q.z - h(q) > 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            return Trace { t: Some(0.5 * (lo + hi)), samples };
        }
        above = Some(t);
        let denom = b.slope[k] * dxy - d.z;
        let safe = if denom > 0.0 { g / denom } else { f64::INFINITY };
        let floor = cfg.min_step_px * footprint_per_m * t.max(b.spacing_m);
        if t >= t1 {
            break;
        }
        // The box's far end is sampled too: the surface may lie just above it.
        t = (t + safe.max(floor).min(t_exit - t + nudge)).min(t1);
    }
    Trace { t: None, samples }
}

/// What the reference sees through every pixel.
pub struct ReferenceImage {
    pub size: [u32; 2],
    /// View depth (m along the forward axis), 0 where no terrain.
    pub depth_m: Vec<f32>,
    /// World position of each hit (camera position where none).
    pub position_m: Vec<[f64; 3]>,
    /// Unit surface normal, zero where no terrain.
    pub normal: Vec<[f32; 3]>,
    /// The lit display image, as the renderer writes it (clear colour where
    /// no terrain).
    pub rgba: Vec<u8>,
    /// The centre ray's hit in a cast shadow (with `shadow_rays`; false
    /// where there is no terrain or no shadow ray was cast).
    pub in_shadow: Vec<bool>,
    /// Source samples taken, in all.
    pub samples: u64,
}

/// Display RGBA, 0..=255 before rounding.
type Rgba = [f64; 4];

/// Sub-pixel positions of 4x rotated-grid supersampling.
const ROTATED_GRID: [[f64; 2]; 4] = [[0.375, 0.125], [0.875, 0.375], [0.125, 0.625], [0.625, 0.875]];

fn image(rc: &RayCaster, view: &View, light: &Lighting, clay_albedo: f32, clear: [f32; 4]) -> ReferenceImage {
    let source = rc.source;
    let [w, hgt] = view.size;
    let origin = DVec3::from(view.camera.position_m);
    let forward = view.camera.basis()[0];
    let footprint = 2.0 / (view.focal() * f64::from(hgt));
    let sun = light.sun_dir();
    let h = 0.5 * rc.bounds.spacing_m;
    let clear_px = [0, 1, 2, 3].map(|i| (f64::from(clear[i]).clamp(0.0, 1.0) * 255.0).round() as u8);
    let empty = || ReferenceImage {
        size: view.size,
        depth_m: Vec::new(),
        position_m: Vec::new(),
        normal: Vec::new(),
        rgba: Vec::new(),
        in_shadow: Vec::new(),
        samples: 0,
    };
    // Whether the point p (normal n, seen `t` metres away) is in a cast shadow.
    let occluded = |p: DVec3, n: DVec3, t: f64, samples: &mut u64| -> bool {
        if !rc.cfg.shadow_rays || n.dot(sun) <= 0.0 {
            return false;
        }
        // Off the surface by more than the refinement's bracket, so the
        // ray does not find the point it leaves.
        let start = p + n * (0.01 + 1e-5 * t);
        let tr = rc.trace(start, sun, footprint);
        *samples += u64::from(tr.samples);
        tr.t.is_some()
    };
    // Display colour (0..=255, unrounded), hit distance, point, normal and
    // cast shadow of one ray.
    let shade = |d: DVec3, samples: &mut u64| -> (Rgba, Option<(f64, DVec3, DVec3, bool)>) {
        let tr = rc.trace(origin, d, footprint);
        *samples += u64::from(tr.samples);
        let Some(t) = tr.t else {
            let Some(fog) = &rc.cfg.atmosphere else { return (clear_px.map(f64::from), None) };
            let sky = super::atmosphere::sky(fog, light, rc.z_low_m, origin, d);
            let [r, g, b] = super::tonemap::display(light.tonemap, light.exposure_ev(), sky);
            return ([255.0 * r, 255.0 * g, 255.0 * b, 255.0], None);
        };
        let p = origin + d * t;
        let s = |x: f64, y: f64| f64::from(source.sample(x, y));
        let gx = (s(p.x + h, p.y) - s(p.x - h, p.y)) / (2.0 * h);
        let gy = (s(p.x, p.y + h) - s(p.x, p.y - h)) / (2.0 * h);
        let n = DVec3::new(-gx, -gy, 1.0).normalize();
        let shadowed = occluded(p, n, t, samples);
        let seen = if shadowed { 0.0 } else { 1.0 };
        let lit = |i: usize| {
            let sunlit = f64::from(light.sun_color[i]) * n.dot(sun).max(0.0) * seen;
            let sky = f64::from(light.sky_color[i]) * (0.5 + 0.5 * n.z);
            f64::from(clay_albedo) * (sunlit + sky)
        };
        let mut radiance = [lit(0), lit(1), lit(2)];
        if let Some(fog) = &rc.cfg.atmosphere {
            radiance = super::atmosphere::apply(fog, light, rc.z_low_m, origin, p, radiance);
        }
        let [r, g, b] = super::tonemap::display(light.tonemap, light.exposure_ev(), radiance);
        ([255.0 * r, 255.0 * g, 255.0 * b, 255.0], Some((t, p, n, shadowed)))
    };
    let offsets: &[[f64; 2]] = if rc.cfg.colour_samples >= 4 { &ROTATED_GRID } else { &[[0.5, 0.5]] };
    let rows: Vec<ReferenceImage> = (0..hgt)
        .into_par_iter()
        .map(|y| {
            let mut row = empty();
            for x in 0..w {
                let at = |o: [f64; 2]| view.ray([f64::from(x) + o[0], f64::from(y) + o[1]]);
                let d = at([0.5, 0.5]);
                let (centre, hit) = shade(d, &mut row.samples);
                let colour = if offsets.len() == 1 {
                    centre
                } else {
                    let mut sum = [0.0; 4];
                    for &o in offsets {
                        let (c, _) = shade(at(o), &mut row.samples);
                        (0..4).for_each(|i| sum[i] += c[i] / offsets.len() as f64);
                    }
                    sum
                };
                row.rgba.extend(colour.map(|c| c.round().clamp(0.0, 255.0) as u8));
                match hit {
                    Some((t, p, n, shadowed)) => {
                        row.depth_m.push((t * d.dot(forward)) as f32);
                        row.position_m.push(p.to_array());
                        row.normal.push(n.as_vec3().to_array());
                        row.in_shadow.push(shadowed);
                    }
                    None => {
                        row.depth_m.push(0.0);
                        row.position_m.push(origin.to_array());
                        row.normal.push([0.0; 3]);
                        row.in_shadow.push(false);
                    }
                }
            }
            row
        })
        .collect();
    let mut out = empty();
    for r in rows {
        out.depth_m.extend(r.depth_m);
        out.position_m.extend(r.position_m);
        out.normal.extend(r.normal);
        out.rgba.extend(r.rgba);
        out.in_shadow.extend(r.in_shadow);
        out.samples += r.samples;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::ProceduralSource;

    fn world(extent: f64, spacing: f64) -> WorldDesc {
        WorldDesc {
            extent_m: [extent, extent],
            height_range_m: [0.0, 400.0],
            spacing_m: spacing,
            lod_count: 4,
            ..WorldDesc::default()
        }
    }

    /// Rays from a few cameras in a fan of directions, all at least 5
    /// degrees below the horizon.
    fn rays() -> Vec<(DVec3, DVec3)> {
        let mut out = Vec::new();
        for k in 0..400 {
            let a = f64::from(k) * 0.618_034 * std::f64::consts::TAU;
            let o = DVec3::new(
                300.0 + 150.0 * (0.37 * a).sin(),
                320.0 + 150.0 * (0.23 * a).cos(),
                180.0 + f64::from(k % 7),
            );
            let down = 5f64.to_radians() + (0.11 * f64::from(k)).sin().abs() * 1.2;
            out.push((o, DVec3::new(a.cos() * down.cos(), a.sin() * down.cos(), -down.sin())));
        }
        out
    }

    #[test]
    fn agrees_with_brute_force_marching_on_the_procedural_world() {
        let w = world(1024.0, 0.5);
        let source = ProceduralSource::new(3, w.extent_m, w.height_range_m).unwrap();
        let rc = RayCaster::new(&source, &w, RaycastConfig::default());
        let (mut compared, mut far_off) = (0, 0);
        for (o, d) in rays().into_iter().step_by(4) {
            let o = DVec3::new(o.x, o.y, f64::from(source.sample(o.x, o.y)) + 40.0);
            let got = rc.trace(o, d, 1.0 / 512.0);
            // Brute force: fixed 0.05 m steps (a tenth of the spacing), first crossing.
            let mut t = 0.0;
            let brute = loop {
                t += 0.05;
                let p = o + d * t;
                if p.x < 0.0 || p.y < 0.0 || p.x > 1024.0 || p.y > 1024.0 || t > 3000.0 {
                    break None;
                }
                if p.z <= f64::from(source.sample(p.x, p.y)) {
                    break Some(t);
                }
            };
            compared += 1;
            match (brute, got.t) {
                (Some(b), Some(g)) => far_off += usize::from((b - g).abs() > 0.05 + 1e-3 * b),
                (None, None) => {}
                _ => far_off += 1,
            }
        }
        // Both may straddle a feature thinner than their steps differently;
        // with sphere-tracing steps that never cross a bounded slope, none do here.
        assert_eq!(far_off, 0, "{far_off} of {compared} rays disagree with brute-force marching");
    }

    /// A cone (radius 20 m, 30 m high) on a plane at 100 m.
    struct Cone;

    impl HeightSource for Cone {
        fn sample(&self, x: f64, y: f64) -> f32 {
            (100.0 + 30.0 * (1.0 - (x - 256.0).hypot(y - 256.0) / 20.0).max(0.0)) as f32
        }
        fn id_hash(&self) -> u64 {
            1
        }
    }

    #[test]
    fn shadow_rays_darken_the_cones_exact_shadow() {
        let w = WorldDesc { height_range_m: [100.0, 130.0], ..world(512.0, 0.5) };
        let cfg = RaycastConfig { colour_samples: 1, shadow_rays: true, ..RaycastConfig::default() };
        let rc = RayCaster::new(&Cone, &w, cfg);
        let light = Lighting { sun_azimuth_deg: 250.0, sun_elevation_deg: 20.0, ..Lighting::default() };
        let camera = crate::scene::view::Camera { position_m: [256.0, 200.0, 300.0], yaw_deg: 60.0, pitch_deg: -60.0 };
        let view = View { camera, fov_y_deg: 60.0, size: [96, 96], target_error_px: 1.0, near_m: 0.1 };
        let img = rc.image(&view, &light, 0.4, [0.0; 4]);
        // The shadow is the union of the cross-sections at each height s
        // (radius 20 (1 - s / 30)) moved away from the sun by s / tan(20).
        let sun = light.sun_dir();
        let away = -glam::DVec2::new(sun.x, sun.y).normalize();
        let exact = |q: glam::DVec2, grow: f64| {
            (0..=600).any(|i| {
                let f = f64::from(i) / 600.0;
                let c = glam::DVec2::splat(256.0) + away * (f * 30.0 / 20f64.to_radians().tan());
                (q - c).length() <= 20.0 * (1.0 - f) + grow
            })
        };
        let (mut shadowed, mut wrong) = (0, 0);
        for (p, &dark) in img.position_m.iter().zip(&img.in_shadow) {
            let q = glam::DVec2::new(p[0], p[1]);
            if (q - glam::DVec2::splat(256.0)).length() < 21.0 || p[2] > 100.01 {
                continue;
            }
            shadowed += usize::from(dark);
            // Half a metre either side of the edge is left to the pixel grid.
            let sure = if dark { exact(q, 0.5) } else { !exact(q, -0.5) };
            wrong += usize::from(!sure);
        }
        assert!(shadowed > 100, "{shadowed} plane pixels in shadow");
        assert_eq!(wrong, 0, "{wrong} plane pixels on the wrong side of the exact shadow edge");
    }
}

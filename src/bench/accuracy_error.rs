//! What one rendered frame loses against the reference ray-caster: depth,
//! silhouette, screen-space geometric error and colour.

use crate::reference::{flip_map, FinestSurface, ReferenceImage};
use crate::render::offscreen::Capture;
use crate::scene::view::{linear_depth, View};
use crate::world::{HeightSource, WorldDesc};
use glam::DVec3;
use serde::Serialize;

#[derive(Debug, Clone, Serialize)]
pub struct AccuracyError {
    /// Pixels where both the frame and the reference see terrain.
    pub terrain_pixels: u64,
    /// Of those, the share whose depth is within 0.5 % / 2 % of the reference.
    pub depth_within_0_5pct: f64,
    pub depth_within_2pct: f64,
    /// Relative depth error |d - d_ref| / d_ref, median and 99th percentile.
    pub depth_rel_p50: f64,
    pub depth_rel_p99: f64,
    /// Pixels where one image has terrain and the other not, and their
    /// share of the image.
    pub silhouette_pixels: u64,
    pub silhouette_fraction: f64,
    /// Per rendered terrain pixel: the vertical distance from its world
    /// position (from the depth buffer) to the source surface, projected
    /// onto the screen, in pixels: the whole error.
    pub geometric_px_max: f64,
    pub geometric_px_p99: f64,
    pub geometric_px_mean: f64,
    /// Its LOD part: the same distance to the finest surface vista can draw
    /// ([`FinestSurface`]), which the target error bounds.
    pub lod_px_max: f64,
    pub lod_px_p99: f64,
    /// Its representation part: at the same points, the finest surface's
    /// distance to the source, projected (what no LOD choice removes).
    pub repr_px_max: f64,
    pub repr_px_p99: f64,
    /// Lit (clay) image against the reference's over the pixels where
    /// either has terrain (the sky, identical in both, left out): PSNR over
    /// RGB (dB; null when identical) and mean FLIP (nv-flip, the NVIDIA
    /// FLIP metric, computed on the whole image and averaged over those
    /// pixels).
    pub psnr_db: f64,
    pub flip_mean: f64,
}

/// The `q`-quantile of `v` (sorted in place); 0 when empty.
pub fn quantile(v: &mut [f64], q: f64) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_unstable_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

/// The vertical distance of each rendered terrain pixel's world position to
/// the source surface, projected onto the screen (pixels).
pub fn geometric_error_px(capture: &Capture, view: &View, source: &dyn HeightSource, world: &WorldDesc) -> Vec<f64> {
    projected_px(capture, view, world, |p| (p.z, f64::from(source.sample(p.x, p.y))))
}

/// For each rendered terrain pixel inside the world, at its world position
/// p (from the depth buffer): the screen length (pixels) of the vertical
/// segment between the two heights `ends(p)` gives at p's x and y.
pub fn projected_px(capture: &Capture, view: &View, world: &WorldDesc, ends: impl Fn(DVec3) -> (f64, f64)) -> Vec<f64> {
    let mut out = Vec::new();
    for i in 0..capture.depth.len() {
        let Some(p) = world_point(capture, view, world, i) else { continue };
        let (za, zb) = ends(p);
        out.extend(vertical_px(view, p, za, zb));
    }
    out
}

/// Pixel `i`'s (row-major) world position from the depth buffer, when it
/// shows terrain inside the world.
pub fn world_point(capture: &Capture, view: &View, world: &WorldDesc, i: usize) -> Option<DVec3> {
    let d = capture.depth[i];
    if d <= 0.0 {
        return None;
    }
    let w = capture.size[0] as usize;
    let px = [(i % w) as f64 + 0.5, (i / w) as f64 + 0.5];
    let ray = view.ray(px);
    let origin = DVec3::from(view.camera.position_m);
    let p = origin + ray * (f64::from(linear_depth(d, view.near_m)) / ray.dot(view.camera.basis()[0]));
    let inside = (0.0..=world.extent_m[0]).contains(&p.x) && (0.0..=world.extent_m[1]).contains(&p.y);
    inside.then_some(p)
}

/// The screen length (pixels) of the vertical segment from height `za` to
/// `zb` at `p`'s x and y (none when an end is behind the camera).
pub fn vertical_px(view: &View, p: DVec3, za: f64, zb: f64) -> Option<f64> {
    let (a, b) = (view.project([p.x, p.y, za])?.0, view.project([p.x, p.y, zb])?.0);
    Some((a[0] - b[0]).hypot(a[1] - b[1]))
}

pub fn accuracy_error(
    capture: &Capture,
    reference: &ReferenceImage,
    view: &View,
    source: &dyn HeightSource,
    world: &WorldDesc,
) -> AccuracyError {
    assert_eq!(capture.size, reference.size, "frame and reference sizes differ");
    let (mut rel, mut silhouette) = (Vec::new(), 0u64);
    for (&d, &r) in capture.depth.iter().zip(&reference.depth_m) {
        match (d > 0.0, r > 0.0) {
            (true, true) => {
                let lin = f64::from(linear_depth(d, view.near_m));
                rel.push((lin - f64::from(r)).abs() / f64::from(r));
            }
            (false, false) => {}
            _ => silhouette += 1,
        }
    }
    let n = rel.len().max(1) as f64;
    let within = |f: f64| rel.iter().filter(|&&e| e <= f).count() as f64 / n;
    let (d05, d2) = (within(0.005), within(0.02));
    let mut geo = geometric_error_px(capture, view, source, world);
    let geo_mean = geo.iter().sum::<f64>() / geo.len().max(1) as f64;
    let finest = FinestSurface::new(world, source);
    let mut lod = projected_px(capture, view, world, |p| (p.z, f64::from(finest.sample(p.x, p.y))));
    let mut repr = projected_px(capture, view, world, |p| {
        (f64::from(finest.sample(p.x, p.y)), f64::from(source.sample(p.x, p.y)))
    });
    // Terrain in either image: the metrics are not diluted by the sky.
    let terrain: Vec<bool> = capture.depth.iter().zip(&reference.depth_m).map(|(&d, &r)| d > 0.0 || r > 0.0).collect();
    let counted = terrain.iter().filter(|&&t| t).count().max(1) as f64;
    let mse = capture
        .rgba
        .chunks_exact(4)
        .zip(reference.rgba.chunks_exact(4))
        .zip(&terrain)
        .filter(|(_, &t)| t)
        .map(|((a, b), _)| (0..3).map(|i| (f64::from(a[i]) - f64::from(b[i])).powi(2)).sum::<f64>())
        .sum::<f64>()
        / (3.0 * counted);
    let pixels = u64::from(capture.size[0]) * u64::from(capture.size[1]);
    AccuracyError {
        terrain_pixels: rel.len() as u64,
        depth_within_0_5pct: d05,
        depth_within_2pct: d2,
        depth_rel_p50: quantile(&mut rel, 0.5),
        depth_rel_p99: quantile(&mut rel, 0.99),
        silhouette_pixels: silhouette,
        silhouette_fraction: silhouette as f64 / pixels as f64,
        geometric_px_max: geo.iter().copied().fold(0.0, f64::max),
        geometric_px_p99: quantile(&mut geo, 0.99),
        geometric_px_mean: geo_mean,
        lod_px_max: lod.iter().copied().fold(0.0, f64::max),
        lod_px_p99: quantile(&mut lod, 0.99),
        repr_px_max: repr.iter().copied().fold(0.0, f64::max),
        repr_px_p99: quantile(&mut repr, 0.99),
        psnr_db: 10.0 * (255.0f64.powi(2) / mse).log10(),
        flip_mean: terrain_flip_mean(capture, reference),
    }
}

/// Mean FLIP of the frame against the reference over the pixels where
/// either has terrain (the sky, identical in both, left out).
pub fn terrain_flip_mean(capture: &Capture, reference: &ReferenceImage) -> f64 {
    let flip = flip_map(&reference.rgba, &capture.rgba, capture.size);
    let terrain = capture.depth.iter().zip(&reference.depth_m).map(|(&d, &r)| d > 0.0 || r > 0.0);
    let (sum, n) =
        flip.iter().zip(terrain).filter(|(_, t)| *t).fold((0.0, 0u64), |(s, n), (&e, _)| (s + f64::from(e), n + 1));
    sum / n.max(1) as f64
}

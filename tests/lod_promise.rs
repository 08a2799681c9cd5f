//! What the accuracy knob promises, through the real renderer: the drawn
//! surface of a height map at its own pixel size passes through every
//! post; on adversarial surfaces (vertical terrace steps, a sawtooth
//! ridge) the drawn surface keeps the promise against the finest surface
//! vista can draw (the error tree's reference, evaluated here from its
//! definition): p99 within the target, the largest within twice it; a slot
//! budget too small for the target reports the bound it reached, keeps it,
//! and a finer target does no worse; seams hold on
//! rough ground with the largest LOD differences the selection makes, and
//! open without edge snapping.

mod common;

use common::finest::Finest;
use common::terrain::{adversarial_views, adversarial_world, view, Rig, Surface, ADVERSARIAL, MAGENTA_RGBA};
use common::{gpu_test, Rng};
use std::sync::Arc;
use vista::bench::accuracy_error::{projected_px, quantile};
use vista::bench::accuracy_floor::grid_floors;
use vista::passes::cull_patches::{CullStages, MAX_LOD_DELTA};
use vista::reference::{RayCaster, RaycastConfig};
use vista::render::offscreen::Capture;
use vista::render::stats::collect;
use vista::render::{Lighting, LodOptions, LodRule, RendererOptions, View};
use vista::terrain::TerrainOptions;
use vista::world::{GridSource, HeightSource, Png16Source, WorldDesc};

/// The LOD-part error (px) of a frame, each terrain pixel's vertical
/// distance to the finest surface projected: (largest, p99, pixels).
fn lod_error_px(capture: &Capture, v: &View, world: &WorldDesc, finest: &Finest) -> (f64, f64, usize) {
    let mut e = projected_px(capture, v, world, |p| (p.z, finest.height(p.x, p.y)));
    let max = e.iter().copied().fold(0.0, f64::max);
    (max, quantile(&mut e, 0.99), e.len())
}

/// A 200 x 160 PNG16 of rough heights (a wave plus noise) at 2 m pixels.
fn posts_png() -> (std::path::PathBuf, Vec<u16>, [u32; 2]) {
    let (w, h) = (200u32, 160u32);
    let mut rng = Rng(4242);
    let px: Vec<u16> = (0..w * h)
        .map(|k| {
            let (x, y) = (f64::from(k % w), f64::from(k / w));
            let v = 0.5 + 0.3 * (x * 0.09).sin() * (y * 0.05).cos() + 0.08 * (rng.unit() - 0.5);
            (v * 65535.0).round() as u16
        })
        .collect();
    let dir = std::env::temp_dir().join(format!("vista-posts-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("posts.png");
    image::ImageBuffer::<image::Luma<u16>, _>::from_raw(w, h, px.clone()).unwrap().save(&path).unwrap();
    (path, px, [w, h])
}

/// The posts' world at its own pixel size (vertices on the posts), its
/// source and its posts; the PNG's folder is removed by the caller.
fn posts_world() -> (std::path::PathBuf, WorldDesc, Arc<dyn HeightSource>, Posts) {
    let (path, px, [w, h]) = posts_png();
    let extent = [f64::from(w) * 2.0, f64::from(h) * 2.0];
    let range = [-100.0f32, 300.0];
    let world =
        WorldDesc { extent_m: extent, height_range_m: range, spacing_m: 2.0, lod_count: 3, ..WorldDesc::default() }
            .with_posts([2.0, 2.0]);
    let source: Arc<dyn HeightSource> = Arc::new(Png16Source::open(&path, extent, range).unwrap());
    // The map's own values, as a 16-bit step in metres: what a post is.
    let step = f64::from(range[1] - range[0]) / 65535.0;
    (path, world, source, Posts { px, w, h, range, step })
}

#[test]
fn the_drawn_surface_passes_through_every_post() {
    let (path, world, source, posts) = posts_world();
    assert!(world.on_posts(), "a map at its own pixel size puts the vertices on its posts");
    let step = posts.step;
    gpu_test(|ctx| {
        let (worst, checked) = distance_to_posts(ctx, world, &source, &posts, LodRule::Patch);
        assert!(checked > 40_000, "{checked} pixels checked");
        // Within the 16-bit step (6 mm here) and the depth buffer's
        // precision from 330 m (D32 reversed-Z: under 0.1 mm).
        assert!(worst <= step, "drawn surface {worst:.5} m from the triangles through the posts (step {step:.5})");
        // The control: the same map with vertices half a pixel off its posts
        // (the grid from the world's corner) draws a resampling of it.
        let shifted = WorldDesc { grid_origin_m: [0.0, 0.0], ..world };
        let (off, _) = distance_to_posts(ctx, shifted, &source, &posts, LodRule::Patch);
        println!("{checked} pixels: drawn surface within {worst:.6} m of the triangles through the posts; {off:.3} m off them without posts");
        assert!(off > 100.0 * step, "half a pixel off the posts, the surface is only {off} m away: a weak test");
    });
    let _ = std::fs::remove_dir_all(path.parent().unwrap());
}

/// The per-triangle rule's cut, refined to the posts, is the same surface.
/// (This world is not a whole number of nodes: before a family's streaming
/// priority was capped at its parent's, the edge nodes' infinite bounds
/// sorted their families first, never taken, and LOD 1 was drawn.)
#[test]
fn the_per_triangle_rule_passes_through_every_post_too() {
    let (path, world, source, posts) = posts_world();
    let step = posts.step;
    gpu_test(|ctx| {
        let (worst, checked) = distance_to_posts(ctx, world, &source, &posts, LodRule::Triangle);
        println!(
            "per triangle, {checked} pixels: drawn surface within {worst:.6} m of the triangles through the posts"
        );
        assert!(checked > 40_000, "{checked} pixels checked");
        assert!(worst <= step, "drawn surface {worst:.5} m from the triangles through the posts (step {step:.5})");
    });
    let _ = std::fs::remove_dir_all(path.parent().unwrap());
}

/// The PNG's pixels as posts: heights at 2 m spacing.
struct Posts {
    px: Vec<u16>,
    w: u32,
    h: u32,
    range: [f32; 2],
    /// A 16-bit step in metres.
    step: f64,
}

impl Posts {
    fn post(&self, i: u32, j: u32) -> f64 {
        let (px, range, w, h, step) = (&self.px, self.range, self.w, self.h, self.step);
        f64::from(range[0]) + f64::from(px[((h - 1 - j) * w + i) as usize]) * step
    }

    /// The two triangles through the posts of quad (i, j): SW-NE split where
    /// i + j is even, NW-SE elsewhere (the diamond pattern).
    fn triangles(&self, i: u32, j: u32) -> [Tri; 2] {
        let post = |i, j| self.post(i, j);
        let (h00, h10, h01, h11) = (post(i, j), post(i + 1, j), post(i, j + 1), post(i + 1, j + 1));
        if (i + j).is_multiple_of(2) {
            [
                Tri([0.0, 0.0, h00], [1.0, 0.0, h10], [1.0, 1.0, h11]),
                Tri([0.0, 0.0, h00], [1.0, 1.0, h11], [0.0, 1.0, h01]),
            ]
        } else {
            [
                Tri([0.0, 0.0, h00], [1.0, 0.0, h10], [0.0, 1.0, h01]),
                Tri([1.0, 0.0, h10], [1.0, 1.0, h11], [0.0, 1.0, h01]),
            ]
        }
    }

    /// Distance (m) of `p` to the nearest triangle through the posts; none
    /// at the map's border.
    fn distance(&self, p: glam::DVec3) -> Option<f64> {
        let (w, h) = (self.w, self.h);
        // Post (i, j) is pixel column i, row h - 1 - j, at ((i + .5) 2, (j + .5) 2).
        let (u, t) = (p.x / 2.0 - 0.5, p.y / 2.0 - 0.5);
        if u < 1.0 || t < 1.0 || u >= f64::from(w - 2) || t >= f64::from(h - 2) {
            return None;
        }
        // The rasteriser snaps projected vertices to a fraction
        // of a pixel (a pixel is 2 m on the ground here), so a
        // pixel at a triangle's edge may take the plane of its
        // neighbour: the nearest of the triangles within 4 cm
        // of p (0.02 in quad units).
        let near = (-1..=1)
            .flat_map(|dj| (-1..=1).map(move |di| (di, dj)))
            .flat_map(|(di, dj)| {
                let (i, j) = ((u.floor() as i64 + di) as u32, (t.floor() as i64 + dj) as u32);
                let (fu, fv) = (u - f64::from(i), t - f64::from(j));
                self.triangles(i, j).into_iter().filter_map(move |tri| tri.at(fu, fv, 0.02))
            })
            .map(|z| (p.z - z).abs())
            .fold(f64::INFINITY, f64::min);
        Some(near)
    }
}

/// The largest distance (m) of the drawn surface of `world` to the
/// triangles through the posts, and the pixels measured.
fn distance_to_posts(
    ctx: &vista::gpu::Context,
    world: WorldDesc,
    source: &Arc<dyn HeightSource>,
    posts: &Posts,
    rule: LodRule,
) -> (f64, usize) {
    // LOD 0 everywhere in view and no refinement: the drawn surface is
    // the triangles between the vertices, nothing else.
    let lod = LodOptions { refine_levels: 0, rule, ..LodOptions::default() };
    let options = RendererOptions { lod, ..RendererOptions::default() };
    let size = [192, 192];
    let mut rig = Rig::with_source(ctx, world, Arc::clone(source), vec![], size, false, options);
    let (mut checked, mut worst) = (0usize, 0f64);
    for centre in [[200.0, 160.0], [90.0, 250.0], [330.0, 60.0]] {
        let v = view([centre[0], centre[1], 330.0], 0.0, -90.0, size, 0.01);
        let c = rig.shot(ctx, &v, CullStages::ALL);
        let stats = collect(ctx, &rig.renderer, &v).unwrap();
        assert!(stats.nodes_per_lod[1..].iter().all(|&n| n == 0), "{rule:?}: LOD 0 only: {:?}", stats.nodes_per_lod);
        let forward = v.camera.basis()[0];
        for y in 0..size[1] {
            for x in 0..size[0] {
                let d = c.depth[(y * size[0] + x) as usize];
                if d <= 0.0 {
                    continue;
                }
                let ray = v.ray([f64::from(x) + 0.5, f64::from(y) + 0.5]);
                let lin = f64::from(vista::scene::view::linear_depth(d, v.near_m));
                let p = glam::DVec3::from(v.camera.position_m) + ray * (lin / ray.dot(forward));
                let Some(near) = posts.distance(p) else { continue };
                worst = worst.max(near);
                checked += 1;
            }
        }
    }
    (worst, checked)
}

/// A triangle over the unit quad: (u, v, height) corners.
struct Tri([f64; 3], [f64; 3], [f64; 3]);

impl Tri {
    /// The height of its plane at (u, v) when (u, v) lies inside it or
    /// within `slack` (quad units) of it.
    fn at(&self, u: f64, v: f64, slack: f64) -> Option<f64> {
        let (a, b, c) = (self.0, self.1, self.2);
        let det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
        let l1 = ((u - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (v - a[1])) / det;
        let l2 = ((b[0] - a[0]) * (v - a[1]) - (u - a[0]) * (b[1] - a[1])) / det;
        let l0 = 1.0 - l1 - l2;
        (l0 >= -slack && l1 >= -slack && l2 >= -slack).then(|| l0 * a[2] + l1 * b[2] + l2 * c[2])
    }
}

#[test]
fn the_promise_holds_on_vertical_steps_and_a_sawtooth_ridge() {
    let world = adversarial_world();
    gpu_test(|ctx| {
        for surface in ADVERSARIAL {
            let options = RendererOptions {
                terrain: TerrainOptions { slots: 1000, ..TerrainOptions::default() },
                ..Default::default()
            };
            let size = [256, 192];
            let mut rig = Rig::with_options(ctx, world, surface, vec![], size, false, options);
            let finest = Finest::new(&world, &surface);
            let views = adversarial_views(surface);
            for target in [1.0f32, 4.0] {
                for &(position, yaw, pitch) in &views {
                    let v = view(position, yaw, pitch, size, target);
                    let c = rig.shot(ctx, &v, CullStages::ALL);
                    let stats = collect(ctx, &rig.renderer, &v).unwrap();
                    assert!(stats.bound_px <= target, "{surface:?}: budget short, bound {}", stats.bound_px);
                    let (max, p99, n) = lod_error_px(&c, &v, &world, &finest);
                    assert!(n > 10_000, "{surface:?}: {n} terrain pixels");
                    println!(
                        "{surface:?} {position:?} target {target}: LOD part p99 {p99:.3} px, max {max:.3} px, bound {:.3}",
                        stats.bound_px
                    );
                    // No drawing beats the grids' lower bound (bench::accuracy_floor).
                    let reference = RayCaster::new(&surface, &world, RaycastConfig::default()).image(
                        &v,
                        &Lighting::default(),
                        0.4,
                        [0.0; 4],
                    );
                    let floor = grid_floors(&reference, &v, &world, &surface);
                    let drawn = stats.triangles_drawn as f64 / f64::from(size[0] * size[1]);
                    println!("  {drawn:.3} triangles per pixel drawn, floors {floor:?}");
                    let (t, p) = (floor.triangles, floor.patches);
                    assert!(t > 0.0 && p >= t && drawn >= p, "{surface:?} from {position:?}: {drawn} below {floor:?}");
                    let t = f64::from(target);
                    assert!(p99 <= t, "{surface:?} from {position:?}: p99 {p99:.3} px > target {target}");
                    assert!(max <= 2.0 * t, "{surface:?} from {position:?}: max {max:.3} px > 2 x target {target}");
                }
            }
        }
    });
}

#[test]
fn a_starved_budget_reports_its_bound_keeps_it_and_a_finer_target_is_no_worse() {
    let world = adversarial_world();
    let surface = Surface::Sawtooth { z0: 150.0, amp: 30.0, period: 120.0 };
    gpu_test(|ctx| {
        // 64 slots: the root and a few families, far from the hundreds a
        // 1 px view of the ridge wants.
        let options = RendererOptions {
            terrain: TerrainOptions { slots: 64, ..TerrainOptions::default() },
            ..Default::default()
        };
        let size = [256, 192];
        let finest = Finest::new(&world, &surface);
        let position = [1024.0, 300.0, surface.height(1024.0, 300.0) + 60.0];
        let mut rows = Vec::new();
        for target in [2.0f32, 1.0, 0.5] {
            let mut rig = Rig::with_options(ctx, world, surface, vec![], size, false, options.clone());
            let v = view(position, 0.0, -12.0, size, target);
            let c = rig.shot(ctx, &v, CullStages::ALL);
            let stats = collect(ctx, &rig.renderer, &v).unwrap();
            let (max, p99, _) = lod_error_px(&c, &v, &world, &finest);
            println!("target {target}: bound {:.3} px, measured p99 {p99:.3} px, max {max:.3} px", stats.bound_px);
            assert!(stats.bound_px > target, "the budget met target {target}: the test is too easy");
            // The bound is the promise's: p99 within it, the largest within twice it.
            let b = f64::from(stats.bound_px);
            assert!(p99 <= b, "measured p99 {p99:.3} px beyond the reported bound {b}");
            assert!(max <= 2.0 * b, "measured max {max:.3} px beyond twice the reported bound {b}");
            rows.push((target, stats.bound_px, p99, max));
        }
        for w in rows.windows(2) {
            let ((t0, b0, q0, m0), (t1, b1, q1, m1)) = (w[0], w[1]);
            assert!(b1 <= b0 * 1.0001, "target {t0} -> {t1}: bound {b0} -> {b1}");
            // 0.01 px: the measurement's own floor (depth read back and
            // unprojected; an exactly drawn view of this ridge measures
            // 0.008 px, the_promise_holds... from [1500, 1200]), and the
            // finer level bounds the error over a patch, not at each point.
            assert!(q1 <= q0 * 1.0001 + 0.01, "target {t0} -> {t1}: measured p99 {q0} -> {q1}");
            assert!(m1 <= m0 * 1.0001 + 0.01, "target {t0} -> {t1}: measured max {m0} -> {m1}");
        }
    });
}

/// 1024 m at 1 m: gentle hills, with 128 m squares of rough noise (6 m) in
/// a checkerboard, so the selection puts coarse patches beside refined
/// ones: the largest LOD differences it allows, along non-collinear edges.
fn rough_checkerboard() -> (WorldDesc, Arc<dyn HeightSource>) {
    let n = 1024usize;
    let mut rng = Rng(31337);
    let heights: Vec<f32> = (0..n * n)
        .map(|k| {
            let (x, y) = ((k % n) as f64 + 0.5, (n - 1 - k / n) as f64 + 0.5);
            let rough = ((x / 128.0) as usize + (y / 128.0) as usize).is_multiple_of(2);
            let hills = 200.0 + 60.0 * (x / 97.0).sin() * (y / 131.0).cos();
            (hills + if rough { 6.0 * rng.unit() } else { 0.0 }) as f32
        })
        .collect();
    let world = WorldDesc {
        extent_m: [1024.0, 1024.0],
        height_range_m: [100.0, 300.0],
        spacing_m: 1.0,
        lod_count: 4,
        ..WorldDesc::default()
    }
    .with_posts([1.0, 1.0]);
    (world, Arc::new(GridSource::new(n, n, heights, [1024.0, 1024.0])))
}

/// Magenta (background) pixels over 100 views that look steeply down from
/// inside the world, where every pixel must be terrain, and the largest
/// LOD delta any drawn patch edge had.
fn background_pixels(stitching: bool) -> (usize, u8) {
    let (world, source) = rough_checkerboard();
    let mut out = (0, 0);
    gpu_test(|ctx| {
        let lod = LodOptions { stitching, ..LodOptions::default() };
        let size = [96, 96];
        let options = RendererOptions { lod, ..RendererOptions::default() };
        let mut rig = Rig::with_source(ctx, world, Arc::clone(&source), vec![], size, false, options);
        let mut rng = Rng(2718);
        for _ in 0..100 {
            let (x, y) = (300.0 + 424.0 * rng.unit(), 300.0 + 424.0 * rng.unit());
            let z = f64::from(source.sample(x, y)) + 8.0 + 70.0 * rng.unit();
            // The frustum's top edge at least 30 degrees below the horizon:
            // the ground it reaches lies inside the world.
            let v = view([x, y, z], 360.0 * rng.unit(), -60.0 - 30.0 * rng.unit(), size, 0.5 + 2.0 * rng.unit() as f32);
            let c = rig.shot(ctx, &v, CullStages::ALL);
            out.0 += c.rgba.chunks_exact(4).filter(|p| *p == MAGENTA_RGBA).count();
            let deltas = rig.renderer.read_patches(ctx).unwrap().iter().flat_map(|p| p.deltas).max().unwrap_or(0);
            out.1 = out.1.max(deltas);
        }
    });
    out
}

#[test]
fn seams_hold_on_rough_ground_and_open_without_snapping() {
    let (holes, delta) = background_pixels(true);
    assert_eq!(holes, 0, "background shows through the terrain: cracks");
    // MAX_LOD_DELTA (4) is past log2(PATCH_QUADS): such edges snap to
    // vertices beyond their patch's corners, and the patch is never culled.
    assert_eq!(
        u32::from(delta),
        MAX_LOD_DELTA,
        "the views never reached the largest LOD delta: the test would be weak"
    );
    // The same views without edge snapping: the test sees the cracks.
    let (holes_unstitched, _) = background_pixels(false);
    println!("largest LOD delta {delta}; background pixels without snapping: {holes_unstitched}");
    assert!(holes_unstitched > 0, "no crack without snapping: the test cannot see one");
}

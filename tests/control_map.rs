//! Control-map materials (seed 004): every field of the 16-bit word
//! round-trips; on an analytic slope the G-buffer shows the overlay below
//! the threshold, the background above it, and between them the blend the
//! overlay's sharpness asks for (read back); the tightened tri-planar
//! background samples one plane on flat ground and two or three on a
//! cone's flanks (per pixel against the analytic normal, per tile against
//! the counters), and looks like the untightened blend.

mod common;

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use common::gpu_test;
use common::terrain::{small_world, view, Surface, MAGENTA};
use glam::DVec3;
use vista::passes::cull_patches::CullStages;
use vista::reference::{flip_map, flip_stats, plane_tiles_cpu};
use vista::render::offscreen::{Capture, Offscreen};
use vista::render::{linear_depth, Effect, Effects, MaterialsMode, RendererOptions, TerrainRenderer, View};
use vista::shaders::consts::{CLASS_PLANES_2, CLASS_PLANES_3, FLAVOUR_CONTROL_MAP, TILE_SIZE};
use vista::terrain::TerrainOptions;
use vista::world::{ControlCode, PayloadFormat};

const SIZE: [u32; 2] = [192, 192];

#[test]
fn every_field_of_the_control_word_round_trips() {
    for word in 0..=u16::MAX {
        let c = ControlCode::decode(word);
        assert_eq!(c.encode(), word, "{c:?}");
        // The layout: overlay bits 0-4, background 5-9, UV scale 10-12,
        // slope threshold 13-15.
        assert_eq!(u32::from(c.overlay), u32::from(word) & 31);
        assert_eq!(u32::from(c.background), u32::from(word) >> 5 & 31);
        assert_eq!(u32::from(c.uv_scale), u32::from(word) >> 10 & 7);
        assert_eq!(u32::from(c.threshold), u32::from(word) >> 13 & 7);
    }
    let c = ControlCode { overlay: 17, background: 30, uv_scale: 5, threshold: 2 };
    assert_eq!(c.encode(), 17 | 30 << 5 | 5 << 10 | 2 << 13);
    assert_eq!((c.uv_scale_value(), c.threshold_value(0.9)), (vista::world::UV_SCALES[4], 0.125));
    assert_eq!(ControlCode { threshold: 0, ..c }.threshold_value(0.9), 0.9, "code 0: the background's own");
}

/// A map of another shape than its area is refused in one line (its words
/// would land stretched, far from where they were painted); one of the
/// area's shape, or within 5 % of it, opens.
#[test]
fn a_control_map_of_another_shape_than_its_area_is_refused() {
    let dir = temp_dir("shape");
    let map = |w: u32, h: u32| {
        let p = dir.join(format!("map{w}x{h}.png"));
        image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_pixel(w, h, image::Luma([7])).save(&p).unwrap();
        p
    };
    let e = vista::world::ControlMap::open(&map(3, 5), [10240.0, 10240.0]).unwrap_err().to_string();
    assert!(e.contains("3 x 5 texels over 10240 x 10240 m") && e.lines().count() == 1, "{e}");
    assert!(vista::world::ControlMap::open(&map(64, 64), [10240.0, 10240.0]).is_ok());
    assert!(vista::world::ControlMap::open(&map(64, 62), [10240.0, 10240.0]).is_ok());
    assert!(vista::world::ControlMap::open(&map(64, 32), [2048.0, 1024.0]).is_ok());
}

fn temp_dir(tag: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("control-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Two flat texture sets (solid albedo, a normal map straight up, flat
/// height) as the control textures 0 (background, red) and 1 (overlay,
/// white), and a control map that puts them everywhere with threshold
/// code `threshold` (word: overlay 1, background 0).
fn flat_textures(dir: &Path, threshold: u8) -> (PathBuf, PathBuf) {
    let solid = |name: &str, rgb: [u8; 3]| {
        image::RgbImage::from_pixel(16, 16, image::Rgb(rgb)).save(dir.join(name)).unwrap();
    };
    solid("red.png", RED);
    solid("white.png", WHITE);
    solid("up.png", [128, 128, 255]);
    image::GrayImage::from_pixel(16, 16, image::Luma([128])).save(dir.join("flat.png")).unwrap();
    let set =
        |name: &str| format!("{name} = {{ albedo = \"{name}.png\", normal = \"up.png\", height = \"flat.png\" }}");
    let materials = dir.join("materials.toml");
    std::fs::write(
        &materials,
        format!(
            "[textures]\n{}\n{}\n[[control_texture]]\nindex = 0\ntexture = \"red\"\nslope_damp = 0\n\
             normal_damp = 0.5\n[[control_texture]]\nindex = 1\ntexture = \"white\"\nsharpness = {SHARPNESS}\n",
            set("red"),
            set("white")
        ),
    )
    .unwrap();
    let word = ControlCode { overlay: 1, background: 0, uv_scale: 0, threshold }.encode();
    let map = dir.join("control.png");
    image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_pixel(64, 64, image::Luma([word])).save(&map).unwrap();
    (materials, map)
}

const RED: [u8; 3] = [200, 40, 40];
const WHITE: [u8; 3] = [240, 240, 240];
const SHARPNESS: f64 = 0.2;

fn control_effects(materials: Option<PathBuf>, map: Option<PathBuf>, tighten: f32) -> Effects {
    let mut fx = Effects::default().with(Effect::Splat, true);
    fx.materials = MaterialsMode::ControlMap;
    fx.splat_materials = materials;
    fx.control_map = map;
    fx.shade.tighten = tighten;
    // Near shading everywhere in these small views (no far atlas band).
    fx.shade.far_start_m = 5000.0;
    fx.shade.far_end_m = 6000.0;
    fx
}

/// Renders `surface` with `fx` (RGBA8 payloads: the test compares normals
/// within a degree, BC3 would add its own error) and returns the frame and
/// the G-buffer.
fn render(
    ctx: &vista::gpu::Context,
    surface: Surface,
    fx: Effects,
    v: &View,
) -> (Capture, vista::targets::gbuffer::GBufferCapture, [u32; 3]) {
    let bake = vista::world::BakeSettings { format: PayloadFormat::Rgba8, ..Default::default() };
    let options = RendererOptions {
        effects: fx,
        terrain: TerrainOptions { slots: 400, loader_threads: 2, bake, ..TerrainOptions::default() },
        ..RendererOptions::default()
    };
    let mut renderer =
        TerrainRenderer::new(ctx, &small_world(), Arc::new(surface), vec![], &options).expect("renderer");
    let mut off = Offscreen::new(ctx, SIZE, 2, MAGENTA).unwrap();
    renderer.stages = CullStages::ALL;
    let s = off.settle(ctx, &mut renderer, v, Duration::from_secs(300)).unwrap();
    assert!(s.settled, "streaming did not settle");
    let capture = off.capture(ctx).unwrap();
    let g = renderer.gbuffer.as_ref().unwrap().capture(ctx).unwrap();
    let planes = renderer.read_counters(ctx).unwrap().plane_tiles;
    (capture, g, planes)
}

/// World position of pixel (x, y) from the depth buffer.
fn world_at(v: &View, c: &Capture, x: u32, y: u32) -> Option<DVec3> {
    let d = c.depth[(y * SIZE[0] + x) as usize];
    if d <= 0.0 {
        return None;
    }
    let ray = v.ray([f64::from(x) + 0.5, f64::from(y) + 0.5]);
    let forward = v.camera.basis()[0];
    Some(DVec3::from(v.camera.position_m) + ray * (f64::from(linear_depth(d, v.near_m)) / ray.dot(forward)))
}

fn srgb_to_linear(v: u8) -> f64 {
    let c = f64::from(v) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// A paraboloid seen from above: slopes from flat at its centre to 68
/// degrees at the edge of the view. Threshold 0.5 (45 degrees) and
/// sharpness 0.2: overlay (white) up to 45 degrees, background (red) from
/// 63, the blend between them linear in the slope.
#[test]
fn a_slope_shows_the_overlay_below_the_threshold_and_the_background_above_it() {
    gpu_test(|ctx| {
        let dir = temp_dir("slope");
        let threshold_code = 5; // SLOPE_THRESHOLDS[4] = 0.5
        let threshold = f64::from(vista::world::SLOPE_THRESHOLDS[threshold_code as usize - 1]);
        let (materials, map) = flat_textures(&dir, threshold_code);
        let (a, c) = (0.0042, [512.0, 512.0]);
        let surface = Surface::Paraboloid { z0: 120.0, a, c };
        let v = view([512.0, 512.0, 900.0], 0.0, -90.0, SIZE, 1.0);
        let (capture, g, _) = render(ctx, surface, control_effects(Some(materials), Some(map), 0.3), &v);
        let (white, red) = (srgb_to_linear(WHITE[1]), srgb_to_linear(RED[1]));
        let (mut checked, mut worst, mut overlay, mut background, mut blend) = (0, 0f64, 0, 0, 0);
        for y in 0..SIZE[1] {
            for x in 0..SIZE[0] {
                let i = (y * SIZE[0] + x) as usize;
                let Some(p) = world_at(&v, &capture, x, y) else { continue };
                assert!(g.classification[i] & FLAVOUR_CONTROL_MAP as u8 != 0, "pixel {x},{y} not control-map");
                // The analytic slope, as the flavour measures it; beyond
                // 290 m the paraboloid leaves the world's height range.
                let r = ((p.x - c[0]).powi(2) + (p.y - c[1]).powi(2)).sqrt();
                if r > 290.0 {
                    continue;
                }
                let slope01 = (2.0 * a * r).atan() / std::f64::consts::FRAC_PI_2;
                let want = ((slope01 - threshold) / SHARPNESS).clamp(0.0, 1.0);
                // The background's share from the green channel.
                let got = (srgb_to_linear(g.albedo[i][1]) - white) / (red - white);
                // Tolerance: the normal the flavour sees is the baked one,
                // stored as 8-bit x and y in the atlas (up to 0.9 degrees
                // at 60 degrees of slope), filtered between texels 8 m
                // apart, and again as an 8+8-bit octahedral code in the
                // G-buffer (half a degree): about 1.5 degrees at worst,
                // 0.017 of slope01, 0.08 of the share at this sharpness;
                // the 8-bit sRGB albedo quantises the share by under 0.01.
                // Measured worst: 0.095.
                let err = (got - want).abs();
                worst = worst.max(err);
                assert!(
                    err <= 0.12,
                    "pixel {x},{y} (r {r:.1} m, slope {slope01:.3}): background share {got:.3}, expected {want:.3}"
                );
                overlay += usize::from(want == 0.0);
                background += usize::from(want == 1.0);
                blend += usize::from(want > 0.1 && want < 0.9);
                checked += 1;
            }
        }
        println!("{checked} pixels: {overlay} overlay, {background} background, {blend} blended; worst share error {worst:.3}");
        // Overlay inside r = 119 m (45 degrees), the blend to r = 233 m (63
        // degrees), the background beyond: measured 2348 / 9260 / 18960.
        assert!(overlay > 1000 && blend > 4000 && background > 8000, "{overlay} / {blend} / {background}");
    });
}

/// The classification's plane count at a pixel.
fn planes_of(class: u8) -> u32 {
    let c = u32::from(class);
    if c & CLASS_PLANES_3 != 0 {
        3
    } else if c & CLASS_PLANES_2 != 0 {
        2
    } else {
        1
    }
}

/// A 45-degree cone on flat ground: its flanks lean along x or y (two
/// planes) or diagonally (three, with 0.3: sin 45 / sqrt 2 = 0.5), the
/// ground one. Per pixel the plane bits agree with the analytic normal,
/// the counters with the read-back classification, and the tightened image
/// stays near the untightened one.
#[test]
fn tightened_tri_planar_samples_one_plane_on_flat_ground_and_more_on_flanks() {
    gpu_test(|ctx| {
        let surface = Surface::Bump { z0: 150.0, c: [512.0, 512.0], r: 150.0, h: 150.0 };
        let v = view([512.0, 380.0, 600.0], 0.0, -60.0, SIZE, 1.0);
        let tighten = 0.3;
        let (tight, g, counters) = render(ctx, surface, control_effects(None, None, tighten), &v);
        assert_eq!(counters, plane_tiles_cpu(&g.classification, SIZE, TILE_SIZE), "counters against the read-back");
        let (mut agree, mut total) = (0, 0);
        let mut seen = [0usize; 3];
        for y in 0..SIZE[1] {
            for x in 0..SIZE[0] {
                let i = (y * SIZE[0] + x) as usize;
                let Some(p) = world_at(&v, &tight, x, y) else { continue };
                let d = ((p.x - 512.0).powi(2) + (p.y - 512.0).powi(2)).sqrt();
                // Away from the apex and the foot, where the baked normals
                // (central differences of samples up to 8 m apart, then
                // interpolated) round the cone's kinks, and from normals
                // within 0.02 of the threshold.
                let n = if d > 160.0 {
                    DVec3::Z
                } else if (10.0..140.0).contains(&d) {
                    let s = std::f64::consts::FRAC_1_SQRT_2;
                    DVec3::new(s * (p.x - 512.0) / d, s * (p.y - 512.0) / d, s)
                } else {
                    continue;
                };
                if n.to_array().iter().any(|c| (c.abs() - f64::from(tighten)).abs() < 0.02) {
                    continue;
                }
                let want = n.to_array().iter().filter(|c| c.abs() > f64::from(tighten)).count() as u32;
                let got = planes_of(g.classification[i]);
                seen[got as usize - 1] += 1;
                agree += usize::from(got == want);
                total += 1;
            }
        }
        println!("plane bits: {agree} of {total} pixels agree with the analytic normal; pixels with 1/2/3 planes {seen:?}; tiles {counters:?}");
        assert!(agree as f64 >= 0.99 * total as f64, "{agree} of {total}");
        assert!(counters.iter().all(|&n| n >= 4), "tiles of every plane count: {counters:?}");

        // Untightened (every plane the normal leans towards, weighted by
        // |n|): the flanks' weights below 0.3 were small, so the picture
        // hardly moves. Measured: FLIP mean 0.0001, p99 0.0027; the bound
        // is the golden images' tolerance (the same renderer and view).
        let (loose, _, loose_counters) = render(ctx, surface, control_effects(None, None, 0.0), &v);
        let stats = flip_stats(flip_map(&loose.rgba, &tight.rgba, SIZE));
        println!(
            "tightened against untightened: FLIP mean {:.4}, p99 {:.4}; tiles {loose_counters:?}",
            stats.mean, stats.p99
        );
        assert!(stats.mean <= 0.005 && stats.p99 <= 0.05, "{stats:?}");
        assert!(loose_counters[0] < counters[0], "untightened, fewer tiles sample one plane: {loose_counters:?}");
    });
}

/// Every control texture looks alike far away (the looks only colour the
/// far atlas; these tests read the words).
fn grey_looks() -> vista::world::ControlLooks {
    use vista::world::CONTROL_TEXTURES;
    vista::world::ControlLooks {
        albedo: vec![[100, 100, 100]; CONTROL_TEXTURES],
        smoothness: vec![50; CONTROL_TEXTURES],
        threshold: vec![0.4; CONTROL_TEXTURES],
        sharpness: vec![0.1; CONTROL_TEXTURES],
    }
}

/// A control-map bake: the words come from the map (nearest texel) and
/// survive the node file; repainting a corner of the map rebakes exactly
/// the nodes whose bake reads a repainted texel, and the result equals a
/// full bake byte for byte.
#[test]
fn repainting_a_corner_of_the_control_map_rebakes_only_the_nodes_there() {
    use vista::world::{bake_region, bake_world, BakeSettings, ControlBake, ControlMap, ControlSource, NodeId};
    let world = vista::world::WorldDesc {
        extent_m: [2048.0, 2048.0],
        height_range_m: [0.0, 300.0],
        spacing_m: 2.0,
        lod_count: 4,
        ..Default::default()
    };
    let source: Arc<dyn vista::world::HeightSource> = Arc::new(Surface::Plane(100.0));
    let looks = grey_looks();
    // 256 x 256 texels of 8 m; the repaint covers texel columns 12..20 and
    // rows 230..240 (row 0 north): x in [96, 160) m and, rows counting
    // down from the north edge, y in (128, 208] m.
    let base = ControlCode { overlay: 2, background: 0, uv_scale: 0, threshold: 3 }.encode();
    let paint = ControlCode { overlay: 4, background: 3, uv_scale: 1, threshold: 6 }.encode();
    let mut words = vec![base; 256 * 256];
    let map = |words: &[u16]| {
        let m = ControlMap::from_words(256, 256, words, world.extent_m);
        let control = ControlBake { source: ControlSource::Map(Arc::new(m)), looks: looks.clone(), stamps: Vec::new() };
        BakeSettings { control: Some(control), ..BakeSettings::default() }
    };
    let dir = temp_dir("repaint");
    let (edited, fresh) = (dir.join("edited"), dir.join("fresh"));
    let first = bake_world(Arc::clone(&source), &world, &[], &map(&words), None, &edited, false).unwrap();
    assert_eq!(first.baked, 85);
    for j in 230..240 {
        for i in 12..20 {
            words[j * 256 + i] = paint;
        }
    }
    let block = [96.0, 128.0, 160.0, 208.0];
    let settings = map(&words);
    let second = bake_world(Arc::clone(&source), &world, &[], &settings, None, &edited, false).unwrap();
    // The nodes whose bake region touches a repainted texel's area.
    let touched: Vec<NodeId> = (0..world.lod_count as u8)
        .flat_map(|l| world.nodes_at(l))
        .filter(|&id| {
            let r = bake_region(&world, id);
            r[2] >= block[0] && r[0] < block[2] && r[3] > block[1] && r[1] <= block[3]
        })
        .collect();
    println!("repaint: {} reused, {} rebaked; touched {touched:?}", second.cached, second.rebaked);
    assert_eq!((second.rebaked, second.cached), (touched.len(), 85 - touched.len()));
    // The words of a touched LOD-0 node: texel (i, j) at sample (2i, 2j).
    let cache =
        vista::world::NodeCache::with_settings(&edited, world, Arc::clone(&source), vec![], settings.clone()).unwrap();
    let (node, _) = cache.get_or_bake(NodeId::new(0, 0, 0)).unwrap();
    assert_eq!(node.control.len(), 65 * 65);
    for (k, &w) in node.control.iter().enumerate() {
        let (x, y) = (4.0 * (k % 65) as f64, 4.0 * (k / 65) as f64);
        let inside = (96.0..160.0).contains(&x) && y > 128.0 && y <= 208.0;
        assert_eq!(w, if inside { paint } else { base }, "texel {k} at ({x}, {y})");
    }
    let full = bake_world(source, &world, &[], &settings, None, &fresh, false).unwrap();
    for f in &full.files {
        let rel = format!("lod{}/{}_{}.vnode", f.id.lod, f.id.x, f.id.y);
        assert!(std::fs::read(edited.join(&rel)).unwrap() == std::fs::read(fresh.join(&rel)).unwrap(), "{rel}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A stamp's own control map: inside the stamp's square, where its blend
/// weight reaches a half, its words replace the world's (rotated with it);
/// elsewhere the world's map decides.
#[test]
fn a_stamps_control_map_paints_its_square() {
    use glam::{DMat2, DVec2};
    use vista::world::{
        bake_node_with, BakeSettings, ControlBake, ControlMap, ControlSource, NodeId, StampBlend, StampControl,
        StampPlacement,
    };
    let world = vista::world::WorldDesc {
        extent_m: [1024.0, 1024.0],
        height_range_m: [0.0, 300.0],
        spacing_m: 1.0,
        lod_count: 4,
        ..Default::default()
    };
    let looks = grey_looks();
    let base = ControlCode { overlay: 2, background: 0, uv_scale: 0, threshold: 3 }.encode();
    // The stamp's map: 4 x 4 texels, each its own word (overlay = column,
    // background = row + 8).
    let word =
        |i: usize, j: usize| ControlCode { overlay: i as u8, background: 8 + j as u8, uv_scale: 2, threshold: 1 };
    let words: Vec<u16> = (0..16).map(|k| word(k % 4, k / 4).encode()).collect();
    let placement = StampPlacement {
        center_m: [60.0, 70.0],
        size_m: 80.0,
        rotation_deg: 30.0,
        height_m: 10.0,
        offset_m: 0.0,
        blend: StampBlend::Add,
        falloff_m: 20.0,
    };
    let stamp = StampControl { placement, map: Arc::new(ControlMap::from_words(4, 4, &words, [80.0; 2])) };
    let world_map = ControlMap::from_words(1, 1, &[base], world.extent_m);
    let control = ControlBake { source: ControlSource::Map(Arc::new(world_map)), looks, stamps: vec![stamp] };
    let settings = BakeSettings { control: Some(control), ..BakeSettings::default() };
    let node = bake_node_with(&Surface::Plane(100.0), &world, &[], &settings, NodeId::new(0, 0, 0));
    let (mut inside, mut outside) = (0, 0);
    for (k, &w) in node.control.iter().enumerate() {
        // Splat texel k is node sample (2i, 2j): 2 m apart from the corner.
        let p = DVec2::new(2.0 * (k % 65) as f64, 2.0 * (k / 65) as f64);
        let local = DMat2::from_angle(-30f64.to_radians()) * (p - DVec2::new(60.0, 70.0));
        // The weight reaches 0.5 half-way through the 20 m falloff band.
        let edge = 40.0 - local.x.abs().max(local.y.abs());
        if (edge - 10.0).abs() < 0.01 {
            continue;
        }
        let want = if edge > 10.0 {
            inside += 1;
            // Texel (i, j) of the map, row 0 at the square's north edge.
            let (i, j) = (((local.x + 40.0) / 20.0) as usize, ((40.0 - local.y) / 20.0) as usize);
            word(i.min(3), j.min(3)).encode()
        } else {
            outside += 1;
            base
        };
        assert_eq!(w, want, "texel {k} at {p}: {:?}", ControlCode::decode(w));
    }
    assert!(inside > 500 && outside > 2000, "{inside} inside, {outside} outside");
}

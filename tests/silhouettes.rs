//! No dotted silhouettes: views with ridges and terraces (the default
//! world's overview, low flight, a ridge faced, a low sun with shadows, and
//! Mont Blanc) are rendered in clay and searched for dark dots along depth
//! edges: 0 allowed.
//!
//! A dot is a pixel on the near side of a depth edge (a 4-neighbour at
//! least EDGE_FAR times farther, or background, with the opposite neighbour
//! within EDGE_SAME of its depth: the surface it belongs to) whose lit
//! luminance is below DARK times both the surface it belongs to and the
//! surface beyond (the former alone against background), and below DARK
//! times the darkest the exact surface shows within one pixel of it (the
//! CPU ray caster, one centre ray per pixel, exact shadow rays). Why the
//! last clause: point-sampled, the exact surface has dark edge pixels of its
//! own (a crest's facet that turns from the sun; the counts are printed),
//! and a renderer within a pixel of it may show them a pixel away. DARK
//! (0.75): a one-pixel step of 25 % reads as a dot at display contrast,
//! while a grazing surface's own shading changes by less across a pixel.
//!
//! The cause and the fix: shaders_glsl/common/silhouette.glsl. Before it,
//! these views had 220, 44, 59, 0 and 111 dots.

mod common;

use std::sync::Arc;

use glam::DVec3;
use vista::bench::cull::cull_views;
use vista::passes::cull_patches::CullStages;
use vista::reference::raycast::{RayCaster, RaycastConfig};
use vista::render::offscreen::Offscreen;
use vista::render::{linear_depth, overview_camera, Camera, Effect, Effects, RendererOptions, TerrainRenderer, View};
use vista::terrain::TerrainOptions;
use vista::world::{default_cache_dir, ErrorTree, HeightSource, Png16Source, ProceduralSource, WorldDesc};

const SIZE: [u32; 2] = [640, 360];
/// Linear depth ratios. A few percent: ridges kilometres away overlap ones
/// only 3-7 % farther. On a smooth surface neighbouring pixels differ by
/// nearly the same ratio on both sides, so "4 % farther one way, within 3 %
/// the other" holds only at a step.
const EDGE_FAR: f64 = 1.04;
const EDGE_SAME: f64 = 1.03;
const DARK: f64 = 0.75;
const CLAY: f32 = 0.4;
const LUMA: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// Lit luminance and linear depth (0: background) per pixel.
struct Lit {
    lum: Vec<f64>,
    depth_m: Vec<f64>,
}

impl Lit {
    fn at(&self, x: i64, y: i64) -> usize {
        (y * i64::from(SIZE[0]) + x) as usize
    }
}

/// Near-side depth-edge pixels darker than both surfaces around them, and
/// (with `floor`) darker than DARK times `floor` there too.
fn dark_edges(img: &Lit, floor: Option<&[f64]>) -> Vec<(i64, i64)> {
    let (w, h) = (i64::from(SIZE[0]), i64::from(SIZE[1]));
    let mut out = Vec::new();
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let i = img.at(x, y);
            let z = img.depth_m[i];
            if z <= 0.0 || floor.is_some_and(|f| img.lum[i] >= DARK * f[i]) {
                continue;
            }
            let dark = [(0, -1), (0, 1), (-1, 0), (1, 0)].into_iter().any(|(dx, dy)| {
                let (far, own) = (img.at(x + dx, y + dy), img.at(x - dx, y - dy));
                let (zf, zo) = (img.depth_m[far], img.depth_m[own]);
                let background = zf <= 0.0;
                if zo <= 0.0 || zo > z * EDGE_SAME || z > zo * EDGE_SAME || !(background || zf >= z * EDGE_FAR) {
                    return false;
                }
                let around = if background { img.lum[own] } else { img.lum[own].min(img.lum[far]) };
                img.lum[i] < DARK * around
            });
            if dark {
                out.push((x, y));
            }
        }
    }
    out
}

struct Case {
    name: &'static str,
    world: WorldDesc,
    source: Arc<dyn HeightSource>,
    camera: Camera,
    effects: Effects,
}

fn clay(sun: Option<(f64, f64)>, shadows: bool) -> Effects {
    let mut fx = Effects::default().with(Effect::Shadows, shadows);
    fx.lighting.clay_albedo = Some(CLAY);
    if let Some((azimuth, elevation)) = sun {
        fx.lighting.sun_azimuth_deg = azimuth;
        fx.lighting.sun_elevation_deg = elevation;
    }
    fx
}

fn cases() -> Vec<Case> {
    let world = WorldDesc::default();
    // Terraced, as the default world was before it was eroded: risers are
    // the silhouettes this checks. (The eroded default shows 1 dot in the
    // low-sun shadowed view, at (37, 122): not yet understood.)
    let source = ProceduralSource::new(1, world.extent_m, world.height_range_m).expect("default world");
    let source: Arc<dyn HeightSource> = Arc::new(source.with_terraces(true));
    let views = cull_views(&world, &*source);
    let named = |n: &str| views.iter().find(|(name, _)| name == n).expect("a cull view").1;
    let overview = overview_camera(&world, &*source);
    let mb_world = WorldDesc {
        extent_m: [60_000.0, 60_000.0],
        height_range_m: [454.0, 4810.0],
        spacing_m: 8.0,
        lod_count: 6,
        ..WorldDesc::default()
    };
    let mb_path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/montblanc.png");
    let mb: Arc<dyn HeightSource> =
        Arc::new(Png16Source::open(&mb_path, mb_world.extent_m, mb_world.height_range_m).expect("Mont Blanc DEM"));
    let mb_camera = overview_camera(&mb_world, &*mb);
    let case = |name, world: &WorldDesc, source: &Arc<dyn HeightSource>, camera, effects| Case {
        name,
        world: *world,
        source: source.clone(),
        camera,
        effects,
    };
    vec![
        case("default overview", &world, &source, overview, clay(None, false)),
        case("default low sun, shadows", &world, &source, overview, clay(Some((120.0, 12.0)), true)),
        case("default low flight", &world, &source, named("low flight"), clay(None, false)),
        case("default facing ridge", &world, &source, named("facing ridge"), clay(None, false)),
        case("Mont Blanc overview", &mb_world, &mb, mb_camera, clay(Some((135.0, 35.0)), true)),
    ]
}

/// Renders `case` and returns vista's lit clay image.
fn render(ctx: &vista::gpu::Context, case: &Case, view: &View) -> Lit {
    // The user's error-tree cache, shared with `vista golden` and the
    // tools: the default world's tree takes minutes to compute on 2 cores.
    let errors = ErrorTree::new(&case.world, case.source.clone(), default_cache_dir().as_deref()).expect("error tree");
    let options = RendererOptions {
        effects: case.effects.clone(),
        terrain: TerrainOptions { errors: Some(Arc::new(errors)), ..TerrainOptions::default() },
        ..RendererOptions::default()
    };
    let mut renderer = TerrainRenderer::new(ctx, &case.world, case.source.clone(), vec![], &options).expect("renderer");
    renderer.stages = CullStages::ALL;
    let mut off = Offscreen::new(ctx, SIZE, 2, [0.0; 4]).expect("offscreen");
    off.settle(ctx, &mut renderer, view, std::time::Duration::from_secs(600)).expect("settles");
    let capture = off.capture(ctx).expect("capture");
    let g = renderer.gbuffer.as_ref().expect("a G-buffer").capture(ctx).expect("G-buffer capture");
    Lit {
        lum: g.hdr.iter().map(|c| (0..3).map(|k| f64::from(c[k]) * LUMA[k]).sum()).collect(),
        depth_m: capture.depth.iter().map(|&d| f64::from(linear_depth(d, view.near_m))).collect(),
    }
}

/// The exact surface's lit clay image: the lighting model of
/// `lighting_resolve` on the ray caster's centre normals and shadow rays.
fn reference(case: &Case, view: &View) -> Lit {
    let cfg = RaycastConfig {
        colour_samples: 1,
        shadow_rays: case.effects.is_on(Effect::Shadows),
        ..RaycastConfig::default()
    };
    let caster = RayCaster::new(&*case.source, &case.world, cfg);
    let light = &case.effects.lighting;
    let img = caster.image(view, light, CLAY, [0.0; 4]);
    let sun = light.sun_dir();
    let luma = |c: [f32; 3]| (0..3).map(|k| f64::from(c[k]) * LUMA[k]).sum::<f64>();
    let (sun_l, sky_l) = (luma(light.sun_color), luma(light.sky_color));
    let lum = img
        .normal
        .iter()
        .zip(&img.in_shadow)
        .map(|(n, &shadowed)| {
            let n = DVec3::from(n.map(f64::from));
            let seen = if shadowed { 0.0 } else { 1.0 };
            f64::from(CLAY) * (sun_l * n.dot(sun).max(0.0) * seen + sky_l * (0.5 + 0.5 * n.z))
        })
        .collect();
    Lit { lum, depth_m: img.depth_m.iter().map(|&d| f64::from(d)).collect() }
}

/// The darkest exact-surface luminance within one pixel (3x3), infinite
/// where the exact surface shows only background there.
fn darkest_within_a_pixel(exact: &Lit) -> Vec<f64> {
    let (w, h) = (i64::from(SIZE[0]), i64::from(SIZE[1]));
    let mut out = vec![f64::INFINITY; exact.lum.len()];
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            for (dx, dy) in (-1..=1).flat_map(|dy| (-1..=1).map(move |dx| (dx, dy))) {
                let j = exact.at(x + dx, y + dy);
                if exact.depth_m[j] > 0.0 {
                    out[exact.at(x, y)] = out[exact.at(x, y)].min(exact.lum[j]);
                }
            }
        }
    }
    out
}

#[test]
fn ridges_and_terraces_have_no_dark_dots_along_depth_edges() {
    common::gpu_test(|ctx| {
        let mut failures = Vec::new();
        for case in cases() {
            let view = View { camera: case.camera, fov_y_deg: 60.0, size: SIZE, target_error_px: 1.0, near_m: 0.1 };
            let lit = render(ctx, &case, &view);
            let exact = reference(&case, &view);
            let floor = darkest_within_a_pixel(&exact);
            let dots = dark_edges(&lit, Some(&floor));
            println!(
                "{:<26} dark edge pixels: vista {}, exact surface {}; dots (darker than the exact surface too): {}",
                case.name,
                dark_edges(&lit, None).len(),
                dark_edges(&exact, None).len(),
                dots.len()
            );
            if !dots.is_empty() {
                failures.push(format!("{}: {} dots, first at {:?}", case.name, dots.len(), &dots[..dots.len().min(8)]));
            }
        }
        assert!(failures.is_empty(), "{failures:#?}");
    });
}

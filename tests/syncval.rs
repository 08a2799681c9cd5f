//! Every pass under synchronization validation, with the scene options
//! that build it: one renderer with every effect on (holes, cone and
//! occlusion culling, splat, cliffs, virtual texture, decals with a
//! displacement decal, grass, assets, cliff meshes, shadows, atmosphere,
//! lighting, the debug views), its camera moving close over a meadow with
//! a cone and a hole so that pages render, grass is placed and drawn, the
//! pigment map and the cliff meshes are redone, and a moving sun redoes
//! shadows; one and two command buffers per frame, outputs `lit`, `hdr`
//! and `gbuffer` (the latter two over an engine's loaded depth with its
//! occluder); and the per-triangle LOD rule with every effect. The layer
//! reports nothing, and every pass the renderer built was recorded at
//! least once.

mod common;

use common::gpu_test_with;
use common::terrain::{small_world as world, view, Rig, Surface};
use std::collections::BTreeSet;
use vista::effects::assets::{Asset, AssetKind};
use vista::effects::cliff_meshes::CliffMeshParams;
use vista::effects::grass::GrassParams;
use vista::effects::virtual_texture::decals::{Decal, DecalSet, DecalShape, DecalTexture};
use vista::gpu::{ContextOptions, QueueMode};
use vista::passes::debug_view::DebugView;
use vista::passes::terrain_geometry::DepthOptions;
use vista::render::offscreen::{EngineWall, Offscreen, OffscreenDesc};
use vista::render::{Effect, Effects, LodOptions, LodRule, RendererOptions, View};
use vista::scene::graph::{FramePass, Outcome};
use vista::shaders::consts::DECAL_TEXELS;
use vista::targets::{GbufferLayout, Output};
use vista::world::Hole;

const SIZE: [u32; 2] = [160, 96];
/// A meadow (grass) with a 51-degree cone (rock: cliffs, cliff meshes).
const GROUND: Surface = Surface::Bump { z0: 300.0, c: [500.0, 232.0], r: 10.0, h: 12.0 };
const FRAMES: u32 = 14;

fn effects() -> Effects {
    let mut fx = Effects::default();
    for e in [
        Effect::Splat,
        Effect::Cliffs,
        Effect::VirtualTexture,
        Effect::Decals,
        Effect::Grass,
        Effect::Assets,
        Effect::CliffMeshes,
        Effect::Shadows,
        Effect::Atmosphere,
        Effect::Vegetation,
    ] {
        fx.set(e, true);
    }
    // Scaled to the test world (as each effect's own tests do).
    fx.grass = GrassParams { radius_m: 20.0, fade_m: 4.0, ..GrassParams::default() };
    // The vegetation's occurrence map too (grass_place's OCCURRENCE variant).
    let dir = common::occurrence::unique_dir("vista-syncval-occurrence");
    fx.grass.occurrence = Some(common::occurrence::checkerboard(&dir, world().extent_m, 4.0, [1.0; 5]));
    // Trees and bushes along the walk, near and far (every LOD's draw).
    let at = |x: f64, y: f64| [x as f32, y as f32, GROUND.height(x, y) as f32];
    let trees: Vec<[f32; 3]> = (0..40).map(|k| at(480.0 + 7.0 * (k % 6) as f64, 200.0 + 9.0 * k as f64)).collect();
    let bushes: Vec<[f32; 3]> = (0..12).map(|k| at(505.0 + 2.0 * k as f64, 205.0 + 1.5 * k as f64)).collect();
    let forest = dir.join("forest");
    fx.vegetation.set = Some(std::sync::Arc::new(common::occurrence::forest(&forest, &trees, &bushes)));
    fx.vegetation.folder = Some(forest);
    fx.vegetation.lod_m = [15.0, 60.0];
    fx.cliff_meshes = CliffMeshParams { radius_m: 24.0, ..CliffMeshParams::default() };
    fx.virtual_texture.cache_mb = 16;
    fx.virtual_texture.indirection = 512;
    fx.shade.far_start_m = 300.0;
    fx.shade.far_end_m = 450.0;
    fx
}

fn decals() -> DecalSet {
    let n = DECAL_TEXELS;
    let img = image::RgbaImage::from_fn(n, n, |x, y| image::Rgba([(x % 256) as u8, (y % 256) as u8, 90, 200]));
    let quad = |center: [f64; 2], displace_m| Decal {
        shape: DecalShape::Quad { center_m: center.into(), size_m: [6.0, 4.0].into(), rotation_deg: 30.0 },
        texture: 0,
        opacity: 1.0,
        roughness: Some(0.8),
        displace_m,
    };
    let road = Decal {
        shape: DecalShape::Road {
            points_m: vec![[490.0, 212.0].into(), [505.0, 218.0].into()],
            width_m: 3.0,
            repeat_m: 6.0,
        },
        ..quad([0.0, 0.0], None)
    };
    DecalSet {
        textures: vec![DecalTexture::from_rgba("stripes", &img)].into(),
        decals: vec![quad([496.0, 216.0], Some(0.5)), road],
    }
}

fn options(output: Output, depth: DepthOptions, rule: LodRule) -> RendererOptions {
    RendererOptions {
        lod: LodOptions { rule, ..LodOptions::default() },
        effects: effects(),
        decals: decals(),
        assets: vec![
            Asset { kind: AssetKind::Rock, at_m: [503.0, 214.0], scale: 1.2, yaw_deg: 20.0 },
            Asset { kind: AssetKind::Trunk, at_m: [494.0, 220.0], scale: 1.0, yaw_deg: 0.0 },
        ],
        output,
        depth,
        // The per-pass statistics queries (begun and ended around every
        // graphics-queue pass, reset in the buffer submitted first) are
        // validated with the rest.
        counters: true,
        ..RendererOptions::default()
    }
}

/// Frame `i`: 2 m over the meadow, walking north-east 1.5 m a frame
/// towards the cone (the pigment map's and the cliff meshes' steps are
/// crossed), turning a little.
fn walk(i: u32) -> View {
    let t = f64::from(i);
    let (x, y) = (497.0 + 0.6 * t, 196.0 + 1.4 * t);
    view([x, y, GROUND.height(x, y) + 2.0], 5.0 + t, -10.0, SIZE, 1.0)
}

/// Renders the walk in `mode` (the sun moving 7 degrees a frame, the debug
/// views in turn on the lit output) and returns the passes recorded.
fn run(
    ctx: &vista::gpu::Context,
    output: Output,
    depth: DepthOptions,
    mode: QueueMode,
    rule: LodRule,
) -> BTreeSet<String> {
    let colour = output.color_format().is_some();
    let holes = vec![Hole::Circle { center_m: [505.0, 222.0], radius_m: 3.0 }];
    let mut rig = Rig::with_options(ctx, world(), GROUND, holes, SIZE, false, options(output.clone(), depth, rule));
    let desc = OffscreenDesc { mode, output, ..OffscreenDesc::new(SIZE, common::terrain::MAGENTA) };
    rig.off = Offscreen::with_desc(ctx, &desc).unwrap();
    if depth.load {
        rig.off.wall = Some(EngineWall { rect: [100, 10, 150, 60], distance_m: 25.0, colour: [0.3, 0.3, 0.3, 1.0] });
    }
    // The per-triangle rule's lists start small: they grow (a new buffer
    // each, the old retired behind its frames) under validation too.
    if let Some(t) = rig.renderer.triangles.as_mut() {
        t.emit.restart_lists(ctx, 1000).unwrap();
    }
    let built: Vec<FramePass> = rig.renderer.pass_graph().iter().filter(|n| n.built).map(|n| n.pass).collect();
    let mut ran = BTreeSet::new();
    let mut note = |rig: &Rig| {
        for (pass, outcome) in &rig.renderer.last_frame_log().unwrap().entries {
            if matches!(outcome, Outcome::Recorded { .. }) {
                ran.insert(pass.label());
            }
        }
    };
    // Streaming in (every node arriving is an upload), then the walk; the
    // loader threads get the cores between unsettled frames.
    while !rig.renderer.settled() || rig.renderer.frames_recorded() < 3 {
        assert!(rig.renderer.frames_recorded() < 3000, "streaming did not settle in 3000 frames");
        rig.off.frame(ctx, &mut rig.renderer, &walk(0)).unwrap();
        note(&rig);
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    let views = [DebugView::Lod, DebugView::Classification, DebugView::PatchEdges, DebugView::OcclusionPhase];
    for i in 0..FRAMES {
        rig.renderer.effects.lighting.sun_azimuth_deg = 200.0 + 7.0 * f64::from(i);
        rig.renderer.debug_view = (colour && i % 3 == 2).then(|| views[(i / 3) as usize % views.len()]);
        // Every other frame as a render waiting to settle records it: the
        // whole-frame feedback and the shadows' largest budget.
        rig.renderer.set_catch_up(i % 2 == 1);
        // Every fourth frame draws the last frame's LOD (the LOD camera of
        // `vista bench accuracy --fly`): the LOD phase reads its own view.
        rig.renderer.lod_camera = (i % 4 == 3).then(|| walk(i - 1).camera);
        rig.off.frame(ctx, &mut rig.renderer, &walk(i)).unwrap();
        note(&rig);
    }
    rig.off.capture(ctx).unwrap();
    if let Some(t) = &rig.renderer.triangles {
        assert!(t.emit.capacity(false) > 1000, "{mode:?}: the triangle list never grew");
    }
    for p in built {
        assert!(ran.contains(&p.label()), "{mode:?}: pass {} was built but never recorded: {ran:?}", p.label());
    }
    ran
}

fn syncval() -> ContextOptions {
    ContextOptions { validation: true, sync_validation: true, ..Default::default() }
}

#[test]
fn every_pass_of_every_effect_is_clean_under_synchronization_validation() {
    gpu_test_with(&syncval(), |ctx| {
        for mode in [QueueMode::Single, QueueMode::SplitOneQueue] {
            let ran = run(ctx, Output::default(), DepthOptions::default(), mode, LodRule::Patch);
            // The effects' passes, each recorded (not only built).
            for p in ["vt_pages", "vt_feedback", "grass_place", "grass_draw", "grass_pigment", "asset_draw"] {
                assert!(ran.contains(p), "{mode:?}: {p} did not run: {ran:?}");
            }
            for p in ["cliff_mesh_build", "cliff_meshes", "decal_meshes", "sun_shadows", "debug_view", "terrain_holes"]
            {
                assert!(ran.contains(p), "{mode:?}: {p} did not run: {ran:?}");
            }
            for p in ["vegetation_cull", "vegetation_draw"] {
                assert!(ran.contains(p), "{mode:?}: {p} did not run: {ran:?}");
            }
        }
    });
}

#[test]
fn the_per_triangle_rule_with_every_effect_is_clean_under_synchronization_validation() {
    gpu_test_with(&syncval(), |ctx| {
        for mode in [QueueMode::Single, QueueMode::SplitOneQueue] {
            let ran = run(ctx, Output::default(), DepthOptions::default(), mode, LodRule::Triangle);
            for p in [
                "emit_triangles",
                "emit_fine",
                "terrain_triangles",
                "grass_draw",
                "cliff_meshes",
                "sun_shadows",
                "vt_pages",
            ] {
                assert!(ran.contains(p), "{mode:?}: {p} did not run: {ran:?}");
            }
            for p in ["select_patches", "cull_patches", "terrain_geometry", "terrain_holes", "cull_occluded"] {
                assert!(!ran.contains(p), "{mode:?}: {p} ran beside the per-triangle rule: {ran:?}");
            }
        }
    });
}

#[test]
fn hdr_and_gbuffer_over_a_loaded_depth_are_clean_under_synchronization_validation() {
    gpu_test_with(&syncval(), |ctx| {
        let load = DepthOptions { load: true, ..DepthOptions::default() };
        run(ctx, Output::hdr(), load, QueueMode::SplitOneQueue, LodRule::Patch);
        let ran = run(ctx, Output::Gbuffer(GbufferLayout::octahedral()), load, QueueMode::Single, LodRule::Patch);
        assert!(!ran.contains("lighting_resolve"), "output gbuffer lights nothing: {ran:?}");
        assert!(ran.contains("grass_draw") && ran.contains("asset_draw"), "{ran:?}");
    });
}

/// Frame k's compute submission waits only for frame k-2's graphics
/// (`gpu::COMPUTE_LAG`): on a compute-only queue it runs beside frame
/// k-1's graphics. Syncval cannot see that on a device with one queue (its
/// submissions run in order there), so this test reads what each command
/// buffer touched (`Recorder::log_accesses`, descriptor bindings by their
/// reflected access) over a walk that streams, renders pages, grass and
/// meshes and moves the sun, and proves that frame k's compute and frame
/// k-1's graphics touch nothing that either writes. The one exception are
/// the node atlases, which compute writes a layer at a time while graphics
/// samples the whole array: every layer written must be one frame k-1
/// could not read (not resident then). It is not vacuous: each frame's
/// compute writes what its own graphics and frame k-2's graphics read.
#[test]
fn a_frames_compute_and_the_last_frames_graphics_share_nothing_either_writes() {
    use vista::gpu::access_log::{conflicts, Access};
    use vista::gpu::{vk, FrameCommands, FrameRing};
    use vista::passes::terrain_geometry::RenderTargets;
    use vista::render::offscreen::render_targets;
    common::gpu_test(|ctx| {
        let holes = vec![Hole::Circle { center_m: [505.0, 222.0], radius_m: 3.0 }];
        let options = options(Output::default(), DepthOptions::default(), LodRule::Patch);
        let mut rig = Rig::with_options(ctx, world(), GROUND, holes, SIZE, false, options);
        let mode = QueueMode::SplitOneQueue;
        let mut ring = FrameRing::with_mode(ctx, 2, mode).unwrap();
        let (color, depth) =
            render_targets(ctx, "in_flight", SIZE, vista::passes::terrain_geometry::DEPTH_FORMAT).unwrap();
        // Per frame: compute's accesses, graphics', the slots held after it.
        let mut frames: Vec<(Vec<Access>, Vec<Access>, Vec<u32>)> = Vec::new();
        // 30 frames at least, and on until streaming settled (the loader
        // threads get the cores between unsettled frames): every node the
        // walk wants arrives while the frame before it is drawn.
        let mut i = 0u32;
        while i < 30 || !rig.renderer.settled() {
            assert!(i < 3000, "streaming did not settle in 3000 frames");
            rig.renderer.effects.lighting.sun_azimuth_deg = 200.0 + 7.0 * f64::from(i % 50);
            let view = walk((i / 2).min(14));
            ring.record_frame(ctx, |cmds| {
                let FrameCommands::Split { compute, graphics } = cmds else { unreachable!("a split ring") };
                compute.log_accesses();
                graphics.log_accesses();
                if i == 0 {
                    graphics.discard_to(&color, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
                    graphics.discard_to(&depth, vista::passes::terrain_geometry::DEPTH_LAYOUT);
                    graphics.take_accesses();
                }
                let split = FrameCommands::Split { compute: &mut *compute, graphics: &mut *graphics };
                let targets = RenderTargets::color(&color, &depth, common::terrain::MAGENTA);
                rig.renderer.record_frame(split, mode, &view, &targets)?;
                frames.push((
                    compute.take_accesses(),
                    graphics.take_accesses(),
                    rig.renderer.terrain.tree.shadow.held_slots(),
                ));
                Ok(())
            })
            .unwrap();
            if !rig.renderer.settled() {
                std::thread::sleep(std::time::Duration::from_millis(10));
            }
            i += 1;
        }
        ring.wait_all(ctx).unwrap();
        let (mut layers_written, mut same_frame, mut two_back) = (0, 0, 0);
        for k in 1..frames.len() {
            let (compute, _, _) = &frames[k];
            let (_, previous_graphics, held) = &frames[k - 1];
            for (c, g) in conflicts(compute, previous_graphics) {
                // A layer of an array compute uploads: one frame k - 1 held no node in.
                let free_layer = c.layer.is_some_and(|l| !held.contains(&l)) && !g.write;
                assert!(free_layer, "frame {k}'s compute and frame {}'s graphics both touch {c:?} / {g:?}", k - 1);
                layers_written += 1;
            }
            same_frame += conflicts(compute, &frames[k].1).len();
            if k >= 2 {
                two_back += conflicts(compute, &frames[k - 2].1).iter().filter(|(c, _)| c.layer.is_none()).count();
            }
        }
        println!(
            "atlas layers written beside the last frame's sampling: {layers_written}; compute/graphics pairs \
                  the semaphores order: {same_frame} in the same frame, {two_back} two frames apart"
        );
        assert!(
            layers_written > 0,
            "no node arrived while the last frame sampled the atlases: the walk streamed nothing"
        );
        assert!(same_frame > 0 && two_back > 0, "the check would pass anything");
    });
}

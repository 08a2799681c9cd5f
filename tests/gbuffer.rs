//! The G-buffer tile shading: the tile lists equal a CPU classification of
//! the read-back classification target; shading tile by tile with one
//! pipeline per variant equals one pipeline doing every flavour
//! everywhere; stochastic cliffs stay put under a 1 cm camera step and
//! average over hash seeds to the fully blended shading.

mod common;

use common::gpu_test;
use common::terrain::{small_world as world, view, Rig, Surface};
use vista::passes::cull_patches::CullStages;
use vista::reference::classify_tiles_cpu;
use vista::render::{Effect, Effects, RendererOptions, Shading, View};
use vista::shaders::consts::{
    FLAVOUR_FAR_ATLAS, FLAVOUR_FAR_CLIFF, FLAVOUR_NEAR_CLIFF, FLAVOUR_SPLAT, FLAVOUR_VARIANTS, TILE_SIZE,
};
use vista::targets::gbuffer::GBufferCapture;

/// Not a multiple of the tile size: the last tile column and row are partial.
const SIZE: [u32; 2] = [100, 60];

/// Over the hills with every flavour in view: the thresholds are scaled to
/// this small world (the hills are gentle, so cliffs start at 12 degrees).
fn shading() -> Effects {
    let mut fx = Effects::default().with(Effect::Splat, true).with(Effect::Cliffs, true);
    fx.shade.cliff_slope_deg = 12.0;
    fx.shade.cliff_band_deg = 6.0;
    fx.shade.far_start_m = 300.0;
    fx.shade.far_end_m = 450.0;
    fx.shade.cliff_split_start_m = 250.0;
    fx.shade.cliff_split_end_m = 350.0;
    fx
}

fn over_the_hills() -> View {
    view([512.0, 120.0, 520.0], 10.0, -25.0, SIZE, 1.0)
}

fn rig(ctx: &vista::gpu::Context, fx: Effects, shading: Shading) -> Rig {
    let options = RendererOptions { effects: fx, shading, ..RendererOptions::default() };
    Rig::with_options(ctx, world(), Surface::Hills, vec![], SIZE, false, options)
}

fn capture(ctx: &vista::gpu::Context, rig: &Rig) -> GBufferCapture {
    rig.renderer.gbuffer.as_ref().unwrap().capture(ctx).unwrap()
}

#[test]
fn tile_lists_equal_a_cpu_classification_of_the_read_back_target() {
    gpu_test(|ctx| {
        let mut rig = rig(ctx, shading(), Shading::Tiled);
        rig.shot(ctx, &over_the_hills(), CullStages::ALL);
        let g = capture(ctx, &rig);
        let expected = classify_tiles_cpu(&g.classification, SIZE, TILE_SIZE, FLAVOUR_VARIANTS as usize);
        let mut got = rig.renderer.classify.lists.as_ref().unwrap().read(ctx).unwrap();
        for l in &mut got {
            l.sort_by_key(|t| (t[1], t[0]));
        }
        assert_eq!(got, expected, "tile lists per variant");
        let used: Vec<usize> = (0..expected.len()).filter(|&v| !expected[v].is_empty()).collect();
        // A meaningful view: every flavour and several combined variants.
        let bits = used.iter().fold(0, |a, &v| a | v as u32);
        let all = FLAVOUR_FAR_ATLAS | FLAVOUR_SPLAT | FLAVOUR_NEAR_CLIFF | FLAVOUR_FAR_CLIFF;
        assert_eq!(bits, all, "variants in view: {used:?}");
        assert!(used.len() >= 4, "variants in view: {used:?}");
        // The frame-late counters agree with the lists.
        let counters = rig.renderer.read_counters(ctx).unwrap();
        for (v, list) in expected.iter().enumerate() {
            assert_eq!(counters.tiles[v] as usize, list.len(), "variant {v} tile count");
        }
    });
}

#[test]
fn tiled_shading_equals_one_shader_doing_every_flavour() {
    gpu_test(|ctx| {
        let v = over_the_hills();
        let mut tiled = rig(ctx, shading(), Shading::Tiled);
        let a = tiled.shot(ctx, &v, CullStages::ALL);
        let ga = capture(ctx, &tiled);
        drop(tiled);
        // Both one-pipeline references: branching past unneeded flavours,
        // and evaluating every flavour with weight 0 where unneeded.
        for mode in [Shading::OneShader, Shading::OneShaderEveryFlavour] {
            let mut one = rig(ctx, shading(), mode);
            let b = one.shot(ctx, &v, CullStages::ALL);
            let gb = capture(ctx, &one);
            assert_eq!(one.renderer.gbuffer_tiles.variants().len(), 1, "{mode:?}: one pipeline");
            assert_eq!(ga.classification, gb.classification);
            // Each pipeline is compiled from the same code with other
            // constant flavour bits; a compiler may still contract or
            // reorder the arithmetic of the flavours both evaluate
            // differently, so allow one 8-bit step; the material ids and
            // flavour bits must agree.
            let max_diff = |x: &[[u8; 4]], y: &[[u8; 4]]| {
                x.iter().zip(y).flat_map(|(p, q)| (0..4).map(move |i| p[i].abs_diff(q[i]))).max().unwrap_or(0)
            };
            assert!(max_diff(&ga.albedo, &gb.albedo) <= 1, "{mode:?}: albedo");
            assert!(max_diff(&ga.normal, &gb.normal) <= 1, "{mode:?}: normal");
            assert_eq!(ga.material, gb.material, "{mode:?}: material ids and flavour bits");
            let rgba = |c: &[u8]| c.chunks(4).map(|p| [p[0], p[1], p[2], p[3]]).collect::<Vec<_>>();
            assert!(max_diff(&rgba(&a.rgba), &rgba(&b.rgba)) <= 1, "{mode:?}: lit image");
        }
        let terrain = ga.classification.iter().filter(|&&c| c != 0).count();
        assert!(terrain > SIZE[0] as usize * SIZE[1] as usize / 2, "mostly terrain: {terrain}");
    });
}

/// Mean over cliff pixels (flavour bits of either cliff) of |a - b| in
/// linear RGB.
fn cliff_mean_diff(g: &GBufferCapture, a: &[[f32; 4]], b: &[[f32; 4]]) -> (f64, usize) {
    let cliff = (FLAVOUR_NEAR_CLIFF | FLAVOUR_FAR_CLIFF) as u8;
    let (mut sum, mut n) = (0.0, 0);
    for (i, &c) in g.classification.iter().enumerate() {
        if c & cliff != 0 {
            sum += (0..3).map(|k| f64::from((a[i][k] - b[i][k]).abs())).sum::<f64>() / 3.0;
            n += 1;
        }
    }
    (sum / n.max(1) as f64, n)
}

#[test]
fn stochastic_cliffs_are_stable_and_average_to_the_blended_shading() {
    gpu_test(|ctx| {
        let v = over_the_hills();
        let mut fx = shading();
        fx.shade.stochastic = false;
        let mut blended = rig(ctx, fx, Shading::Tiled);
        blended.shot(ctx, &v, CullStages::ALL);
        let reference = capture(ctx, &blended);
        drop(blended);

        let mut r = rig(ctx, shading(), Shading::Tiled);
        r.shot(ctx, &v, CullStages::ALL);
        let one_seed = capture(ctx, &r);
        let (single_err, cliff_px) = cliff_mean_diff(&reference, &one_seed.hdr, &reference.hdr);
        assert!(cliff_px > 200, "cliff pixels in view: {cliff_px}");

        // 1 cm sideways: world-anchored noise keeps each pixel's choice
        // (only the sub-pixel shift of the surface changes a pixel).
        let mut step = v.clone();
        step.camera.position_m[0] += 0.01;
        r.again(ctx, &step, CullStages::ALL);
        let moved = capture(ctx, &r);
        let (motion, _) = cliff_mean_diff(&reference, &moved.hdr, &one_seed.hdr);
        // Screen-space noise would re-pick per pixel: a change about the
        // size of the single-seed error. World-anchored: far below it.
        assert!(motion < 0.25 * single_err, "1 cm step changed cliffs by {motion:.5} (noise level {single_err:.5})");

        // Averaging seeds converges to the blended shading.
        let seeds = 24;
        let mut mean = vec![[0.0f32; 4]; one_seed.hdr.len()];
        for s in 0..seeds {
            r.renderer.shade.hash_seed = 1000 + s;
            r.again(ctx, &v, CullStages::ALL);
            let g = capture(ctx, &r);
            for (m, p) in mean.iter_mut().zip(&g.hdr) {
                (0..4).for_each(|k| m[k] += p[k] / seeds as f32);
            }
        }
        let (avg_err, _) = cliff_mean_diff(&reference, &mean, &reference.hdr);
        // The mean of n picks has about 1/sqrt(n) of one pick's error.
        assert!(
            avg_err < 0.5 * single_err,
            "{seeds} seeds: {avg_err:.5} vs one seed {single_err:.5} from the blended shading"
        );
        println!(
            "cliff pixels {cliff_px}: one seed {single_err:.5}, 1 cm step {motion:.5}, {seeds} seeds {avg_err:.5}"
        );
    });
}

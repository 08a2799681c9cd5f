//! Effect `vegetation` (trees and bushes of a `vista vegetate` folder)
//! under the validation layer: culling is conservative (the picture with
//! every cull on is the picture with none), the counters add up and every
//! LOD is drawn, and off builds nothing.

mod common;

use common::gpu_test;
use common::terrain::{small_world as world, view, Rig, Surface};
use std::sync::Arc;
use vista::effects::vegetation::frame::{Vegetation, VegetationHeaderGpu};
use vista::gpu::Context;
use vista::passes::cull_patches::CullStages;
use vista::render::{Effect, Effects, RendererOptions, View};

const SIZE: [u32; 2] = [192, 128];
/// A meadow with a 40 m hill on the line of trees (it hides some).
const GROUND: Surface = Surface::Bump { z0: 300.0, c: [500.0, 420.0], r: 80.0, h: 40.0 };

/// Trees every 12 m along a line north from the camera (near, middle and
/// far: every LOD), some behind it and beyond the draw distance, and a
/// row of bushes.
fn effects(on: bool) -> Effects {
    let dir = common::occurrence::unique_dir("vista-vegetation-draw");
    let at = |x: f64, y: f64| [x as f32, y as f32, GROUND.height(x, y) as f32];
    let trees: Vec<[f32; 3]> =
        (0..80).map(|k| at(500.0 + 9.0 * (k % 3) as f64, 126.0 + 12.0 * k as f64)).chain([at(500.0, 60.0)]).collect();
    let bushes: Vec<[f32; 3]> = (0..20).map(|k| at(485.0 + 1.5 * k as f64, 140.0 + 2.0 * k as f64)).collect();
    let mut fx = Effects::default().with(Effect::Vegetation, on).with(Effect::Lighting, true);
    fx.vegetation.set = Some(Arc::new(common::occurrence::forest(&dir, &trees, &bushes)));
    fx.vegetation.folder = Some(dir);
    fx.vegetation.lod_m = [40.0, 150.0];
    fx.vegetation.tree_draw_m = 700.0;
    fx
}

fn rig(ctx: &Context, fx: Effects) -> Rig {
    let options = RendererOptions { effects: fx, ..RendererOptions::default() };
    Rig::with_options(ctx, world(), GROUND, vec![], SIZE, false, options)
}

/// 8 m over the meadow at (500, 110), looking north along the trees.
fn look() -> View {
    view([500.0, 110.0, GROUND.height(500.0, 110.0) + 8.0], 0.0, -2.0, SIZE, 1.0)
}

fn header(ctx: &Context, rig: &Rig) -> VegetationHeaderGpu {
    let v = rig.renderer.effect::<Vegetation>().expect("vegetation is built");
    bytemuck::pod_read_unaligned(&ctx.read_buffer(v.header()).unwrap()[..VegetationHeaderGpu::BYTES as usize])
}

/// Every instance culled or drawn once, counted where it was culled.
fn check_counts(h: &VegetationHeaderGpu) -> Vec<u32> {
    let drawn: Vec<u32> = (0..6).map(|d| h.drawn(d)).collect();
    println!(
        "{} clusters ({} instances) culled whole; {} visited: {} by distance, {} by the frustum, {} by the \
         pyramid; drawn {drawn:?}",
        h.clusters_culled, h.skipped, h.considered, h.culled_distance, h.culled_frustum, h.culled_hiz
    );
    let all = h.culled_distance + h.culled_frustum + h.culled_hiz + drawn.iter().sum::<u32>();
    assert_eq!((h.considered + h.skipped, all), (101, h.considered), "every instance culled or drawn once");
    drawn
}

/// With 64 m clusters the far trees' clusters are culled whole; with one
/// cluster every instance is tested one by one. Both pictures equal the
/// one with no culling at all.
#[test]
fn culling_is_conservative_and_every_lod_draws() {
    gpu_test(|ctx| {
        let mut pictures = Vec::new();
        for cluster_m in [64.0, 10_000.0] {
            let mut fx = effects(true);
            fx.vegetation.cluster_m = cluster_m;
            let mut rig = rig(ctx, fx);
            pictures.push(rig.shot(ctx, &look(), CullStages::ALL));
            let h = header(ctx, &rig);
            let drawn = check_counts(&h);
            assert!(
                drawn[0] > 0 && drawn[1] > 0 && drawn[2] > 0 && drawn[3] > 0,
                "trees at each LOD, bushes: {drawn:?}"
            );
            if cluster_m == 64.0 {
                assert!(h.clusters_culled > 0 && h.skipped > 0, "the far trees' clusters are culled whole");
            } else {
                assert_eq!(h.clusters_culled, 0, "one cluster, in view");
                assert!(h.culled_distance > 0 && h.culled_frustum > 0, "the far trees and the one behind, one by one");
            }
        }
        let mut rig = rig(ctx, effects(true));
        rig.renderer.effect_mut::<Vegetation>().unwrap().no_culling = true;
        let every = rig.shot(ctx, &look(), CullStages::ALL);
        let h = header(ctx, &rig);
        assert_eq!((h.culled_distance, h.culled_frustum, h.culled_hiz, h.skipped), (0, 0, 0, 0));
        // Every instance drawn, and not one pixel differs: no culled
        // instance or cluster covered any.
        for culled in &pictures {
            assert!(culled.rgba == every.rgba && culled.depth == every.depth, "culling changed the picture");
        }
    });
}

#[test]
fn off_nothing_is_built_and_a_folder_is_needed() {
    gpu_test(|ctx| {
        let mut off = rig(ctx, effects(false));
        let mut no_folder = Effects::default().with(Effect::Vegetation, true);
        no_folder.vegetation = Default::default();
        let refused = rig(ctx, no_folder);
        let d = refused.renderer.effects().iter().find(|d| d.effect == Effect::Vegetation).unwrap().clone();
        assert!(!d.on && d.reason.contains("no vegetation folder"), "{}", d.reason);
        for r in [&off, &refused] {
            assert!(r.renderer.effect::<Vegetation>().is_none());
            assert!(!r.renderer.pipelines().iter().any(|p| p.contains("vegetation")), "{:?}", r.renderer.pipelines());
            assert!(!r.renderer.memory().iter().any(|(_, _, e)| e.contains(&Effect::Vegetation)));
        }
        let mut on = rig(ctx, effects(true));
        let a = off.shot(ctx, &look(), CullStages::ALL);
        let b = on.shot(ctx, &look(), CullStages::ALL);
        let differs = a.rgba.chunks(4).zip(b.rgba.chunks(4)).filter(|(x, y)| x != y).count();
        assert!(differs > 1000, "the trees changed {differs} pixels");
    });
}

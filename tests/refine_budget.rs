//! The refinement budget refuses by priority, not by arrival: with about
//! ten times more LOD-0 patches asking to be refined below the samples than
//! the budget holds, every selection word, the counters and the frame are
//! the same whether select_patches takes the node list and each node's
//! patches in order or reversed (the workgroup and invocation order of
//! another device); the patches kept are within the budget. The first-come
//! cap this replaced (`atomicAdd(refined) >= budget`) fails it: reversed,
//! 48 selection words differ (24 patches refused, 24 others refined).

mod common;

use common::gpu_test;
use vista::render::stats::collect;
use vista::render::{LodOptions, RendererOptions, View};
use vista::stability::rig::{fly_through, Rig};

const BUDGET: u32 = 24;

#[test]
fn a_capped_refinement_does_not_depend_on_the_order_nodes_are_taken_in() {
    gpu_test(|ctx| {
        let lod = LodOptions { refine_budget: BUDGET, ..LodOptions::default() };
        let mut rig =
            Rig::new(ctx, [96, 64], 400, RendererOptions { lod, ..RendererOptions::default() }, Vec::new()).unwrap();
        // The low end of the stability script's flight at a fine target:
        // about ten times the budget asks to be refined.
        let view = View { target_error_px: 0.1, ..rig.view(fly_through(&rig, 29, 30)) };
        let listed = rig.settled_shot(ctx, &view).unwrap();
        let select = collect(ctx, &rig.renderer, &view).unwrap().select;
        assert!(select.refined > 4 * BUDGET, "the view must ask for more than the budget: {select:?}");
        let kept = select.refined - select.refine_capped;
        assert!(kept > 0 && kept <= BUDGET, "{select:?}");
        let levels = ctx.read_buffer(rig.renderer.select.levels()).unwrap();
        // The levels are double-buffered by frame parity: the reversed frame
        // writes over what the same parity's listed frame wrote.
        rig.shot(ctx, &view).unwrap();
        rig.renderer.select.reversed = true;
        let reversed = rig.shot(ctx, &view).unwrap();
        let again = collect(ctx, &rig.renderer, &view).unwrap().select;
        assert_eq!(again, select, "the counters with the node list reversed");
        let reversed_levels = ctx.read_buffer(rig.renderer.select.levels()).unwrap();
        let differ = levels.chunks(4).zip(reversed_levels.chunks(4)).filter(|(a, b)| a != b).count();
        assert_eq!(differ, 0, "selection words that changed with the order of the node list");
        assert!(reversed.rgba == listed.rgba, "the picture changed with the order of the node list");
        assert!(reversed.depth == listed.depth, "the depth changed with the order of the node list");
        // Without a budget every asking patch is refined.
        let lod = LodOptions::default();
        let mut free =
            Rig::new(ctx, [96, 64], 400, RendererOptions { lod, ..RendererOptions::default() }, Vec::new()).unwrap();
        free.settled_shot(ctx, &view).unwrap();
        let all = collect(ctx, &free.renderer, &view).unwrap().select;
        assert_eq!((all.refined, all.refine_capped), (select.refined, 0), "{all:?}");
    });
}

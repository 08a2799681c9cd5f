//! The debug views of `vista view` (`TerrainRenderer::debug_view`): each
//! colours every pixel as its CPU twin (`DebugView::colour_of`) says from
//! the G-buffer's patch info and classification, and keeps the picture
//! elsewhere; the patch info holds the LOD and refinement of the patches
//! actually drawn; nothing is recorded when no view is asked for.

mod common;

use common::gpu_test;
use common::terrain::{small_world, view, Rig, Surface};
use std::collections::BTreeSet;
use vista::passes::cull_patches::CullStages;
use vista::passes::debug_view::DebugView;
use vista::scene::graph::{FramePass, Outcome, Skip};
use vista::shaders::consts as k;

const SIZE: [u32; 2] = [128, 80];

#[test]
fn each_debug_view_matches_its_cpu_twin_and_the_patch_info_names_the_patches_drawn() {
    gpu_test(|ctx| {
        // Low over hills: several LODs in view.
        let mut rig = Rig::new(ctx, small_world(), Surface::Hills, vec![], SIZE, false);
        let v = view([512.0, 60.0, 330.0], 0.0, -15.0, SIZE, 0.5);
        rig.shot(ctx, &v, CullStages::ALL);
        // Phase 1 draws what its copy of the visibility bits holds (two
        // frames old, frame::per_frame): one more frame and it knows every
        // node the settle brought.
        let plain = rig.again(ctx, &v, CullStages::ALL);
        let outcome = |rig: &Rig| rig.renderer.last_frame_log().and_then(|l| l.outcome(FramePass::DEBUG_VIEW)).cloned();
        assert_eq!(outcome(&rig), Some(Outcome::Skipped(Skip::NoDebugView)));
        let g = rig.renderer.gbuffer.as_ref().unwrap().capture(ctx).unwrap();

        // What the patch info says was drawn is what the patch list drew.
        let drawn: BTreeSet<(u8, u8)> =
            rig.renderer.read_patches(ctx).unwrap().iter().map(|p| (p.lod, p.refine)).collect();
        let mut seen = BTreeSet::new();
        let (mut edges, mut terrain) = (0, 0);
        for (&info, &class) in g.patch_info.iter().zip(&g.classification) {
            if class == 0 {
                continue;
            }
            terrain += 1;
            let lod = (u32::from(info) & k::PATCH_INFO_LOD_MASK) as u8;
            let refine = ((u32::from(info) >> k::PATCH_INFO_REFINE_SHIFT) & 3) as u8;
            seen.insert((lod, refine));
            edges += usize::from(u32::from(info) >> k::PATCH_INFO_EDGE_SHIFT != 0);
            // A settled, static view: phase 1 draws everything visible.
            assert_eq!((u32::from(info) >> k::PATCH_INFO_PHASE_SHIFT) & 1, 0, "a pixel drawn in phase 2");
        }
        assert!(seen.is_subset(&drawn), "patch info {seen:?}, patches drawn {drawn:?}");
        assert!(seen.len() >= 3, "too few levels in view to test: {seen:?}");
        // Patch outlines a pixel wide: some pixels, far from all.
        assert!(edges > terrain / 50 && edges < terrain / 2, "{edges} edge pixels of {terrain}");

        for dv in DebugView::ALL {
            rig.renderer.debug_view = Some(dv);
            let shot = rig.again(ctx, &v, CullStages::ALL);
            assert!(matches!(outcome(&rig), Some(Outcome::Recorded { .. })), "{}: not recorded", dv.name());
            let mut worst = 0;
            for i in 0..(SIZE[0] * SIZE[1]) as usize {
                let want = dv.colour_of(g.patch_info[i], g.classification[i]);
                let want = want.unwrap_or([plain.rgba[4 * i], plain.rgba[4 * i + 1], plain.rgba[4 * i + 2]]);
                let got = &shot.rgba[4 * i..4 * i + 3];
                worst = worst.max(want.iter().zip(got).map(|(a, b)| a.abs_diff(*b)).max().unwrap());
            }
            // One step: the shader's UNORM rounding of the same mean.
            assert!(worst <= 1, "{}: a pixel {worst} steps from its CPU twin", dv.name());
        }
        rig.renderer.debug_view = None;
        let back = rig.again(ctx, &v, CullStages::ALL);
        assert!(back.rgba == plain.rgba, "the picture without a debug view changed");
    });
}

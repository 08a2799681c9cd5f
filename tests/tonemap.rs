//! The display image is the linear image through the scene's tonemapper:
//! every terrain pixel of `lighting_resolve`'s output equals the CPU
//! reference's transform (src/reference/tonemap.rs, from the published
//! definitions) of the HDR value read back beside it, for ACES fitted with
//! an exposure and for the clip; highlights above 1 roll off under ACES
//! instead of clipping.

mod common;

use common::gpu_test;
use common::terrain::{small_world as world, view, Rig, Surface};
use vista::passes::cull_patches::CullStages;
use vista::reference::tonemap::display;
use vista::render::{Effect, Effects, RendererOptions, Tonemap};

const SIZE: [u32; 2] = [96, 64];

#[test]
fn the_display_image_is_the_hdr_image_through_the_tonemapper() {
    gpu_test(|ctx| {
        for (tonemap, ev) in [(Tonemap::Aces, 0.7), (Tonemap::Clip, -0.5), (Tonemap::Aces, 0.0)] {
            let mut fx = Effects::default().with(Effect::Lighting, true);
            // Bright clay: sunlit slopes reach 1.3 to 1.6, above the clip.
            fx.lighting.clay_albedo = Some(0.8);
            fx.lighting.tonemap = tonemap;
            fx.lighting.exposure_ev = Some(ev);
            let options = RendererOptions { effects: fx, ..RendererOptions::default() };
            let mut rig = Rig::with_options(ctx, world(), Surface::Hills, vec![], SIZE, false, options);
            let shot = rig.shot(ctx, &view([512.0, 120.0, 520.0], 10.0, -25.0, SIZE, 1.0), CullStages::ALL);
            let g = rig.renderer.gbuffer.as_ref().unwrap().capture(ctx).unwrap();
            let (mut terrain, mut bright, mut worst) = (0, 0, 0i32);
            for (i, hdr) in g.hdr.iter().enumerate() {
                // Terrain only: the background keeps the clear colours.
                if shot.depth[i] == 0.0 {
                    continue;
                }
                terrain += 1;
                let rgb = [hdr[0], hdr[1], hdr[2]].map(f64::from);
                let want = display(tonemap, ev, rgb).map(|c| (c * 255.0).round() as i32);
                let got = &shot.rgba[4 * i..4 * i + 3];
                for c in 0..3 {
                    worst = worst.max((i32::from(got[c]) - want[c]).abs());
                }
                let exposed = rgb.map(|c| c * 2f64.powf(ev.into()));
                if exposed.iter().any(|&c| c > 1.0) {
                    bright += 1;
                    // Under ACES a highlight keeps its gradation: below white.
                    if tonemap == Tonemap::Aces && exposed.iter().all(|&c| c < 4.0) {
                        assert!(got.iter().any(|&c| c < 255), "{tonemap} pixel {i}: {got:?} from {exposed:?}");
                    }
                }
            }
            assert!(terrain > (SIZE[0] * SIZE[1]) as usize / 2, "{tonemap}: {terrain} terrain pixels");
            assert!(bright > 0, "{tonemap} {ev}: no exposed value above 1 in view");
            // One 8-bit step: the HDR target holds f16 (relative error
            // 2^-11) and the GPU evaluates in f32, the reference in f64.
            assert!(worst <= 1, "{tonemap} {ev}: a channel {worst} steps from the reference");
        }
    });
}

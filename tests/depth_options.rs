//! The engine's depth target (`RendererOptions::depth`): vista draws the
//! same picture and depth into `D32_SFLOAT` (no stencil, in
//! DEPTH_ATTACHMENT_OPTIMAL) as into the default `D32_SFLOAT_S8_UINT`; it
//! sets exactly the stencil bit it is given on exactly the terrain pixels;
//! without a bit it leaves the engine's stencil as it was; and a format or
//! bit it cannot use is refused before anything is built.

mod common;

use common::gpu_test;
use common::terrain::{small_world as world, view, Rig, Surface};
use std::sync::Arc;
use vista::error::Error;
use vista::gpu::{vk, Context};
use vista::passes::cull_patches::CullStages;
use vista::passes::terrain_geometry::DepthOptions;
use vista::render::{Effects, RendererOptions, TerrainRenderer, View};
use vista::world::Hole;

const SIZE: [u32; 2] = [96, 64];

/// Over the hills toward a hole and the sky: terrain, background and a
/// hole's edge in one picture.
fn toward_hole() -> View {
    view([512.0, 250.0, 750.0], 0.0, -30.0, SIZE, 1.0)
}

fn holes() -> Vec<Hole> {
    vec![Hole::Circle { center_m: [512.0, 600.0], radius_m: 60.0 }]
}

fn rig(ctx: &Context, depth: DepthOptions) -> Rig {
    let options = RendererOptions { depth, effects: Effects::default(), ..RendererOptions::default() };
    Rig::with_options(ctx, world(), Surface::Hills, holes(), SIZE, false, options)
}

/// The stencil bit `bit` of every pixel, and whether the pixel has terrain
/// (depth above the far plane's 0).
fn bits_and_terrain(stencil: &[u8], depth: &[f32], bit: u32) -> (Vec<bool>, Vec<bool>) {
    (stencil.iter().map(|s| s & (1 << bit) != 0).collect(), depth.iter().map(|&d| d > 0.0).collect())
}

#[test]
fn a_depth_only_target_gets_the_same_picture_and_depth() {
    gpu_test(|ctx| {
        let v = toward_hole();
        let default = rig(ctx, DepthOptions::default()).shot(ctx, &v, CullStages::ALL);
        let only = DepthOptions { format: vk::Format::D32_SFLOAT, terrain_stencil_bit: None, load: false };
        let mut r = rig(ctx, only);
        let c = r.shot(ctx, &v, CullStages::ALL);
        assert_eq!(r.off.depth.layout(), vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL);
        let terrain = c.depth.iter().filter(|&&d| d > 0.0).count();
        assert!(terrain > 100 && terrain < c.depth.len() - 100, "terrain and background in view: {terrain}");
        assert!(c.depth == default.depth, "depth differs from the default target's");
        assert!(c.rgba == default.rgba, "the picture differs from the default target's");
    });
}

#[test]
fn the_stencil_bit_asked_for_is_set_exactly_on_terrain_pixels() {
    gpu_test(|ctx| {
        let v = toward_hole();
        for bit in [0, 5, 7] {
            let mut r = rig(ctx, DepthOptions { terrain_stencil_bit: Some(bit), ..DepthOptions::default() });
            let c = r.shot(ctx, &v, CullStages::ALL);
            let stencil = ctx.read_stencil(&r.off.depth).unwrap();
            let (set, terrain) = bits_and_terrain(&stencil, &c.depth, bit);
            assert!(set == terrain, "bit {bit}: set where there is no terrain or missing where there is");
            let others = stencil.iter().filter(|&&s| s & !(1 << bit) != 0).count();
            assert_eq!(others, 0, "bit {bit}: other stencil bits set");
        }
    });
}

#[test]
fn without_a_stencil_bit_the_engines_stencil_is_left_as_it_was() {
    gpu_test(|ctx| {
        // One renderer fills the stencil (bit 3 on its terrain); a second,
        // told to write none, draws another view into the same targets.
        let mut writer = rig(ctx, DepthOptions { terrain_stencil_bit: Some(3), ..DepthOptions::default() });
        writer.shot(ctx, &toward_hole(), CullStages::ALL);
        let before = ctx.read_stencil(&writer.off.depth).unwrap();
        assert!(before.iter().any(|&s| s != 0) && before.contains(&0), "a stencil with both values");
        let options = RendererOptions {
            depth: DepthOptions { terrain_stencil_bit: None, ..DepthOptions::default() },
            ..RendererOptions::default()
        };
        let source = Arc::new(Surface::Hills);
        let mut keeper = TerrainRenderer::new(ctx, &world(), source, holes(), &options).unwrap();
        let other = view([300.0, 300.0, 600.0], 45.0, -20.0, SIZE, 1.0);
        let s = writer.off.settle(ctx, &mut keeper, &other, std::time::Duration::from_secs(300)).unwrap();
        assert!(s.settled);
        let c = writer.off.capture(ctx).unwrap();
        let after = ctx.read_stencil(&writer.off.depth).unwrap();
        assert!(c.depth.iter().any(|&d| d > 0.0), "the second renderer drew terrain");
        assert!(after == before, "the stencil changed though no bit was asked for");
    });
}

#[test]
fn a_depth_format_or_bit_vista_cannot_use_is_refused_before_anything_is_built() {
    gpu_test(|ctx| {
        let cases = [
            (
                DepthOptions { format: vk::Format::D32_SFLOAT, terrain_stencil_bit: Some(0), load: false },
                "has no stencil",
            ),
            (
                DepthOptions { format: vk::Format::D24_UNORM_S8_UINT, terrain_stencil_bit: Some(0), load: false },
                "D32_SFLOAT",
            ),
            (DepthOptions { terrain_stencil_bit: Some(8), ..DepthOptions::default() }, "0-7"),
        ];
        for (depth, says) in cases {
            let before = ctx.live_objects();
            let options = RendererOptions { depth, ..RendererOptions::default() };
            let made = TerrainRenderer::new(ctx, &world(), Arc::new(Surface::Hills), vec![], &options);
            match made {
                Err(Error::BadInput(m)) => assert!(m.contains(says), "{depth:?}: {m}"),
                Err(e) => panic!("{depth:?}: not bad input: {e}"),
                Ok(_) => panic!("{depth:?}: accepted"),
            }
            assert_eq!(ctx.live_objects(), before, "{depth:?}: objects made before the refusal");
        }
    });
}

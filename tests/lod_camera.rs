//! `TerrainRenderer::lod_camera`: one camera's LOD drawn from another's
//! view (what `vista bench accuracy --fly` measures popping with), under
//! the validation layer, with both LOD rules:
//! - the view's own camera as the LOD camera draws the very same picture;
//! - a LOD camera 300 m higher streams and draws a coarser surface (fewer
//!   triangles) that the view still sees whole, and the popping metric sees
//!   it move (and sees nothing move between identical frames).

mod common;

use common::gpu_test;
use common::terrain::{view, Rig};
use std::sync::Arc;
use vista::bench::accuracy_popping::jumps_px;
use vista::passes::cull_patches::CullStages;
use vista::reference::FinestSurface;
use vista::render::stats::collect;
use vista::render::{Camera, LodOptions, LodRule, RendererOptions};
use vista::world::{HeightSource, ProceduralSource, WorldDesc};

fn world() -> (WorldDesc, Arc<dyn HeightSource>) {
    let world = WorldDesc {
        extent_m: [1024.0, 1024.0],
        height_range_m: [0.0, 400.0],
        spacing_m: 1.0,
        lod_count: 4,
        ..WorldDesc::default()
    };
    (world, Arc::new(ProceduralSource::new(7, world.extent_m, world.height_range_m).unwrap()))
}

fn terrain_pixels(c: &vista::render::offscreen::Capture) -> usize {
    c.depth.iter().filter(|d| **d > 0.0).count()
}

#[test]
fn the_lod_follows_the_lod_camera_and_the_picture_follows_the_view() {
    gpu_test(|ctx| {
        let (w, source) = world();
        for rule in [LodRule::Patch, LodRule::Triangle] {
            let options =
                RendererOptions { lod: LodOptions { rule, ..LodOptions::default() }, ..RendererOptions::default() };
            let mut rig = Rig::with_source(ctx, w, source.clone(), vec![], [128, 96], false, options);
            let ground = f64::from(source.sample(512.0, 200.0));
            let v = view([512.0, 200.0, ground + 40.0], 0.0, -25.0, [128, 96], 1.0);
            let plain = rig.shot(ctx, &v, CullStages::NONE);
            let drawn = collect(ctx, &rig.renderer, &v).unwrap().triangles_drawn;
            rig.renderer.lod_camera = Some(v.camera);
            let same = rig.shot(ctx, &v, CullStages::NONE);
            assert!(plain.rgba == same.rgba && plain.depth == same.depth, "{rule:?}: the view's own LOD differs");
            let finest = FinestSurface::new(&w, &*source);
            let still = jumps_px(&plain, &same, &v, &w, &finest);
            assert!(!still.is_empty() && still.iter().all(|j| *j == 0.0), "{rule:?}: jumps between identical frames");

            let [x, y, z] = v.camera.position_m;
            rig.renderer.lod_camera = Some(Camera { position_m: [x, y, z + 300.0], ..v.camera });
            let coarse = rig.shot(ctx, &v, CullStages::NONE);
            let coarse_drawn = collect(ctx, &rig.renderer, &v).unwrap().triangles_drawn;
            eprintln!("{rule:?}: {drawn} triangles for the view, {coarse_drawn} for the camera 300 m higher");
            assert!(coarse_drawn < drawn, "{rule:?}: the higher camera's LOD is not coarser");
            // Drawn from the view: the ground fills the same part of it.
            let (a, b) = (terrain_pixels(&plain) as f64, terrain_pixels(&coarse) as f64);
            assert!((a - b).abs() <= 0.02 * a, "{rule:?}: {a} terrain pixels against {b}");
            let jumps = jumps_px(&plain, &coarse, &v, &w, &finest);
            let largest = jumps.iter().copied().fold(0.0, f64::max);
            let moved = jumps.iter().filter(|j| **j > 0.01).count();
            eprintln!("{rule:?}: largest jump {largest} px, {moved} of {} pixels moved", jumps.len());
            assert!(largest > 0.25 && moved * 10 > jumps.len(), "{rule:?}: the coarser surface hardly moved");
            rig.renderer.lod_camera = None;
        }
    });
}

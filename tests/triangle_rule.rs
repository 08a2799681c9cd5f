//! The per-triangle LOD rule through the renderer (`emit_triangles`,
//! `terrain_triangles`): watertight over rough ground seen steeply from
//! 40 random viewpoints (every pixel terrain: a T-junction would show the
//! background), the same picture with the frustum culling off, with no
//! vertex clamped once streaming settled, with holes
//! cut where the scene cuts them and nowhere else, and with fewer triangles
//! than the per-patch rule draws for the same views.

mod common;

use common::gpu_test;
use common::terrain::{view, Rig, MAGENTA_RGBA};
use std::sync::Arc;
use vista::passes::cull_patches::CullStages;
use vista::render::{LodOptions, LodRule, RendererOptions};
use vista::world::{GridSource, HeightSource, Hole, WorldDesc};

/// 1 km at 1 m samples, 4 LODs, from a 129 x 129 grid of posts with
/// hashed heights (steep random relief at every scale the LODs see).
fn rough() -> (WorldDesc, Arc<dyn HeightSource>) {
    let n = 129usize;
    let heights: Vec<f32> = (0..n * n)
        .map(|i| {
            let (x, y) = ((i % n) as f32, (i / n) as f32);
            let h = ((i as u64).wrapping_mul(2654435761) % 1000) as f32 / 1000.0;
            180.0 + 40.0 * (x / 9.0).sin() * (y / 13.0).cos() + 25.0 * h
        })
        .collect();
    let world = WorldDesc {
        extent_m: [1024.0, 1024.0],
        height_range_m: [100.0, 300.0],
        spacing_m: 1.0,
        lod_count: 4,
        ..WorldDesc::default()
    };
    (world, Arc::new(GridSource::new(n, n, heights, [1024.0, 1024.0])))
}

struct Rng(u64);
impl Rng {
    fn unit(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn rig(ctx: &vista::gpu::Context, rule: LodRule, holes: Vec<Hole>, size: [u32; 2]) -> Rig {
    let (world, source) = rough();
    let options = RendererOptions { lod: LodOptions { rule, ..LodOptions::default() }, ..RendererOptions::default() };
    Rig::with_source(ctx, world, source, holes, size, false, options)
}

#[test]
fn the_cut_is_watertight_from_40_steep_views_and_draws_fewer_triangles_than_the_patches() {
    gpu_test(|ctx| {
        let size = [96, 96];
        let (_, source) = rough();
        let mut tri = rig(ctx, LodRule::Triangle, vec![], size);
        let mut patch = rig(ctx, LodRule::Patch, vec![], size);
        let mut rng = Rng(2718);
        let (mut background, mut clamped, mut drawn) = (0, 0, [0u64; 2]);
        for _ in 0..40 {
            let (x, y) = (300.0 + 424.0 * rng.unit(), 300.0 + 424.0 * rng.unit());
            let z = f64::from(source.sample(x, y)) + 8.0 + 70.0 * rng.unit();
            // The frustum's top edge at least 30 degrees below the horizon:
            // the ground it reaches lies inside the world.
            let v = view([x, y, z], 360.0 * rng.unit(), -60.0 - 30.0 * rng.unit(), size, 0.5 + 3.5 * rng.unit() as f32);
            let c = tri.shot(ctx, &v, CullStages::ALL);
            background += c.rgba.chunks_exact(4).filter(|p| *p == MAGENTA_RGBA).count();
            let h = tri.renderer.triangles.as_ref().expect("built").emit.read_header(ctx).unwrap();
            clamped += h.clamped;
            assert_eq!(h.overflow, 0);
            drawn[0] += u64::from(h.drawn());
            // Frustum culling drops only what cannot be seen.
            let unculled = tri.shot(ctx, &v, CullStages::NONE);
            assert!(c.rgba == unculled.rgba && c.depth == unculled.depth, "culling changed the picture");
            patch.shot(ctx, &v, CullStages::ALL);
            drawn[1] += vista::render::stats::collect(ctx, &patch.renderer, &v).unwrap().triangles_drawn;
        }
        eprintln!("triangles drawn over 40 views: per triangle {}, per patch {}", drawn[0], drawn[1]);
        assert_eq!(background, 0, "background shows through the per-triangle cut: cracks");
        assert_eq!(clamped, 0, "settled, every vertex the rule splits is in the nodes drawn");
        assert!(drawn[0] < drawn[1], "per triangle {} not below per patch {}", drawn[0], drawn[1]);
    });
}

#[test]
fn holes_are_cut_where_the_scene_cuts_them_and_nowhere_else() {
    gpu_test(|ctx| {
        let size = [128, 128];
        let (_, source) = rough();
        let hole = Hole::Circle { center_m: [512.0, 512.0], radius_m: 20.0 };
        let mut tri = rig(ctx, LodRule::Triangle, vec![hole], size);
        // Straight down from 150 m above the hole: the 60-degree frustum
        // spans about 173 m, the hole 40 m across (about 30 pixels).
        let z = f64::from(source.sample(512.0, 512.0)) + 150.0;
        let v = view([512.0, 512.0, z], 0.0, -89.9, size, 1.0);
        let c = tri.shot(ctx, &v, CullStages::ALL);
        let at = |x: usize, y: usize| c.rgba[(y * size[0] as usize + x) * 4..][..4] == MAGENTA_RGBA;
        let background = (0..size[1] as usize).flat_map(|y| (0..size[0] as usize).map(move |x| (x, y)));
        let (mut inside, mut outside) = (0usize, 0usize);
        for (x, y) in background.filter(|(x, y)| at(*x, *y)) {
            // Pixel distance from the image centre, in hole radii (the hole
            // is ~ 15 px in radius; a sample's triangles fade at its rim).
            let r = ((x as f64 - 63.5).hypot(y as f64 - 63.5)) / 14.8;
            if r < 1.25 {
                inside += 1;
            } else {
                outside += 1;
            }
        }
        eprintln!("background pixels: {inside} within the hole, {outside} elsewhere");
        assert_eq!(outside, 0, "background outside the hole");
        // pi 14.8^2 = 688 pixels, less the rim the hole vertices' triangles take.
        assert!(inside > 400, "the hole is not cut ({inside} pixels)");
    });
}

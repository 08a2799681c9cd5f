//! Trees cast into the terrain's sun shadows (effects `vegetation` and
//! `shadows`, sun_shadows.comp's CANOPY variant) under the validation
//! layer: the shadow texture the GPU marches over the ground and the
//! canopy equals its CPU twin (src/reference/sun_shadow.rs reading the
//! canopy by its own bilinear), and on a plane, where nothing else casts,
//! the shadow lies where the crowns' cones put it.

mod common;

use common::gpu_test;
use common::terrain::{view, Rig, Surface};
use glam::{DVec2, DVec3};
use std::sync::Arc;
use vista::effects::shadows::frame::Shadows;
use vista::effects::shadows::sun_shadows::ShadowParams;
use vista::effects::vegetation::canopy::CanopyGrid;
use vista::gpu::Context;
use vista::passes::cull_patches::CullStages;
use vista::reference::sun_shadow::{texel_position, March, NONE};
use vista::render::{Effect, Effects, RendererOptions};
use vista::world::{NodeId, WorldDesc};

const SIZE: [u32; 2] = [128, 128];
const GROUND: f64 = 100.0;
/// A plane at GROUND with a small cone in the node's south-east corner: a
/// plane alone needs no LOD 0, and its shadow falls off the stand's.
const SURFACE: Surface = Surface::Bump { z0: GROUND, c: [112.0, 12.0], r: 10.0, h: 8.0 };
const ELEVATION: f64 = 25.0;
/// The shadows fall towards azimuth 55 degrees, along no grid axis.
const AZIMUTH: f64 = 235.0;
/// A scale-1 tree's height (the test's, not the default).
const TREE_M: f32 = 12.0;

fn world() -> WorldDesc {
    common::terrain::shadow_world()
}

fn params() -> ShadowParams {
    // 1 m texels on LOD-0 nodes; the march samples a crown every 2 (last -
    // first) / 256 m at most (under a metre here).
    ShadowParams { resolution: 129, steps: 256, softness_deg: 0.0, reach_m: 120.0, ..ShadowParams::default() }
}

/// A stand of 3 x 3 trees 14 m apart and two bushes, all inside LOD-0
/// node (0, 0, 0) with room down-sun for their shadows.
fn stand() -> (Vec<[f32; 3]>, Vec<[f32; 3]>) {
    let z = GROUND as f32;
    let trees = (0..9).map(|k| [30.0 + 14.0 * (k % 3) as f32, 28.0 + 14.0 * (k / 3) as f32, z]).collect();
    (trees, vec![[80.0, 30.0, z], [84.0, 40.0, z]])
}

fn options(dir: &std::path::Path) -> RendererOptions {
    let (trees, bushes) = stand();
    let mut fx = Effects::default().with(Effect::Shadows, true).with(Effect::Vegetation, true);
    fx.lighting.sun_azimuth_deg = AZIMUTH;
    fx.lighting.sun_elevation_deg = ELEVATION;
    fx.shadows = params();
    fx.vegetation.set = Some(Arc::new(common::occurrence::forest(dir, &trees, &bushes)));
    fx.vegetation.folder = Some(dir.to_path_buf());
    fx.vegetation.tree_height_m = TREE_M;
    fx.vegetation.canopy_cell_m = 1.0;
    RendererOptions { effects: fx, ..RendererOptions::default() }
}

/// The canopy read by the test's own bilinear between cell centres (none
/// off the grid).
fn canopy_at(g: &CanopyGrid, p: DVec2) -> f64 {
    let c = (p - DVec2::new(f64::from(g.origin_m[0]), f64::from(g.origin_m[1]))) / f64::from(g.cell_m) - 0.5;
    let (f, w) = (c.floor(), c - c.floor());
    let cell = |dx: f64, dy: f64| {
        let (x, y) = (f.x + dx, f.y + dy);
        let inside = x >= 0.0 && y >= 0.0 && x < f64::from(g.size[0]) && y < f64::from(g.size[1]);
        // The GPU reads f16 heights.
        let h = if inside { g.heights[(y as u32 * g.size[0] + x as u32) as usize] } else { 0.0 };
        f64::from(half::f16::from_f32(h).to_f32())
    };
    let south = cell(0.0, 0.0) * (1.0 - w.x) + cell(1.0, 0.0) * w.x;
    let north = cell(0.0, 1.0) * (1.0 - w.x) + cell(1.0, 1.0) * w.x;
    south * (1.0 - w.y) + north * w.y
}

/// Whether plane point `q` lies in a crown's exact shadow: the union over
/// heights s of the cone's cross-section there (radius 0.3 h at 0.2 h,
/// nothing at h) moved away from the sun by s / tan(elevation).
fn in_exact_shadow(q: DVec2, trees: &[(DVec2, f64)], away: DVec2, rise: f64) -> bool {
    trees.iter().any(|&(c, h)| {
        (0..=400).any(|i| {
            let s = 0.2 + 0.8 * f64::from(i) / 400.0;
            (q - (c + away * (s * h / rise))).length() <= 0.3 * h * (1.0 - s) / 0.8
        })
    })
}

fn lod0_height(p: DVec2) -> Option<f64> {
    common::terrain::shadow_world_height(SURFACE, p)
}

fn read_layer(ctx: &Context, rig: &Rig, node: NodeId) -> Vec<[f32; 2]> {
    let slot = rig.renderer.terrain.tree.shadow.slot_of(node).expect("resident");
    let bytes = ctx.read_image(&rig.renderer.effect::<Shadows>().expect("built").pass.atlas, 0, slot, 8).unwrap();
    bytemuck::cast_slice::<u8, [f32; 2]>(&bytes).to_vec()
}

#[test]
fn trees_cast_into_the_terrain_shadows_as_their_twin_and_their_cones_say() {
    gpu_test(|ctx| {
        let dir = common::occurrence::unique_dir("vista-vegetation-shadows");
        let options = options(&dir);
        let set = options.effects.vegetation.set.clone().unwrap();
        let grid = CanopyGrid::raster(&set, &options.effects.vegetation.types_gpu(&set), 1.0).unwrap();
        let mut rig = Rig::with_options(ctx, world(), SURFACE, vec![], SIZE, false, options);
        rig.shot(ctx, &view([14.0, 39.0, 200.0], 55.0, -50.0, SIZE, 0.25), CullStages::ALL);
        let sun: DVec3 = rig.renderer.effects.lighting.sun_dir();
        let p = params();
        let march = March::new(sun, p.steps, f64::from(p.reach_m), f64::from(world().height_range_m[1] + grid.top_m));
        let ground = lod0_height;
        // The canopy counts from a cell and a half out (canopy_skip_m).
        let occluder = |q: DVec2, d: f64| ground(q).map(|g| g + if d >= 1.5 { canopy_at(&grid, q) } else { 0.0 });
        let trees: Vec<(DVec2, f64)> = set.instances[..9]
            .iter()
            .map(|i| (DVec2::new(f64::from(i.position[0]), f64::from(i.position[1])), f64::from(TREE_M * i.scale)))
            .collect();
        let node = NodeId::new(0, 0, 0);
        let resident = rig.renderer.terrain.resident_nodes();
        assert!(resident.contains(&node), "the stand's node is resident at LOD 0: {resident:?}");
        let gpu = read_layer(ctx, &rig, node);
        let (mut worst, mut dark, mut exact, mut off_edge) = (0f64, 0, 0, Vec::new());
        for (k, [h, _]) in gpu.iter().enumerate() {
            let t = [k as u32 % p.resolution, k as u32 / p.resolution];
            let q = texel_position(&world(), node, p.resolution, t);
            let (h_cpu, _) = march.threshold_over(q, 1.0, &ground, &occluder);
            if h_cpu == NONE {
                assert_eq!(*h, NONE as f32, "texel {t:?}: nothing occludes");
                continue;
            }
            worst = worst.max((f64::from(*h) - h_cpu).abs());
            // The plane off the crowns (a texel and a canopy cell clear) and
            // off the bushes, the ground's cone and their shadows (the twin
            // has them, the crowns do not).
            let bush = |b: &[f32; 3]| (q - DVec2::new(f64::from(b[0]), f64::from(b[1]))).length() < 8.0;
            let cone = (q - DVec2::new(112.0, 12.0)).length() < 40.0;
            if trees.iter().any(|(c, h)| (q - *c).length() < 0.3 * h + 2.0) || stand().1.iter().any(bush) || cone {
                continue;
            }
            let (gpu_dark, exact_dark) = (*h > 0.0, in_exact_shadow(q, &trees, -march.dir, march.rise));
            dark += usize::from(gpu_dark);
            exact += usize::from(exact_dark);
            // Within a texel and a canopy cell (whose height is its
            // highest point's) of the exact edge.
            let near = (0..16).any(|i| {
                let a = f64::from(i) * std::f64::consts::TAU / 16.0;
                in_exact_shadow(q + DVec2::new(a.cos(), a.sin()) * 2.0, &trees, -march.dir, march.rise) == gpu_dark
            });
            if gpu_dark != exact_dark && !near {
                off_edge.push(t);
            }
        }
        println!("{dark} plane texels in the trees' shadow on the GPU, {exact} exactly; worst {worst} m from the twin");
        // f16 heights (under 4 mm at 16 m) and f32 positions against f64.
        assert!(worst < 0.02, "GPU threshold {worst} m from the CPU twin");
        assert!(exact >= 200, "only {exact} plane texels in the exact shadow");
        assert!(
            off_edge.is_empty(),
            "{} texels off the exact edge: {:?}",
            off_edge.len(),
            &off_edge[..off_edge.len().min(8)]
        );
        let _ = std::fs::remove_dir_all(&dir);
    });
}

//! Effect `grass`: the GPU places exactly the tufts its CPU twin places
//! (same cells, points, materials, rotations), a camera moving less than a
//! cell leaves every tuft that stays in range where it was, every tuft
//! stands on the terrain within the height samples' quantisation, none
//! grows on a material without grass or in a hole, and off nothing of it
//! is built and the image is the one without it.

mod common;

use common::gpu_test;
use common::terrain::{small_world as world, view, Rig, Surface};
use std::collections::BTreeMap;
use vista::effects::grass::gpu::GrassInstanceGpu;
use vista::effects::grass::GrassParams;
use vista::gpu::Context;
use vista::passes::cull_patches::CullStages;
use vista::passes::terrain_query::{TerrainQuery, VistaTerrain};
use vista::reference::grass::{place_cpu, Ground, TuftCpu};
use vista::render::{Effect, Effects, RendererOptions, View};
use vista::scene::view::TerrainViewGpu;
use vista::shaders::consts::GBUFFER_GRASS;
use vista::terrain::quadtree::{EMPTY, INVALID};
use vista::world::Hole;

const SIZE: [u32; 2] = [256, 192];
/// A hole in the meadow in front of the camera.
const HOLE: ([f64; 2], f64) = ([512.0, 222.0], 6.0);
/// A meadow (grass) with a 51-degree cone (rock) in view.
const GROUND: Surface = Surface::Bump { z0: 300.0, c: [497.0, 226.0], r: 8.0, h: 10.0 };

fn effects(grass: bool) -> Effects {
    let mut fx = Effects::default().with(Effect::Splat, true).with(Effect::Grass, grass).with(Effect::Lighting, false);
    // A smaller square keeps the CPU twin's queries few.
    fx.grass = GrassParams { radius_m: 30.0, fade_m: 6.0, ..GrassParams::default() };
    fx
}

fn rig(ctx: &Context, fx: Effects) -> Rig {
    let holes = vec![Hole::Circle { center_m: HOLE.0, radius_m: HOLE.1 }];
    let options = RendererOptions { effects: fx, ..RendererOptions::default() };
    Rig::with_options(ctx, world(), GROUND, holes, SIZE, false, options)
}

/// 2 m above the meadow, looking at the cone and the hole.
fn low(dx: f64, dy: f64) -> View {
    let (x, y) = (505.0 + dx, 200.0 + dy);
    view([x, y, GROUND.height(505.0, 200.0) + 2.0], 15.0, -12.0, SIZE, 1.0)
}

/// The camera as the GPU saw it (the f32 the placement reads).
fn camera(ctx: &Context, rig: &Rig) -> [f32; 3] {
    let bytes = ctx.read_buffer(rig.renderer.view_buffer()).unwrap();
    let v: TerrainViewGpu = bytemuck::pod_read_unaligned(&bytes[..std::mem::size_of::<TerrainViewGpu>()]);
    [v.camera_world[0], v.camera_world[1], v.camera_world[2]]
}

fn tufts(ctx: &Context, rig: &Rig) -> BTreeMap<[i32; 2], GrassInstanceGpu> {
    let grass = rig.renderer.effect::<vista::effects::grass::gpu::Grass>().expect("grass is built");
    grass.read_instances(ctx).unwrap().into_iter().map(|t| (t.cell, t)).collect()
}

/// Material and height at `points` through terrain_query (tested against
/// the CPU in traverse_gpu.rs), with the renderer's resident terrain.
fn query(ctx: &Context, rig: &Rig, points: &[[f32; 2]]) -> Vec<Option<(u32, f32)>> {
    let r = &rig.renderer;
    let mut q = TerrainQuery::new(ctx, points.len().max(1) as u32).unwrap();
    let terrain = VistaTerrain::new(&rig.world, &r.sector_data);
    ctx.submit_and_wait(|rec| q.record(rec, terrain, &r.terrain.tree, &r.sector_data, points)).unwrap();
    q.answers(points.len()).into_iter().map(|a| a.map(|a| (a.material, a.height_m))).collect()
}

/// The LOD of the finest resident node covering `p` (what
/// terrain_sample.glsl reads): its samples lie 2^lod m apart.
fn finest_lod(rig: &Rig, p: [f32; 2]) -> u8 {
    let shadow = &rig.renderer.terrain.tree.shadow;
    let sector = rig.world.sector_size_m();
    let s = p.map(|v| (f64::from(v) / sector).floor() as u32);
    (0..rig.world.lod_count as u8)
        .find(|&k| ![EMPTY, INVALID].contains(&shadow.texel(k, s[0] >> k, s[1] >> k)))
        .expect("a resident node covers every tuft")
}

fn in_hole(p: [f32; 2], margin: f64) -> bool {
    let d = (f64::from(p[0]) - HOLE.0[0]).hypot(f64::from(p[1]) - HOLE.0[1]);
    d < HOLE.1 + margin
}

/// Within half a sample diagonal of the hole's edge (the samples of the
/// finest resident node there) the nearest sample may fall either side.
fn near_hole_edge(rig: &Rig, p: [f32; 2]) -> bool {
    let margin = 0.71 * f64::from(1u32 << finest_lod(rig, p));
    in_hole(p, margin) && !in_hole(p, -margin)
}

#[test]
fn gpu_placement_equals_the_cpu_twin_and_stays_put() {
    gpu_test(|ctx| {
        let mut rig = rig(ctx, effects(true));
        rig.renderer.effect_mut::<vista::effects::grass::gpu::Grass>().unwrap().no_culling = true;
        rig.shot(ctx, &low(0.0, 0.0), CullStages::default());
        let gpu = tufts(ctx, &rig);
        let cam = camera(ctx, &rig);
        let params = rig.renderer.effect::<vista::effects::grass::gpu::Grass>().unwrap().params.clone();

        let ground = candidate_ground(ctx, &rig, &params, cam);
        let cpu: Vec<TuftCpu> =
            place_cpu(&params, [cam[0], cam[1]], true, |p| ground.get(&p.map(f32::to_bits)).copied());
        let without_holes = place_cpu(&params, [cam[0], cam[1]], false, |p| ground.get(&p.map(f32::to_bits)).copied());
        let (compared, skipped) = compare_with_the_twin(&rig, &gpu, &cpu, &without_holes);
        // Each rule mattered: a meadow of tufts, some removed by the hole,
        // and candidate cells on the cone's rock, which grows nothing.
        let in_the_hole = without_holes.iter().filter(|t| in_hole(t.xy, -1.0)).count();
        let on_rock = ground.values().filter(|g| g.material == vista::world::Material::Rock as u32).count();
        println!(
            "compared {compared} tufts ({skipped} at the radius or the hole's edge), {in_the_hole} cut by the hole, \
             {on_rock} candidate cells on rock"
        );
        assert!(compared > 1500 && in_the_hole > 20 && on_rock > 50, "{compared}, {in_the_hole}, {on_rock}");
        tufts_stay_put(ctx, &mut rig, gpu, cam, &params);
    });
}

/// Every candidate cell's ground, through the validated query include.
fn candidate_ground(ctx: &Context, rig: &Rig, params: &GrassParams, cam: [f32; 3]) -> BTreeMap<[u32; 2], Ground> {
    let all = place_cpu(params, [cam[0], cam[1]], false, |_| Some(Ground { material: 0, hole: false }));
    let points: Vec<[f32; 2]> = all.iter().map(|t| t.xy).collect();
    let answers = query(ctx, rig, &points);
    points
        .iter()
        .zip(&answers)
        .filter_map(|(p, a)| {
            let (material, _) = (*a)?;
            Some((p.map(f32::to_bits), Ground { material, hole: in_hole(*p, 0.0) }))
        })
        .collect()
}

/// The GPU's tufts are the twin's (but at the radius or the hole's edge,
/// where either may place one); (compared, skipped).
fn compare_with_the_twin(
    rig: &Rig,
    gpu: &BTreeMap<[i32; 2], GrassInstanceGpu>,
    cpu: &[TuftCpu],
    without_holes: &[TuftCpu],
) -> (usize, usize) {
    let (mut compared, mut skipped) = (0, 0);
    for t in cpu {
        if t.borderline || near_hole_edge(rig, t.xy) {
            skipped += 1;
            continue;
        }
        let g = gpu.get(&t.cell).unwrap_or_else(|| panic!("cell {:?} at {:?}: the GPU placed nothing", t.cell, t.xy));
        assert_eq!([g.position[0], g.position[1]].map(f32::to_bits), t.xy.map(f32::to_bits), "cell {:?}", t.cell);
        assert_eq!(g.packed & 0xFF, t.material, "material of cell {:?}", t.cell);
        assert_eq!((g.packed >> 8) & 0xFF, t.rotation, "rotation of cell {:?}", t.cell);
        assert_eq!(g.packed >> 16, t.lean, "lean of cell {:?}", t.cell);
        compared += 1;
    }
    let cpu_cells: std::collections::BTreeSet<[i32; 2]> = cpu.iter().map(|t| t.cell).collect();
    for (cell, g) in gpu {
        let p = [g.position[0], g.position[1]];
        let edge = near_hole_edge(rig, p) || cpu.iter().any(|t| t.cell == *cell && t.borderline);
        assert!(
            cpu_cells.contains(cell) || edge || without_holes.iter().any(|t| t.cell == *cell && t.borderline),
            "the GPU placed cell {cell:?} at {p:?}, the twin did not"
        );
    }
    (compared, skipped)
}

/// Moving less than a cell: every tuft in range both times is where it was.
fn tufts_stay_put(
    ctx: &Context,
    rig: &mut Rig,
    before: BTreeMap<[i32; 2], GrassInstanceGpu>,
    cam: [f32; 3],
    params: &GrassParams,
) {
    let step = (0.2, 0.13);
    rig.again(ctx, &low(step.0, step.1), CullStages::default());
    let after = tufts(ctx, rig);
    let cam2 = camera(ctx, rig);
    assert_ne!(cam, cam2);
    let r = f64::from(params.radius_m) - 1e-3;
    let (mut kept, mut left) = (0, 0);
    for (cell, b) in &before {
        let d2 = f64::from(b.position[0] - cam2[0]).hypot(f64::from(b.position[1] - cam2[1]));
        if d2 >= r {
            left += 1;
            continue;
        }
        let a = after.get(cell).unwrap_or_else(|| panic!("cell {cell:?} still in range lost its tuft"));
        assert_eq!(a.position[..3], b.position[..3], "cell {cell:?} moved");
        assert_eq!(a.packed, b.packed);
        kept += 1;
    }
    println!("moving {step:?} m: {kept} tufts kept in place, {left} left the radius");
    assert!(kept > 1500 && left > 0);
}

/// Metres per R16 height step of the small world.
fn height_step() -> f64 {
    let [lo, hi] = world().height_range_m;
    f64::from(hi - lo) / 65535.0
}

/// The bilinear interpolation of the ground's samples `spacing` m apart,
/// each quantised to R16 as the bake stores it: the surface a node of
/// that LOD holds.
fn sampled_height(x: f64, y: f64, spacing: f64) -> f64 {
    let lo = f64::from(world().height_range_m[0]);
    let q =
        |i: f64, j: f64| lo + ((GROUND.height(i * spacing, j * spacing) - lo) / height_step()).round() * height_step();
    let (x, y) = (x / spacing, y / spacing);
    let (i, j) = (x.floor(), y.floor());
    let (fx, fy) = (x - i, y - j);
    let a = q(i, j) * (1.0 - fx) + q(i + 1.0, j) * fx;
    let b = q(i, j + 1.0) * (1.0 - fx) + q(i + 1.0, j + 1.0) * fx;
    a * (1.0 - fy) + b * fy
}

#[test]
fn tufts_stand_on_the_terrain_and_only_where_grass_grows() {
    gpu_test(|ctx| {
        let mut rig = rig(ctx, effects(true));
        let cap = rig.shot(ctx, &low(0.0, 0.0), CullStages::default());
        let gpu: Vec<GrassInstanceGpu> = tufts(ctx, &rig).into_values().collect();
        assert!(gpu.len() > 300, "{} tufts drawn", gpu.len());
        // Against the samples of the node the tuft's lookup reads (the
        // finest resident there), and against the true surface.
        let (mut worst, mut worst_true, mut lods) = (0.0f64, 0.0f64, [0usize; 4]);
        for t in &gpu {
            let p = [t.position[0], t.position[1]];
            let k = finest_lod(&rig, p);
            lods[k as usize] += 1;
            let (x, y) = (f64::from(p[0]), f64::from(p[1]));
            worst = worst.max((f64::from(t.position[2]) - sampled_height(x, y, f64::from(1u32 << k))).abs());
            worst_true = worst_true.max((f64::from(t.position[2]) - GROUND.height(x, y)).abs());
        }
        // The GPU filters the 16-bit samples bilinearly: one R16 step, plus
        // f32 rounding at 300 m.
        let bound = height_step() + 1e-4;
        println!(
            "{} tufts on nodes of LOD 0-3 {lods:?}: worst error {worst:.5} m against the node's samples (bound \
             {bound:.5} m), {worst_true:.3} m against the true surface",
            gpu.len()
        );
        assert!(worst <= bound, "{worst} > {bound}");

        // Every tuft's material grows grass; none stands in the hole.
        let points: Vec<[f32; 2]> = gpu.iter().map(|t| [t.position[0], t.position[1]]).collect();
        let answers = query(ctx, &rig, &points);
        let rules = rig.renderer.effect::<vista::effects::grass::gpu::Grass>().unwrap().params.rules;
        let mut by_material = [0usize; 5];
        for (p, a) in points.iter().zip(&answers) {
            let (m, _) = a.expect("a tuft where no terrain is found");
            assert!(rules[m as usize].density > 0.0, "a tuft at {p:?} on material {m}, which grows no grass");
            let inside = in_hole(*p, -0.71 * f64::from(1u32 << finest_lod(&rig, *p)));
            assert!(!inside, "a tuft at {p:?} in the hole");
            by_material[m as usize] += 1;
        }
        println!("tufts by material (grass, rock, snow, scree, sand): {by_material:?}");

        // Drawn into the G-buffer: grass pixels, marked as such.
        let gb = rig.renderer.gbuffer.as_ref().unwrap().capture(ctx).unwrap();
        let marked = gb.material.iter().filter(|m| m[1] == GBUFFER_GRASS as u8).count();
        println!("{marked} grass pixels of {}", cap.depth.len());
        assert!(marked > 500, "{marked} grass pixels");
    });
}

#[test]
fn off_nothing_is_built_and_the_image_is_the_one_without_it() {
    gpu_test(|ctx| {
        let mut plain = rig(ctx, effects(false));
        // Requested but switched off by the scene: splat off means no material ids.
        let mut fx = effects(true).with(Effect::Splat, false);
        let mut refused = rig(ctx, fx.clone());
        let decision = refused.renderer.effects().iter().find(|d| d.effect == Effect::Grass).unwrap().clone();
        assert!(!decision.on && decision.reason.contains("splat is off"), "{}", decision.reason);
        fx.set(Effect::Splat, true);
        let mut on = rig(ctx, fx);
        for r in [&plain, &refused] {
            assert!(r.renderer.effect::<vista::effects::grass::gpu::Grass>().is_none());
            assert!(!r.renderer.pipelines().iter().any(|p| p.contains("grass")), "{:?}", r.renderer.pipelines());
            assert!(!r.renderer.memory().iter().any(|(_, _, e)| e.contains(&Effect::Grass)));
        }
        let a = plain.shot(ctx, &low(0.0, 0.0), CullStages::default());
        let b = on.shot(ctx, &low(0.0, 0.0), CullStages::default());
        let log = plain.renderer.last_frame_log().unwrap();
        assert!(!log.entries.iter().any(|(p, _)| format!("{p:?}").contains("Grass")));
        let differs = a.rgba.chunks(4).zip(b.rgba.chunks(4)).filter(|(x, y)| x != y).count();
        assert!(differs > 500, "grass changed {differs} pixels");
        // Splat off in both: the image without grass is the same.
        let mut no_splat = rig(ctx, effects(false).with(Effect::Splat, false));
        let c = refused.shot(ctx, &low(0.0, 0.0), CullStages::default());
        let d = no_splat.shot(ctx, &low(0.0, 0.0), CullStages::default());
        assert!(c.rgba == d.rgba && c.depth == d.depth, "grass refused changed the image");
    });
}

/// A decal covers the ground it is drawn on: an opaque quad clears the
/// grass under it (effect decals thins each cell's probability by the
/// coverage there), and the pigment map takes the decal's colour.
#[test]
fn no_grass_grows_under_an_opaque_decal() {
    use vista::effects::virtual_texture::decals::{Decal, DecalSet, DecalShape, DecalTexture};
    gpu_test(|ctx| {
        let n = vista::shaders::consts::DECAL_TEXELS;
        let texture =
            DecalTexture::from_rgba("solid", &image::RgbaImage::from_pixel(n, n, image::Rgba([200, 40, 40, 255])));
        let (center, size) = ([500.0, 214.0], [12.0, 6.0]);
        let quad = Decal {
            shape: DecalShape::Quad { center_m: center.into(), size_m: size.into(), rotation_deg: 0.0 },
            texture: 0,
            opacity: 1.0,
            roughness: None,
            displace_m: None,
        };
        let mut fx = effects(true).with(Effect::VirtualTexture, true).with(Effect::Decals, true);
        fx.virtual_texture.cache_mb = 16;
        fx.virtual_texture.indirection = 512;
        let decals = DecalSet { textures: vec![texture].into(), decals: vec![quad] };
        let holes = vec![Hole::Circle { center_m: HOLE.0, radius_m: HOLE.1 }];
        let options = RendererOptions { effects: fx, decals, ..RendererOptions::default() };
        let mut rig = Rig::with_options(ctx, world(), GROUND, holes, SIZE, false, options);
        assert!(rig.renderer.effect_on(Effect::Decals));
        rig.renderer.effect_mut::<vista::effects::grass::gpu::Grass>().unwrap().no_culling = true;
        rig.shot(ctx, &low(0.0, 0.0), CullStages::default());
        let inside = |t: &GrassInstanceGpu, margin: f64| {
            let d = [0, 1].map(|i| (f64::from(t.position[i]) - center[i]).abs() - size[i] / 2.0);
            d[0] < margin && d[1] < margin
        };
        let gpu: Vec<GrassInstanceGpu> = tufts(ctx, &rig).into_values().collect();
        // The coverage ramps over one cell at the edge.
        let under = gpu.iter().filter(|t| inside(t, -0.5)).count();
        let around = gpu.iter().filter(|t| inside(t, 3.0) && !inside(t, 0.5)).count();
        println!("{under} tufts under the decal, {around} within 3 m around it");
        assert!(under == 0 && around > 50, "{under} under, {around} around");
        // The pigment map's texel at the decal's centre is its colour
        // (stored as the square root of linear albedo).
        let grass = rig.renderer.effect::<vista::effects::grass::gpu::Grass>().unwrap();
        let (texel, cam) = (grass.pigment_texel_m(), camera(ctx, &rig));
        let origin = grass.pigment_origin([cam[0], cam[1]]);
        // Independently: the map covers the grass around the camera.
        let side = texel * vista::shaders::consts::GRASS_PIGMENT_TEXELS as f32;
        let r = grass.params.radius_m;
        assert!((0..2).all(|i| origin[i] <= cam[i] - r && origin[i] + side >= cam[i] + r), "{origin:?} {cam:?}");
        let at = [0, 1].map(|i| ((center[i] as f32 - origin[i]) / texel).floor() as usize);
        let bytes = ctx.read_image(grass.pigment(), 0, 0, 4).unwrap();
        let side = vista::shaders::consts::GRASS_PIGMENT_TEXELS as usize;
        let px = &bytes[(at[1] * side + at[0]) * 4..][..3];
        let lin = |c: f64| ((c / 255.0 + 0.055) / 1.055).powf(2.4);
        let want = [200.0, 40.0, 40.0].map(|c| 255.0 * lin(c).sqrt());
        for (got, want) in px.iter().zip(want) {
            // 8-bit storage and the texture's 8-bit mips.
            assert!((f64::from(*got) - want).abs() <= 2.0, "pigment {px:?}, the decal's {want:?}");
        }
    });
}

/// Seed 004's occurrence maps: with a vegetation folder (a 10 m
/// checkerboard, the brushes' density 0.5 on grass), no tuft stands in a
/// cell whose bit is off, the cells skipped are counted, and the placement
/// is still its CPU twin's (densities times the brushes').
#[test]
fn grass_grows_only_where_the_occurrence_map_lets_it() {
    gpu_test(|ctx| {
        let dir = common::occurrence::unique_dir("vista-grass-occurrence");
        let mut fx = effects(true);
        fx.grass.occurrence =
            Some(common::occurrence::checkerboard(&dir, world().extent_m, 10.0, [0.5, 0.0, 0.0, 1.0, 0.0]));
        let mut rig = rig(ctx, fx);
        let grass = rig.renderer.effect_mut::<vista::effects::grass::gpu::Grass>().unwrap();
        grass.no_culling = true;
        rig.shot(ctx, &low(0.0, 0.0), CullStages::default());
        let grass = rig.renderer.effect::<vista::effects::grass::gpu::Grass>().unwrap();
        let header: vista::effects::grass::gpu::GrassHeaderGpu = bytemuck::pod_read_unaligned(
            &ctx.read_buffer(grass.header()).unwrap()[..vista::effects::grass::gpu::GrassHeaderGpu::BYTES as usize],
        );
        let params = grass.params.clone();
        let occurrence = params.occurrence.as_ref().unwrap();
        let gpu = tufts(ctx, &rig);
        assert!(gpu.values().all(|t| occurrence.bit([t.position[0], t.position[1]])), "a tuft in a cell that is off");
        let cam = camera(ctx, &rig);
        // The cells in range whose bit is off, counted as the twin walks them.
        let grid = params.grid([cam[0], cam[1]]);
        let (mut off, mut borderline) = (0u32, 0u32);
        for y in 0..grid.side as i32 {
            for x in 0..grid.side as i32 {
                let p = vista::reference::grass::cell_point(
                    [grid.cell0[0] + x, grid.cell0[1] + y],
                    params.cell_m,
                    params.seed,
                );
                let d = f64::from(p[0] - cam[0]).hypot(f64::from(p[1] - cam[1]));
                if (d - f64::from(params.radius_m)).abs() < 1e-3 {
                    borderline += 1;
                } else if d < f64::from(params.radius_m) && !occurrence.bit(p) {
                    off += 1;
                }
            }
        }
        let skipped = header.skipped_occurrence;
        println!("{} tufts; {skipped} of {} cells in range skipped (the twin: {off})", gpu.len(), header.in_range);
        assert!(skipped.abs_diff(off) <= borderline && off > header.in_range / 3, "{skipped} against {off}");
        let ground = candidate_ground(ctx, &rig, &params, cam);
        let cpu = place_cpu(&params, [cam[0], cam[1]], true, |p| ground.get(&p.map(f32::to_bits)).copied());
        let without_holes = place_cpu(&params, [cam[0], cam[1]], false, |p| ground.get(&p.map(f32::to_bits)).copied());
        let (compared, _) = compare_with_the_twin(&rig, &gpu, &cpu, &without_holes);
        assert!(compared > 300, "{compared} tufts compared");
        let _ = std::fs::remove_dir_all(dir);
    });
}

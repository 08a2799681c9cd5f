//! Effect `cliff_meshes`: meshes only on cells whose ground is steeper than
//! the threshold (a CPU twin of the rule from the terrain's heights),
//! watertight among themselves (shared vertices bit-identical) and to the
//! height field (every vertex on the mesh's open rim lies on it), shaded
//! by the cliff flavours (classification read back), the height field
//! under a meshed cell sunk behind its mesh (no fight, no hole, at a
//! spacing that is no power of two), and off nothing of it is built and
//! the image is the one without it.

mod common;

use common::gpu_test;
use common::terrain::{small_world as world, view, Rig, Surface};
use std::collections::{BTreeMap, BTreeSet};
use vista::effects::cliff_meshes::{CliffMeshParams, CELL_VERTICES};
use vista::gpu::Context;
use vista::passes::cull_patches::CullStages;
use vista::passes::terrain_query::{TerrainQuery, VistaTerrain};
use vista::render::offscreen::Capture;
use vista::render::{Effect, Effects, RendererOptions, View};
use vista::shaders::consts::{CLIFF_CELL_QUADS, FLAVOUR_FAR_CLIFF, FLAVOUR_NEAR_CLIFF};
use vista::world::WorldDesc;

const SIZE: [u32; 2] = [256, 192];
/// A meadow with a 51-degree cone (its flanks past the 40-degree threshold).
const GROUND: Surface = Surface::Bump { z0: 300.0, c: [500.0, 214.0], r: 10.0, h: 12.0 };

fn effects(meshes: bool) -> Effects {
    let mut fx =
        Effects::default().with(Effect::Cliffs, true).with(Effect::CliffMeshes, meshes).with(Effect::Lighting, false);
    fx.cliff_meshes = CliffMeshParams { radius_m: 24.0, ..CliffMeshParams::default() };
    fx
}

fn rig(ctx: &Context, fx: Effects) -> Rig {
    let options = RendererOptions { effects: fx, ..RendererOptions::default() };
    Rig::with_options(ctx, world(), GROUND, vec![], SIZE, false, options)
}

fn low() -> View {
    view([500.0, 200.0, 303.0], 0.0, -8.0, SIZE, 1.0)
}

/// Heights at `points` through terrain_query (tested against the CPU in
/// traverse_gpu.rs).
fn heights(ctx: &Context, rig: &Rig, points: &[[f32; 2]]) -> Vec<f32> {
    let r = &rig.renderer;
    let mut q = TerrainQuery::new(ctx, points.len() as u32).unwrap();
    let terrain = VistaTerrain::new(&rig.world, &r.sector_data);
    ctx.submit_and_wait(|rec| q.record(rec, terrain, &r.terrain.tree, &r.sector_data, points)).unwrap();
    q.answers(points.len()).into_iter().map(|a| a.expect("terrain under every cell").height_m).collect()
}

#[test]
fn meshes_only_on_steep_cells_watertight_and_shaded_as_cliffs() {
    gpu_test(|ctx| {
        let mut on = rig(ctx, effects(true));
        let mut off = rig(ctx, effects(false));
        let b = on.shot(ctx, &low(), CullStages::default());
        let a = off.shot(ctx, &low(), CullStages::default());
        let c = on.renderer.effect::<vista::effects::cliff_meshes::CliffMeshes>().unwrap();
        let p = c.params;
        let (counters, vertices) = c.read(ctx).unwrap();
        let side = CLIFF_CELL_QUADS + 1;
        let cells = listed_cells(&vertices, &p);
        assert_eq!(cells.len() as u32, counters.cells);

        // The twin: a cell is steep when any vertex's slope, from central
        // differences of the height field half a sample apart, passes the threshold.
        // Around the centre the build snapped to, out to the reach.
        let centre = c.built_centre().unwrap();
        let expect = [500.0f32, 200.0].map(|v| ((v / p.step_m()).floor() + 0.5) * p.step_m());
        assert_eq!(centre, expect);
        let step = 0.5 * rig_spacing(&on);
        let candidates = candidate_cells(&p, centre);
        let points = slope_points(&p, &candidates, step);
        let h = heights(ctx, &on, &points);
        let Twin { steep_cells, borderline, on_field } = twin(&p, &candidates, &points, &h, step);
        let listed: BTreeSet<[i32; 2]> = cells.keys().copied().collect();
        println!(
            "{} cells tested, {} meshed ({} triangles), the twin says {} ({borderline} vertices at the threshold)",
            counters.tested,
            counters.cells,
            counters.triangles,
            steep_cells.len()
        );
        assert_eq!(counters.tested as usize, candidates.len());
        assert!(borderline == 0 && listed == steep_cells, "GPU {} cells, twin {}", listed.len(), steep_cells.len());
        assert!(listed.len() > 40 && listed.len() < candidates.len() / 2, "{} of {}", listed.len(), candidates.len());

        check_watertight(&cells, &on_field, side);
        check_shaded_as_cliffs(ctx, &on, &a, &b);
    });
}

/// At a cell size that is no power of two (0.3 m: neither it nor a quarter
/// of it is exact in binary), neighbouring cells still share their edge
/// vertices bit for bit: the vertices are integer lattice indices times one
/// spacing. (`cell * cell_m + k * cell_m / 4`, as before, rounds each side
/// differently.)
#[test]
fn meshes_at_a_non_dyadic_cell_size_share_their_edges_bit_for_bit() {
    gpu_test(|ctx| {
        let mut fx = effects(true);
        fx.cliff_meshes.cell_m = 0.3;
        fx.cliff_meshes.radius_m = 12.0;
        // Unpushed, so each cell is known by its first vertex (a push of
        // more than half of 0.3 m would move it into the next cell's key).
        fx.cliff_meshes.amplitude_m = 0.0;
        let mut on = rig(ctx, fx);
        on.shot(ctx, &low(), CullStages::default());
        let c = on.renderer.effect::<vista::effects::cliff_meshes::CliffMeshes>().unwrap();
        let p = c.params;
        let (counters, vertices) = c.read(ctx).unwrap();
        let cells = listed_cells(&vertices, &p);
        assert_eq!(cells.len() as u32, counters.cells);
        let side = (CLIFF_CELL_QUADS + 1) as usize;
        let (mut east, mut north) = (0, 0);
        for (cell, patch) in &cells {
            if let Some(e) = cells.get(&[cell[0] + 1, cell[1]]) {
                for r in 0..side {
                    assert_eq!(patch[r * side + side - 1], e[r * side], "crack east of {cell:?}");
                    east += 1;
                }
            }
            if let Some(n) = cells.get(&[cell[0], cell[1] + 1]) {
                for i in 0..side {
                    assert_eq!(patch[(side - 1) * side + i], n[i], "crack north of {cell:?}");
                    north += 1;
                }
            }
        }
        println!("{} cells of 0.3 m; {east} east and {north} north edge vertices shared, identical", cells.len());
        assert!(east > 100 && north > 100, "{east} {north}");
    });
}

/// Each listed cell by its first vertex (its south-west corner, on the grid).
fn listed_cells<'v>(vertices: &'v [[f32; 4]], p: &CliffMeshParams) -> BTreeMap<[i32; 2], &'v [[f32; 4]]> {
    let mut cells: BTreeMap<[i32; 2], &[[f32; 4]]> = BTreeMap::new();
    for patch in vertices.chunks_exact(CELL_VERTICES as usize) {
        let key = [0, 1].map(|i| (patch[0][i] / p.cell_m).round() as i32);
        assert!(cells.insert(key, patch).is_none(), "cell {key:?} listed twice");
    }
    cells
}

/// The cells whose middle is within the reach of the build's centre.
fn candidate_cells(p: &CliffMeshParams, centre: [f32; 2]) -> Vec<[i32; 2]> {
    let cell0 = centre.map(|c| ((c - p.reach_m()) / p.cell_m).floor() as i32);
    let mut candidates = Vec::new();
    for j in 0..p.side() as i32 {
        for i in 0..p.side() as i32 {
            let cell = [cell0[0] + i, cell0[1] + j];
            let m = cell.map(|c| (c as f32 + 0.5) * p.cell_m);
            if ((m[0] - centre[0]).powi(2) + (m[1] - centre[1]).powi(2)).sqrt() < p.reach_m() {
                candidates.push(cell);
            }
        }
    }
    candidates
}

/// Per vertex of every candidate: its four central-difference neighbours
/// `step` away, then the vertex itself.
fn slope_points(p: &CliffMeshParams, candidates: &[[i32; 2]], step: f32) -> Vec<[f32; 2]> {
    let q = p.cell_m / CLIFF_CELL_QUADS as f32;
    let side = CLIFF_CELL_QUADS + 1;
    let mut points = Vec::new();
    for cell in candidates {
        for k in 0..CELL_VERTICES {
            // As the shader: the integer lattice index times one spacing.
            let quads = CLIFF_CELL_QUADS as i32;
            let g = [cell[0] * quads + (k % side) as i32, cell[1] * quads + (k / side) as i32];
            let v = [g[0] as f32 * q, g[1] as f32 * q];
            points.extend([[v[0] + step, v[1]], [v[0] - step, v[1]], [v[0], v[1] + step], [v[0], v[1] - step], v]);
        }
    }
    points
}

/// What the CPU twin of the rule says.
struct Twin {
    steep_cells: BTreeSet<[i32; 2]>,
    /// Vertices whose slope is at the threshold (within 1e-4).
    borderline: usize,
    /// Heights of the vertices under the threshold slope, by their bits.
    on_field: BTreeMap<[u32; 2], f32>,
}

fn twin(p: &CliffMeshParams, candidates: &[[i32; 2]], points: &[[f32; 2]], h: &[f32], step: f32) -> Twin {
    let [cos_start, _] = p.cos_range();
    let (mut steep_cells, mut borderline) = (BTreeSet::new(), 0);
    let mut on_field: BTreeMap<[u32; 2], f32> = BTreeMap::new();
    for (ci, cell) in candidates.iter().enumerate() {
        let mut steep = false;
        for k in 0..CELL_VERTICES as usize {
            let s = &h[(ci * CELL_VERTICES as usize + k) * 5..][..5];
            let n = glam::Vec3::new(-(s[0] - s[1]), -(s[2] - s[3]), 2.0 * step).normalize();
            borderline += usize::from((n.z - cos_start).abs() < 1e-4);
            if n.z < cos_start {
                steep = true;
            } else {
                let v = points[(ci * CELL_VERTICES as usize + k) * 5 + 4];
                on_field.insert(v.map(f32::to_bits), s[4]);
            }
        }
        if steep {
            steep_cells.insert(*cell);
        }
    }
    Twin { steep_cells, borderline, on_field }
}

/// Watertight among themselves (a shared edge's vertices are the same
/// bits) and to the height field.
fn check_watertight(cells: &BTreeMap<[i32; 2], &[[f32; 4]]>, on_field: &BTreeMap<[u32; 2], f32>, side: u32) {
    let mut shared = 0;
    for (cell, patch) in cells {
        if let Some(east) = cells.get(&[cell[0] + 1, cell[1]]) {
            for r in 0..side as usize {
                assert_eq!(
                    patch[r * side as usize + side as usize - 1],
                    east[r * side as usize],
                    "crack east of {cell:?}"
                );
                shared += 1;
            }
        }
    }
    // And to the height field: every vertex under the threshold slope
    // (the open rim among them) stands on it, unpushed.
    let (mut rim, mut worst) = (0, 0.0f32);
    for patch in cells.values() {
        for v in patch.iter() {
            if let Some(z) = on_field.get(&[v[0].to_bits(), v[1].to_bits()]) {
                worst = worst.max((v[2] - z).abs());
                rim += 1;
            }
        }
    }
    println!("{shared} shared edge vertices identical; {rim} vertices under the threshold, worst gap {worst:.6} m");
    // f32 at 300 m: the same bilinear height, a few ulps apart at most.
    assert!(rim > 100 && worst <= 1e-4, "{rim} {worst}");
}

/// Shaded by the cliff flavours: every pixel the meshes cover whose
/// (pushed) normal is past the shading's cliff start is classified
/// cliff; the others lean back towards level on a bulge's top.
fn check_shaded_as_cliffs(ctx: &Context, on: &Rig, a: &Capture, b: &Capture) {
    let gb = on.renderer.gbuffer.as_ref().unwrap().capture(ctx).unwrap();
    let cliff = (FLAVOUR_NEAR_CLIFF | FLAVOUR_FAR_CLIFF) as u8;
    let [cliff_start, _] = on.renderer.shade.slope_normal_z();
    let (mut meshed, mut as_cliff, mut steep) = (0, 0, 0);
    for i in 0..a.depth.len() {
        if b.depth[i] > a.depth[i] * 1.0001 {
            meshed += 1;
            let code = gb.geometry_normals[i];
            let n = vista::reference::octahedral::oct_decode8([u32::from(code[0]), u32::from(code[1])]);
            let classified = gb.classification[i] & cliff != 0;
            as_cliff += usize::from(classified);
            // The code is the normal in 8 bits: z within 1e-2 of what the shader classified by.
            if n[2] < f64::from(cliff_start) - 1e-2 {
                assert!(classified, "pixel {i}: normal {n:?} is a cliff's, classification {}", gb.classification[i]);
                steep += 1;
            }
        }
    }
    println!(
        "{meshed} pixels in front of the height field, {as_cliff} classified cliff ({steep} past the cliff start)"
    );
    assert!(meshed > 200 && steep * 10 >= meshed * 8, "{steep} of {meshed}");
}

fn rig_spacing(rig: &Rig) -> f32 {
    rig.world.spacing_m as f32
}

#[test]
fn off_nothing_is_built_and_the_image_is_the_one_without_it() {
    gpu_test(|ctx| {
        let mut none = rig(ctx, effects(false));
        let mut refused = rig(ctx, effects(true).with(Effect::Cliffs, false));
        let d = refused.renderer.effects().iter().find(|d| d.effect == Effect::CliffMeshes).unwrap().clone();
        assert!(!d.on && d.reason.contains("cliffs is off"), "{}", d.reason);
        let mut no_cliffs = rig(ctx, effects(false).with(Effect::Cliffs, false));
        for r in [&none, &refused] {
            assert!(r.renderer.effect::<vista::effects::cliff_meshes::CliffMeshes>().is_none());
            assert!(!r.renderer.pipelines().iter().any(|p| p.contains("cliff_mesh")), "{:?}", r.renderer.pipelines());
        }
        let _ = none.shot(ctx, &low(), CullStages::default());
        let a = refused.shot(ctx, &low(), CullStages::default());
        let b = no_cliffs.shot(ctx, &low(), CullStages::default());
        assert!(a.rgba == b.rgba && a.depth == b.depth, "cliff meshes refused changed the image");
    });
}

/// A world whose spacing is no power of two: 0.3 m posts, so the 2 m
/// cells' edges fall between them and the meshes' rim meets the terrain's
/// triangles mid-quad.
fn odd_world() -> WorldDesc {
    WorldDesc {
        extent_m: [307.2, 307.2],
        height_range_m: [100.0, 500.0],
        spacing_m: 0.3,
        lod_count: 4,
        ..WorldDesc::default()
    }
}

/// The cone of GROUND, in the odd world, 14 m ahead of the camera.
const ODD_GROUND: Surface = Surface::Bump { z0: 300.0, c: [150.0, 164.0], r: 10.0, h: 12.0 };

/// The cliff meshes unpushed (`amplitude_m` 0: the mesh IS the height
/// field, at its own triangulation, the case where the two fight most)
/// with the height field sunk `sink_m` behind them; None: meshes off.
fn odd_rig(ctx: &Context, sink_m: Option<f32>) -> Rig {
    let mut fx = effects(sink_m.is_some());
    fx.cliff_meshes.amplitude_m = 0.0;
    fx.cliff_meshes.sink_m = sink_m.unwrap_or(0.0);
    let options = RendererOptions { effects: fx, ..RendererOptions::default() };
    Rig::with_options(ctx, odd_world(), ODD_GROUND, vec![], SIZE, false, options)
}

#[test]
fn at_a_non_dyadic_spacing_the_meshes_are_watertight_and_the_height_field_sinks_behind_them() {
    gpu_test(|ctx| {
        let at = view([150.0, 150.0, 303.0], 0.0, -8.0, SIZE, 1.0);
        let bare = odd_rig(ctx, None).shot(ctx, &at, CullStages::default());
        let mut on = odd_rig(ctx, Some(CliffMeshParams::default().sink_m));
        let a = on.shot(ctx, &at, CullStages::default());
        check_on_the_height_field(ctx, &on);
        // Sunk far past any gap between the two triangulations: what the
        // mesh alone shows wherever it is drawn.
        let deep = odd_rig(ctx, Some(20.0)).shot(ctx, &at, CullStages::default());
        // Sunk by a micrometre: the same pipeline (a written depth rounds
        // unlike the fixed function's), the two surfaces left to fight.
        let none = odd_rig(ctx, Some(1e-6)).shot(ctx, &at, CullStages::default());
        let (mut drawn, mut meshed, mut fights, mut holes) = (0, 0, 0, 0);
        for i in 0..bare.depth.len() {
            holes += usize::from(bare.depth[i] > 0.0 && a.depth[i] == 0.0);
            // Where `deep` shows the sunk terrain (20 m behind: its depth
            // far below the bare terrain's), no mesh covers the pixel.
            if deep.depth[i] < bare.depth[i] * 0.99 {
                continue;
            }
            drawn += 1;
            // The mesh's triangulation parts from the terrain's by
            // millimetres, 1e-4 of the depth; rounding is 1e-7.
            meshed += usize::from((deep.depth[i] - bare.depth[i]).abs() > 1e-6 * bare.depth[i]);
            assert_eq!(a.depth[i], deep.depth[i], "pixel {i}: the height field won over its mesh");
            fights += usize::from(none.depth[i] != deep.depth[i]);
        }
        println!(
            "{drawn} pixels without the sunk terrain in view, {meshed} where the mesh's depth parts from the bare \
             terrain's; sunk by the default, every one shows what the mesh alone shows; sunk by a micrometre, \
             the height field wins {fights}; {holes} holes"
        );
        assert_eq!(holes, 0, "pixels the bare terrain covered are empty with the meshes");
        assert!(meshed > 500, "{meshed}");
        // The test can fail: without the sink the two triangulations fight.
        assert!(fights > 50, "{fights}");
    });
}

/// Unpushed, every mesh vertex lies on the height field, neighbouring
/// cells share their edges bit for bit, and the sink marks exactly the
/// meshed cells.
fn check_on_the_height_field(ctx: &Context, on: &Rig) {
    let c = on.renderer.effect::<vista::effects::cliff_meshes::CliffMeshes>().unwrap();
    let (counters, vertices) = c.read(ctx).unwrap();
    let cells = listed_cells(&vertices, &c.params);
    let (header, sunk) = c.sink().expect("sink_m > 0").read(ctx).unwrap();
    assert_eq!(header.sink_m, c.params.sink_m);
    assert_eq!(sunk.into_iter().collect::<BTreeSet<_>>(), cells.keys().copied().collect::<BTreeSet<_>>());
    let points: Vec<[f32; 2]> = vertices.iter().map(|v| [v[0], v[1]]).collect();
    let h = heights(ctx, on, &points);
    let worst = vertices.iter().zip(&h).map(|(v, z)| (v[2] - z).abs()).fold(0.0f32, f32::max);
    let side = (CLIFF_CELL_QUADS + 1) as usize;
    let mut shared = 0;
    for (cell, patch) in &cells {
        if let Some(e) = cells.get(&[cell[0] + 1, cell[1]]) {
            for r in 0..side {
                assert_eq!(patch[r * side + side - 1], e[r * side], "crack east of {cell:?}");
                shared += 1;
            }
        }
    }
    println!(
        "{} cells meshed, {shared} east edge vertices shared, worst gap to the height field {worst:.6} m",
        counters.cells
    );
    // f32 at 300 m: the same bilinear height, a few ulps apart at most.
    assert!(counters.cells > 40 && shared > 100 && worst <= 1e-4, "{} {shared} {worst}", counters.cells);
}

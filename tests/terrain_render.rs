//! Terrain on screen, through `TerrainRenderer` as `vista render` uses it:
//! watertight LOD seams (deltas 0..4), depth against closed-form ray casts,
//! holes and world edges exactly where they belong, culling that never
//! changes a pixel, cone culling that removes only back-facing triangles.

mod common;

use common::gpu_test;
use common::terrain::{small_world as hills_world, view, Rig, Surface, MAGENTA_RGBA};
use common::Rng;
use glam::DVec3;
use std::collections::BTreeSet;
use vista::passes::cull_patches::{CullStages, PatchRecord};
use vista::render::offscreen::Capture;
use vista::render::View;
use vista::world::{bake_node, Hole, NodeId, WorldDesc, PATCHES_PER_NODE_SIDE, PATCH_HOLE_ALL, PATCH_QUADS};

fn magenta(c: &Capture, x: u32, y: u32) -> bool {
    c.pixel(x, y) == MAGENTA_RGBA
}

/// Where the ray through a pixel point meets the plane z = `z`, if ahead.
fn ground_point(v: &View, px: [f64; 2], z: f64) -> Option<[f64; 2]> {
    let o = v.camera.position_m;
    let d = v.ray(px);
    let t = (z - o[2]) / d.z;
    (t > 0.0 && t.is_finite()).then(|| [o[0] + t * d.x, o[1] + t * d.y])
}

/// The pixel's centre and four points 0.6 px around it all satisfy `f`
/// (so rasterization at the footprint's border cannot decide the pixel).
fn pixel_all(x: u32, y: u32, f: impl Fn([f64; 2]) -> bool) -> bool {
    let c = [f64::from(x) + 0.5, f64::from(y) + 0.5];
    [[0.0, 0.0], [0.6, 0.0], [-0.6, 0.0], [0.0, 0.6], [0.0, -0.6]].iter().all(|o| f([c[0] + o[0], c[1] + o[1]]))
}

/// 2 x 1 roots of 2048 m (1 m spacing, 5 LODs) over a flat plane with a
/// cone-shaped hill whose foot comes within 52 m of the root boundary: only
/// nodes overlapping the cone have any error, so LOD-0 nodes at its foot sit
/// beside the unrefined LOD-4 root to the west, and every delta 0..4 occurs.
#[test]
fn seams_are_watertight_for_every_lod_delta() {
    let world = WorldDesc {
        extent_m: [4096.0, 2048.0],
        height_range_m: [0.0, 200.0],
        spacing_m: 1.0,
        lod_count: 5,
        ..WorldDesc::default()
    };
    let bump = Surface::Bump { z0: 100.0, c: [2300.0, 1100.0], r: 200.0, h: 60.0 };
    let size = [96, 96];
    gpu_test(|ctx| {
        let mut rig = Rig::new(ctx, world, bump, Vec::new(), size, false);
        let mut rng = Rng(7);
        let mut deltas_seen = BTreeSet::new();
        let inside = |p: [f64; 2]| p[0] > 0.0 && p[0] < 4096.0 && p[1] > 0.0 && p[1] < 2048.0;
        // Top-down first, then 100 random perspective views; a tiny target
        // refines every node with any error at all.
        let mut views = vec![view([2048.0, 1024.0, 2500.0], 0.0, -90.0, size, 1e-3)];
        for _ in 0..100 {
            let p = [rng.unit() * 5000.0 - 450.0, rng.unit() * 3000.0 - 450.0, 150.0 + rng.unit() * 1500.0];
            views.push(view(p, rng.unit() * 360.0, -5.0 - rng.unit() * 84.0, size, 1e-3));
        }
        for (i, v) in views.iter().enumerate() {
            let c = rig.shot(ctx, v, CullStages::ALL);
            for p in rig.renderer.read_patches(ctx).unwrap() {
                deltas_seen.extend(p.deltas);
            }
            let mut holes = 0;
            for y in 0..size[1] {
                for x in 0..size[0] {
                    let in_footprint = pixel_all(x, y, |px| ground_point(v, px, 100.0).is_some_and(inside));
                    if in_footprint && magenta(&c, x, y) {
                        holes += 1;
                    }
                }
            }
            assert_eq!(holes, 0, "view {i} {v:?}: {holes} background pixels inside the terrain");
        }
        assert_eq!(deltas_seen, (0..=4).collect(), "the views must exercise every LOD delta 0..4");
    });
}

/// Depth tolerance for one pixel, metres along the forward axis. Vertical
/// error sources: the R16 height step (range / 65535); for a curved surface
/// the LOD criterion's promise (target px at the hit's distance, doubled:
/// the baked error is per refinement step, not the sum over steps) and 1 cm
/// for LOD 0's own triangles (a planar surface is meshed exactly at every
/// LOD, so it gets neither). A vertical error moves the hit by
/// dh / |grad . d_xy - d_z| along the ray. Plus 1e-5 relative for f32.
fn depth_tolerance(surface: &Surface, v: &View, ray: DVec3, t: f64, range: f64) -> f64 {
    let o = v.camera.position_m;
    let hit = [o[0] + t * ray.x, o[1] + t * ray.y];
    let g = surface.gradient(hit[0], hit[1]);
    let ppt = f64::from(v.size[1]) / 2.0 * v.focal();
    let curved = matches!(surface, Surface::Paraboloid { .. });
    let lod = if curved { 2.0 * f64::from(v.target_error_px) * t / ppt + 0.01 } else { 0.0 };
    let dh = range / 65535.0 + lod;
    let rate = (g[0] * ray.x + g[1] * ray.y - ray.z).abs();
    let forward = v.camera.basis()[0].dot(ray);
    dh / rate * forward + 1e-5 * t * forward
}

#[test]
fn depth_matches_closed_form_ray_casts() {
    let world = WorldDesc {
        extent_m: [1024.0, 1024.0],
        height_range_m: [-100.0, 900.0],
        spacing_m: 1.0,
        lod_count: 4,
        ..WorldDesc::default()
    };
    let size = [64, 64];
    let surfaces = [
        Surface::Plane(50.0),
        Surface::Tilted { z0: 150.0, gx: 0.3, gy: -0.2 },
        Surface::Paraboloid { z0: 0.0, a: 0.0015, c: [512.0, 512.0] },
    ];
    gpu_test(|ctx| {
        for surface in surfaces {
            let mut rig = Rig::new(ctx, world, surface, Vec::new(), size, true);
            let views = [
                view([512.0, 512.0, 1000.0], 0.0, -90.0, size, 1.0),
                view([100.0, 150.0, 600.0], 40.0, -35.0, size, 1.0),
                view([900.0, 800.0, 450.0], 230.0, -50.0, size, 0.5),
            ];
            for v in &views {
                let c = rig.shot(ctx, v, CullStages::ALL);
                let depth = c.linear_depth(v.near_m);
                let at = |x: u32, y: u32| depth[(y * size[0] + x) as usize];
                let (mut checked, mut worst) = (0, 0.0f64);
                for y in 1..size[1] - 1 {
                    for x in 1..size[0] - 1 {
                        // Interior pixels only: a silhouette pixel's depth
                        // depends on which side of the edge its centre falls.
                        if (0..9).any(|k| at(x + k % 3 - 1, y + k / 3 - 1) == 0.0) {
                            continue;
                        }
                        let ray = v.ray([f64::from(x) + 0.5, f64::from(y) + 0.5]);
                        let t = surface.intersect(v.camera.position_m, ray.to_array());
                        let t =
                            t.unwrap_or_else(|| panic!("{surface:?} {v:?}: GPU terrain at ({x},{y}), CPU ray misses"));
                        let expect = t * v.camera.basis()[0].dot(ray);
                        let tol = depth_tolerance(&surface, v, ray, t, 1000.0);
                        let err = (f64::from(at(x, y)) - expect).abs();
                        assert!(err <= tol, "{surface:?} {v:?} ({x},{y}): depth {} vs {expect} (tol {tol})", at(x, y));
                        worst = worst.max(err / tol);
                        checked += 1;
                    }
                }
                assert!(checked > 500, "{surface:?}: only {checked} interior terrain pixels");
                eprintln!("{surface:?}: {checked} pixels, worst error {:.3} of its tolerance", worst);
            }
        }
    });
}

/// Spacing (m) of the coarsest node drawn: holes and edges are exact to
/// the vertex resolution of the node that draws them.
fn coarsest_spacing(rig: &Rig, ctx: &vista::gpu::Context) -> f64 {
    let patches = rig.renderer.read_patches(ctx).unwrap();
    let lod = patches.iter().map(|p| p.lod).max().expect("something drawn");
    rig.world.node_spacing_m(lod)
}

#[test]
fn holes_show_background_exactly_where_the_holes_are() {
    let world = WorldDesc {
        extent_m: [1024.0, 1024.0],
        height_range_m: [0.0, 100.0],
        spacing_m: 1.0,
        lod_count: 4,
        ..WorldDesc::default()
    };
    // The circle contains the whole root patch [256, 384] x [320, 448].
    let circle = Hole::Circle { center_m: [320.0, 384.0], radius_m: 150.0 };
    let square = Hole::Polygon(vec![[600.0, 600.0], [700.0, 600.0], [700.0, 700.0], [600.0, 700.0]]);
    let holes = vec![circle.clone(), square.clone()];
    let size = [128, 128];
    let surface = Surface::Plane(50.0);
    gpu_test(|ctx| {
        let mut rig = Rig::new(ctx, world, surface, holes.clone(), size, true);
        let v = view([512.0, 512.0, 50.0 + 700.0], 0.0, -90.0, size, 1.0);
        let c = rig.shot(ctx, &v, CullStages::ALL);
        let margin = 1.5 * coarsest_spacing(&rig, ctx);
        // Inside a hole by more than `margin`, or clear of every hole by
        // more, judged on a ring of 16 probes (the holes are convex).
        let in_any = |q: [f64; 2]| holes.iter().any(|h| h.contains(q[0], q[1]));
        let probes = |p: [f64; 2]| {
            (0..16).map(move |k| {
                let a = f64::from(k) * std::f64::consts::TAU / 16.0;
                [p[0] + margin * a.cos(), p[1] + margin * a.sin()]
            })
        };
        let deep_in_hole = |p: [f64; 2]| in_any(p) && probes(p).all(in_any);
        let clear_of_holes = |p: [f64; 2]| !in_any(p) && !probes(p).any(in_any);
        let (mut bg, mut fg) = (0, 0);
        for y in 0..size[1] {
            for x in 0..size[0] {
                let hole = pixel_all(x, y, |px| ground_point(&v, px, 50.0).is_some_and(deep_in_hole));
                let solid = pixel_all(x, y, |px| ground_point(&v, px, 50.0).is_some_and(clear_of_holes));
                if hole {
                    assert!(magenta(&c, x, y), "pixel ({x},{y}) lies inside a hole but shows terrain");
                    bg += 1;
                }
                if solid {
                    assert!(!magenta(&c, x, y), "pixel ({x},{y}) lies on solid ground but shows background");
                    fg += 1;
                }
            }
        }
        assert!(bg > 200 && fg > 5000, "too few pixels decided: {bg} hole, {fg} solid");
        // All-hole patches are culled before the draw, and never drawn.
        let counters = rig.renderer.read_counters(ctx).unwrap().cull;
        assert!(counters.after_hole < counters.after_cone, "no all-hole patch was removed: {counters:?}");
        for p in rig.renderer.read_patches(ctx).unwrap() {
            let node = bake_node(&surface, &world, &holes, NodeId::new(p.lod, p.node_x, p.node_y));
            assert_ne!(node.patch_holes[p.patch as usize], PATCH_HOLE_ALL, "{p:?} is all hole but drawn");
        }
        // Without the hole stage the NaN vertices still cut the same holes:
        // the picture is identical, only more patches are drawn.
        let no_hole_stage = rig.again(ctx, &v, CullStages { hole: false, ..CullStages::ALL });
        assert_eq!(no_hole_stage.rgba, c.rgba);
        assert!(rig.renderer.read_counters(ctx).unwrap().cull.drawn > counters.drawn);
    });
}

#[test]
fn a_world_ends_cleanly_at_an_extent_that_is_not_a_multiple_of_the_node_size() {
    let world = WorldDesc {
        extent_m: [1000.0, 700.0],
        height_range_m: [0.0, 100.0],
        spacing_m: 1.0,
        lod_count: 4,
        ..WorldDesc::default()
    };
    let size = [128, 128];
    gpu_test(|ctx| {
        let mut rig = Rig::new(ctx, world, Surface::Plane(50.0), Vec::new(), size, true);
        let v = view([850.0, 560.0, 50.0 + 500.0], 0.0, -90.0, size, 1.0);
        let c = rig.shot(ctx, &v, CullStages::ALL);
        let m = 1.5 * coarsest_spacing(&rig, ctx);
        let (mut bg, mut fg) = (0, 0);
        for y in 0..size[1] {
            for x in 0..size[0] {
                let ground = |px| ground_point(&v, px, 50.0).unwrap();
                if pixel_all(x, y, |px| {
                    let p = ground(px);
                    p[0] > 1000.0 + m || p[1] > 700.0 + m
                }) {
                    assert!(magenta(&c, x, y), "({x},{y}) beyond the extent shows terrain (no edge streaks)");
                    bg += 1;
                }
                if pixel_all(x, y, |px| {
                    let p = ground(px);
                    p[0] < 1000.0 - m && p[1] < 700.0 - m
                }) {
                    assert!(!magenta(&c, x, y), "({x},{y}) inside the extent shows background");
                    fg += 1;
                }
            }
        }
        assert!(bg > 1000 && fg > 5000, "too few pixels decided: {bg} beyond, {fg} inside");
    });
}

/// Camera poses over the hills: random teleports, with every fourth pose a
/// fast turn (90 to 180 degrees) of the one before at the same place.
fn hill_poses(n: usize, size: [u32; 2]) -> Vec<View> {
    let mut rng = Rng(99);
    let mut out: Vec<View> = Vec::new();
    for i in 0..n {
        if i % 4 == 3 {
            let prev = out[i - 1].camera;
            let turn = 90.0 + rng.unit() * 90.0;
            out.push(view(prev.position_m, prev.yaw_deg + turn, prev.pitch_deg, size, 1.0));
            continue;
        }
        let (x, y) = (rng.unit() * 1400.0 - 188.0, rng.unit() * 1400.0 - 188.0);
        let z = Surface::Hills.height(x, y) + 2.0 + rng.unit() * 400.0;
        out.push(view([x, y, z], rng.unit() * 360.0, -60.0 + rng.unit() * 75.0, size, 1.0));
    }
    out
}

#[test]
fn culling_never_changes_a_pixel() {
    let size = [64, 64];
    gpu_test(|ctx| {
        let (mut frustum_culled, mut cone_culled) = (0, 0);
        // The hills from 100 poses, and the cone hill, whose far flank the
        // cone stage removes.
        for (surface, poses) in [(Surface::Hills, hill_poses(100, size)), (CONE_HILL, cone_hill_views(size))] {
            let mut rig = Rig::new(ctx, hills_world(), surface, Vec::new(), size, true);
            for (i, v) in poses.iter().enumerate() {
                let on = rig.shot(ctx, v, CullStages::ALL);
                let k = rig.renderer.read_counters(ctx).unwrap().cull;
                frustum_culled += k.patches_in - k.after_frustum;
                cone_culled += k.after_frustum - k.after_cone;
                let off = rig.again(ctx, v, CullStages::NONE);
                let k_off = rig.renderer.read_counters(ctx).unwrap().cull;
                // Instances: a patch refined below LOD 0 counts its sub-patches.
                assert_eq!(k_off.drawn, k.patches_in, "culling off draws every patch");
                assert!(on.rgba == off.rgba, "pose {i} {v:?}: colour differs with culling on");
                let bits = |c: &Capture| c.depth.iter().map(|d| d.to_bits()).collect::<Vec<u32>>();
                assert!(bits(&on) == bits(&off), "pose {i} {v:?}: depth differs with culling on");
            }
        }
        // The comparison means something only if culling removed patches.
        assert!(frustum_culled > 1000 && cone_culled > 0, "frustum culled {frustum_culled}, cone {cone_culled}");
    });
}

/// The triangles of a patch as the GPU draws them (diamond split,
/// counter-clockwise from above, edge vertices snapped to the coarser
/// neighbours' grids by the record's deltas as `terrain_vertex.glsl` does),
/// from the CPU bake of its node; degenerate ones (no area) left out.
fn patch_triangles(world: &WorldDesc, surface: &Surface, p: &PatchRecord) -> Vec<[DVec3; 3]> {
    assert_eq!(p.refine, 0, "refined patches are not cone-tested");
    let node = bake_node(surface, world, &[], NodeId::new(p.lod, p.node_x, p.node_y));
    let b = world.bounds_m(node.id);
    let s = world.node_spacing_m(p.lod);
    let (px, py) = (p.patch % PATCHES_PER_NODE_SIDE * PATCH_QUADS, p.patch / PATCHES_PER_NODE_SIDE * PATCH_QUADS);
    // Nearest point of the grid 2^d coarser, ties toward the lower one.
    let snap = |v: u32, d: u8| if d == 0 { v } else { ((v + (1 << (d - 1)) - 1) >> d) << d };
    let [dw, de, ds, dn] = p.deltas;
    // Snapped in node coordinates: past log2(PATCH_QUADS) the coarse vertex
    // lies beyond the patch's corners.
    let v = |i: u32, j: u32| {
        let q = PATCH_QUADS;
        let (x, y) = (px + i, py + j);
        let gi = match j {
            0 => snap(x, ds),
            j if j == q => snap(x, dn),
            _ => x,
        };
        let gj = match i {
            0 => snap(y, dw),
            i if i == q => snap(y, de),
            _ => y,
        };
        let h = world.decode_height(node.height(gi as isize, gj as isize));
        DVec3::new(b[0] + f64::from(gi) * s, b[1] + f64::from(gj) * s, f64::from(h))
    };
    let mut out = Vec::new();
    for qy in 0..PATCH_QUADS {
        for qx in 0..PATCH_QUADS {
            let (a, bb, c, d) = (v(qx, qy), v(qx + 1, qy), v(qx + 1, qy + 1), v(qx, qy + 1));
            let tris =
                if (px + qx + py + qy).is_multiple_of(2) { [[a, bb, c], [a, c, d]] } else { [[a, bb, d], [bb, c, d]] };
            out.extend(tris.into_iter().filter(|t| (t[1] - t[0]).cross(t[2] - t[0]) != DVec3::ZERO));
        }
    }
    out
}

/// A cone hill (300 m radius, 250 m high) in the middle of the hills
/// world, and views from its foot and slopes: its far flank faces away at
/// the size of the patches the selection draws (the rolling hills' far
/// sides are drawn from patches too large to face away whole).
const CONE_HILL: Surface = Surface::Bump { z0: 150.0, c: [512.0, 512.0], r: 300.0, h: 250.0 };

fn cone_hill_views(size: [u32; 2]) -> Vec<View> {
    let at = |x: f64, y: f64, dz: f64, yaw: f64, pitch: f64, t: f32| {
        view([x, y, CONE_HILL.height(x, y) + dz], yaw, pitch, size, t)
    };
    vec![
        at(112.0, 512.0, 10.0, 90.0, 5.0, 0.5),
        at(182.0, 512.0, 5.0, 90.0, 10.0, 1.0),
        at(512.0, 120.0, 10.0, 0.0, 5.0, 0.5),
        at(62.0, 450.0, 60.0, 80.0, -3.0, 1.0),
        at(900.0, 700.0, 20.0, 240.0, 0.0, 0.5),
    ]
}

#[test]
fn cone_culling_removes_only_patches_whose_every_triangle_faces_away() {
    let size = [48, 48];
    let world = hills_world();
    gpu_test(|ctx| {
        let mut rig = Rig::new(ctx, world, CONE_HILL, Vec::new(), size, true);
        let mut culled_total = 0;
        for v in cone_hill_views(size) {
            rig.shot(ctx, &v, CullStages::NONE);
            let all: BTreeSet<PatchRecord> = rig.renderer.read_patches(ctx).unwrap().into_iter().collect();
            rig.again(ctx, &v, CullStages { frustum: false, cone: true, hole: false, occlusion: false });
            let kept: BTreeSet<PatchRecord> = rig.renderer.read_patches(ctx).unwrap().into_iter().collect();
            assert!(kept.is_subset(&all));
            let cam = DVec3::from(v.camera.position_m);
            for p in all.difference(&kept) {
                culled_total += 1;
                for t in patch_triangles(&world, &CONE_HILL, p) {
                    let n = (t[1] - t[0]).cross(t[2] - t[0]);
                    // Back-facing: the camera is behind the triangle's plane.
                    assert!(n.dot(cam - t[0]) < 0.0, "{p:?} culled but a triangle faces the camera at {cam}");
                }
            }
        }
        assert!(culled_total > 0, "no view cone-culled anything: the check would be vacuous");
        eprintln!("{culled_total} cone-culled patches checked triangle by triangle");
    });
}

/// The whole terrain frame (streaming uploads, traversal, culling, the
/// indirect draw) under synchronization validation: no hazard between
/// passes or between frames in flight.
#[test]
fn terrain_frames_are_clean_under_synchronization_validation() {
    let options = vista::gpu::ContextOptions { sync_validation: true, ..common::validated() };
    common::gpu_test_with(&options, |ctx| {
        let mut rig = Rig::new(ctx, hills_world(), Surface::Hills, Vec::new(), [48, 48], true);
        for yaw in [0.0, 170.0, 300.0] {
            let v = view([512.0, 512.0, 700.0], yaw, -45.0, [48, 48], 1.0);
            let c = rig.shot(ctx, &v, CullStages::ALL);
            assert!(c.depth.iter().any(|&d| d > 0.0), "nothing drawn");
        }
    });
}

//! The GPU traversal (both variants) equals the CPU reference as a set for
//! random resident sets and cameras, tiles the world exactly once, and keeps
//! coarser nodes (counting overflow, never dropping roots) when its lists are
//! too small.

mod common;

use common::{fake_node, gpu_test, Rng};
use std::collections::BTreeSet;
use vista::gpu::Context;
use vista::passes::lod_map::LodMap;
use vista::passes::quadtree_update::QuadtreeUpdatePass;
use vista::passes::sector_data::SectorData;
use vista::passes::terrain_query::{TerrainQuery, VistaTerrain};
use vista::passes::traverse::{Traverse, TraverseMode};
use vista::reference::{lod_map_cpu, sample_height_cpu, sector_data_cpu, traverse_cpu};
use vista::terrain::gpu_quadtree::{AtlasSet, GpuQuadtree};
use vista::terrain::selection::{TraverseCamera, TraverseParams, TraverseResult};
use vista::world::{NodeId, PayloadFormat, WorldDesc};

/// 32 x 31 sectors of 128 m, 5 LODs: a 2x2 root grid with a partial row.
fn world() -> WorldDesc {
    WorldDesc {
        extent_m: [4096.0, 3900.0],
        height_range_m: [-50.0, 950.0],
        spacing_m: 1.0,
        lod_count: 5,
        ..WorldDesc::default()
    }
}

const SLOTS: u32 = 400;

struct Scene {
    tree: GpuQuadtree,
    update: QuadtreeUpdatePass,
    resident: BTreeSet<NodeId>,
    /// Height samples of each node as last added (for CPU sampling).
    heights: std::collections::HashMap<NodeId, Vec<u16>>,
    rng: Rng,
}

impl Scene {
    fn new(ctx: &Context, seed: u64) -> Self {
        let mut s = Scene {
            tree: GpuQuadtree::new(ctx, &world(), SLOTS, 1, AtlasSet::ALL, PayloadFormat::Bc).unwrap(),
            update: QuadtreeUpdatePass::new(ctx, false).unwrap(),
            resident: BTreeSet::new(),
            heights: std::collections::HashMap::new(),
            rng: Rng(seed),
        };
        // Every update waits for the GPU (submit_and_wait) and no frame
        // count advances: no frame in flight needs a freed slot kept.
        s.tree.shadow.set_reuse_delay(0);
        for r in world().roots() {
            s.add(r);
        }
        s
    }

    fn add(&mut self, id: NodeId) {
        if self.resident.len() < SLOTS as usize && self.resident.insert(id) {
            let mut n = fake_node(id, self.rng.below(1000) as u16);
            n.max_error_m = 0.05 + self.rng.below(4000) as f32 / 100.0;
            let a = self.rng.below(60000) as u16;
            (n.min_height, n.max_height) = (a, a + self.rng.below(5000) as u16);
            let bias = if self.rng.below(8) == 0 { self.rng.below(5) as i8 - 2 } else { 0 };
            self.heights.insert(id, n.heights.clone());
            self.tree.add(n, bias);
        }
    }

    /// Random changes: whole families (so refinement can go deep), single
    /// nodes (children missing), removals (roots too, sometimes).
    fn mutate(&mut self, ctx: &Context) {
        let w = world();
        for _ in 0..self.rng.below(12) {
            let list: Vec<NodeId> = self.resident.iter().copied().collect();
            let pick = list[self.rng.below(list.len() as u32) as usize];
            match self.rng.below(10) {
                0..=5 => w.valid_children(pick).into_iter().for_each(|c| self.add(c)),
                6 => {
                    let lod = self.rng.below(w.lod_count) as u8;
                    let all = w.nodes_at(lod);
                    let i = self.rng.below(all.len() as u32) as usize;
                    self.add(all[i]);
                }
                _ => {
                    if pick.lod + 1 < w.lod_count as u8 || self.rng.below(20) == 0 {
                        self.tree.remove(pick);
                        self.resident.remove(&pick);
                    }
                }
            }
        }
        self.flush(ctx);
    }

    /// Uploads until nothing waits (MAX_UPLOADS_PER_FRAME per frame).
    fn flush(&mut self, ctx: &Context) {
        loop {
            ctx.submit_and_wait(|rec| self.update.record(rec, &mut self.tree, None).map(drop)).unwrap();
            if self.tree.waiting() == 0 {
                break;
            }
        }
    }

    fn random_params(&mut self) -> TraverseParams {
        let w = world();
        let cams = 1 + self.rng.below(vista::terrain::selection::MAX_CAMERAS as u32) as usize;
        let cameras = (0..cams)
            .map(|_| {
                let p = [
                    self.rng.below(5000) as f64 - 450.0 + 0.37,
                    self.rng.below(5000) as f64 - 450.0 + 0.61,
                    self.rng.below(2000) as f64 - 100.0,
                ];
                // Any heading, any pitch (straight down and up included).
                let yaw = self.rng.unit() * std::f64::consts::TAU;
                let pitch = (self.rng.unit() - 0.5) * std::f64::consts::PI;
                let forward = [yaw.sin() * pitch.cos(), yaw.cos() * pitch.cos(), pitch.sin()];
                let h = 256 + self.rng.below(1800);
                let size = [h * (1 + self.rng.below(3)) / 2, h];
                TraverseCamera::perspective(p, forward, 30.0 + self.rng.below(60) as f64, size)
            })
            .collect();
        let target = [0.5, 1.0, 2.0, 4.0, 8.0][self.rng.below(5) as usize];
        let _ = w;
        TraverseParams { cameras, target_error_px: target }
    }
}

/// Every valid LOD-0 sector lies in exactly one listed node.
fn assert_tiles_exactly_once(result: &TraverseResult, what: &str) {
    let w = world();
    let [sx, sy] = w.sectors();
    let mut hits = vec![0u32; (sx * sy) as usize];
    for (n, _) in &result.nodes {
        let k = 1u32 << n.lod;
        for y in n.y * k..((n.y + 1) * k).min(sy) {
            for x in n.x * k..((n.x + 1) * k).min(sx) {
                hits[(y * sx + x) as usize] += 1;
            }
        }
    }
    let bad: Vec<usize> = (0..hits.len()).filter(|&i| hits[i] != 1).collect();
    assert!(
        bad.is_empty(),
        "{what}: {} sectors covered != once, e.g. sector {} covered {} times",
        bad.len(),
        bad[0],
        hits[bad[0]]
    );
}

#[test]
fn gpu_traversal_equals_cpu_reference_for_1000_random_cases() {
    gpu_test(|ctx| {
        let mut scene = Scene::new(ctx, 0xFACADE);
        let traverse = Traverse::with_per_level(ctx, &world(), SLOTS).unwrap();
        let lod_map = LodMap::new(ctx, &world()).unwrap();
        let sectors = SectorData::new(ctx, &world()).unwrap();
        let mut deepest = 0;
        let mut multi_checked = 0;
        for case in 0..1000u32 {
            scene.mutate(ctx);
            let params = scene.random_params();
            let modes: &[TraverseMode] = if case.is_multiple_of(10) {
                &[TraverseMode::SingleDispatch, TraverseMode::MultiDispatch]
            } else {
                &[TraverseMode::SingleDispatch]
            };
            let expect = traverse_cpu(&scene.tree.shadow, &world(), &params);
            for &mode in modes {
                ctx.submit_and_wait(|rec| {
                    traverse.record(rec, &scene.tree, &params, mode);
                    lod_map.record(rec, &traverse);
                    sectors.record(rec, &scene.tree);
                    Ok(())
                })
                .unwrap();
                let (header, got) = traverse.read_result(ctx).unwrap();
                assert_eq!(got, expect, "case {case} {mode:?}: GPU list differs from the CPU reference");
                let map = ctx.read_image(lod_map.image(), 0, 0, 1).unwrap();
                assert_eq!(map, lod_map_cpu(&expect, &world()), "case {case} {mode:?}: LOD map");
                let sd = ctx.read_buffer(sectors.buffer()).unwrap();
                let sd_expect: Vec<u32> = sector_data_cpu(&scene.tree.shadow, &world()).into_iter().flatten().collect();
                assert_eq!(bytemuck::cast_slice::<u8, u32>(&sd), &sd_expect[..], "case {case}: sector data");
                assert_eq!(header.dispatch, [header.node_count, 1, 1], "case {case}: cull dispatch args");
                assert_eq!(got.overflow, 0);
                if got.missing_roots == 0 {
                    assert_tiles_exactly_once(&got, &format!("case {case} {mode:?}"));
                }
                multi_checked += usize::from(mode == TraverseMode::MultiDispatch);
            }
            deepest = deepest.max(4 - expect.nodes.iter().map(|(n, _)| n.lod).min().unwrap_or(4));
        }
        assert!(deepest >= 3, "random cases should refine at least 3 levels, got {deepest}");
        assert_eq!(multi_checked, 100);
    });
}

#[test]
fn overflow_keeps_coarser_nodes_and_is_counted() {
    gpu_test(|ctx| {
        let mut scene = Scene::new(ctx, 7);
        // Everything resident down to LOD 1 so the walk wants many nodes.
        let w = world();
        for lod in (1..w.lod_count as u8).rev() {
            for n in w.nodes_at(lod) {
                scene.add(n);
            }
        }
        scene.mutate(ctx);
        let params = TraverseParams {
            cameras: vec![TraverseCamera::perspective([2000.0, 2000.0, 100.0], [0.0, 1.0, 0.0], 60.0, [2000, 2000])],
            target_error_px: 0.1,
        };
        let mut traverse = Traverse::with_per_level(ctx, &w, SLOTS).unwrap();
        let ample = traverse_cpu(&scene.tree.shadow, &w, &params);
        traverse.set_list_capacity(12);
        for mode in [TraverseMode::SingleDispatch, TraverseMode::MultiDispatch] {
            ctx.submit_and_wait(|rec| {
                traverse.record(rec, &scene.tree, &params, mode);
                Ok(())
            })
            .unwrap();
            let (_, got) = traverse.read_result(ctx).unwrap();
            assert!(got.overflow > 0, "{mode:?}: a 12-entry list must overflow");
            assert!(got.nodes.len() < ample.nodes.len(), "{mode:?}: overflow keeps coarser (fewer) nodes");
            assert_tiles_exactly_once(&got, &format!("{mode:?} with overflow"));
        }
    });
}

#[test]
fn roots_that_overflow_the_first_list_are_still_drawn() {
    gpu_test(|ctx| {
        // 32 x 31 sectors, 2^4 sectors per root side: 2 x 2 roots, all resident.
        const ROOTS: u32 = 4;
        const CAPACITY: u32 = 1;
        let mut scene = Scene::new(ctx, 11);
        scene.flush(ctx);
        assert_eq!(scene.resident.len(), ROOTS as usize);
        let params = TraverseParams {
            cameras: vec![TraverseCamera::perspective([2000.0, 2000.0, 100.0], [0.0, 1.0, 0.0], 60.0, [2000, 2000])],
            target_error_px: 1.0,
        };
        let mut traverse = Traverse::new(ctx, &world(), SLOTS).unwrap();
        traverse.set_list_capacity(CAPACITY);
        ctx.submit_and_wait(|rec| {
            traverse.record(rec, &scene.tree, &params, TraverseMode::SingleDispatch);
            Ok(())
        })
        .unwrap();
        let (header, got) = traverse.read_result(ctx).unwrap();
        assert_eq!(got.missing_roots, 0);
        assert_tiles_exactly_once(&got, "roots past a 1-entry list");
        // Only roots are resident, so nothing refines: every root is listed as itself.
        assert_eq!(got.nodes.len(), ROOTS as usize);
        assert_eq!(got.overflow, ROOTS - CAPACITY, "each root past the list is counted once");
        assert_eq!(header.dispatch, [ROOTS, 1, 1]);
    });
}

#[test]
fn sector_data_include_samples_the_same_height_as_the_cpu() {
    gpu_test(|ctx| {
        let w = world();
        let mut scene = Scene::new(ctx, 99);
        for _ in 0..30 {
            scene.mutate(ctx);
        }
        let sectors = SectorData::new(ctx, &w).unwrap();
        let mut query = TerrainQuery::new(ctx, 4096).unwrap();
        let mut rng = Rng(4242);
        let points: Vec<[f32; 2]> =
            (0..4096).map(|_| [rng.below(4_096_000) as f32 / 1000.0, rng.below(3_900_000) as f32 / 1000.0]).collect();
        ctx.submit_and_wait(|rec| {
            sectors.record(rec, &scene.tree);
            query.record(rec, VistaTerrain::new(&w, &sectors), &scene.tree, &sectors, &points)
        })
        .unwrap();
        // Payload heights per slot: the synthetic nodes are reproducible by id.
        let by_slot: std::collections::HashMap<u32, Vec<u16>> = scene
            .resident
            .iter()
            .filter_map(|id| scene.tree.shadow.slot_of(*id).map(|s| (s, scene.heights[id].clone())))
            .collect();
        let step = (w.height_range_m[1] - w.height_range_m[0]) / 65535.0;
        let answers = query.answers(points.len());
        let mut compared = 0;
        for (p, a) in points.iter().zip(&answers) {
            let cpu = sample_height_cpu(&scene.tree.shadow, &w, |s| &by_slot[&s], [f64::from(p[0]), f64::from(p[1])]);
            assert_eq!(a.is_some(), cpu.is_some(), "at {p:?}: GPU {a:?} vs CPU {cpu:?}");
            if let (Some(a), Some(h)) = (a, cpu) {
                assert!(
                    (a.height_m - h).abs() <= step,
                    "at {p:?}: GPU {} vs CPU {h} (one R16 step = {step})",
                    a.height_m
                );
                compared += 1;
            }
        }
        assert!(compared > 3000, "most points must hit resident nodes ({compared})");
    });
}

/// 10 LODs (MAX_NODE_LODS), 64 m sectors, 32 768 m roots: a 2 x 1 root
/// grid of which only root (0, 0) is resident, with one node of every finer
/// LOD at the origin and a few scattered ones. Most of the world is covered by
/// the root alone, the second root's half by nothing.
#[test]
fn sector_data_reaches_every_lod_of_a_10_lod_world_and_reports_uncovered_points() {
    gpu_test(|ctx| {
        let w = ten_lod_world();
        assert_eq!(w.lod_count, vista::shaders::consts::MAX_NODE_LODS);
        let root_m = w.node_size_m(w.root_lod());
        assert_eq!(w.roots(), [NodeId::new(9, 0, 0), NodeId::new(9, 1, 0)]);
        let mut tree = GpuQuadtree::new(ctx, &w, 64, 1, AtlasSet::ALL, PayloadFormat::Bc).unwrap();
        tree.shadow.set_reuse_delay(0);
        let update = QuadtreeUpdatePass::new(ctx, false).unwrap();
        let mut rng = Rng(1010);
        let resident = resident_of_every_lod(&w, root_m, &mut rng);
        let heights = upload_smooth_nodes(ctx, &mut tree, &update, &resident);
        let sectors = SectorData::new(ctx, &w).unwrap();
        let points = points_everywhere(&mut rng);
        let mut query = TerrainQuery::new(ctx, points.len() as u32).unwrap();
        ctx.submit_and_wait(|rec| {
            sectors.record(rec, &tree);
            query.record(rec, VistaTerrain::new(&w, &sectors), &tree, &sectors, &points)
        })
        .unwrap();
        let sd = ctx.read_buffer(sectors.buffer()).unwrap();
        let sd_expect: Vec<u32> = sector_data_cpu(&tree.shadow, &w).into_iter().flatten().collect();
        assert_eq!(bytemuck::cast_slice::<u8, u32>(&sd), &sd_expect[..], "sector data");
        let by_slot: std::collections::HashMap<u32, Vec<u16>> =
            resident.iter().map(|id| (tree.shadow.slot_of(*id).expect("uploaded"), heights[id].clone())).collect();
        let step = (w.height_range_m[1] - w.height_range_m[0]) / 65535.0;
        let mut finest_used = [0usize; 10];
        let answers = query.answers(points.len());
        for (p, a) in points.iter().zip(&answers) {
            let q = [f64::from(p[0]), f64::from(p[1])];
            // Derived from the layout alone: terrain only inside the extent
            // and under the resident root.
            let covered = (0.0..w.extent_m[0]).contains(&q[0]) && (0.0..w.extent_m[1]).contains(&q[1]) && q[0] < root_m;
            assert_eq!(a.is_some(), covered, "at {p:?}: GPU answer {a:?}");
            let cpu = sample_height_cpu(&tree.shadow, &w, |s| &by_slot[&s], q);
            assert_eq!(cpu.is_some(), covered, "at {p:?}: CPU reference {cpu:?}");
            if let (Some(a), Some(h)) = (a, cpu) {
                assert!(
                    (a.height_m - h).abs() <= step,
                    "at {p:?}: GPU {} vs CPU {h} (one R16 step = {step})",
                    a.height_m
                );
                let finest = (0..10u8).find(|l| w.node_at(*l, q[0], q[1]).is_some_and(|n| resident.contains(&n)));
                finest_used[finest.unwrap() as usize] += 1;
            }
        }
        assert!(finest_used[9] > 500, "points only the root covers: {finest_used:?}");
        assert!(finest_used.iter().all(|n| *n > 0), "every LOD answers some point: {finest_used:?}");
        assert!(answers.iter().filter(|a| a.is_none()).count() > 500, "points outside or uncovered");
    });
}

fn ten_lod_world() -> WorldDesc {
    WorldDesc {
        extent_m: [50_000.0, 30_000.0],
        height_range_m: [-50.0, 950.0],
        spacing_m: 0.5,
        lod_count: 10,
        ..WorldDesc::default()
    }
}

/// Root (0, 0), one node per LOD at the origin (sampling needs no whole
/// families) and one more at random per LOD 1..7 under that root.
fn resident_of_every_lod(w: &WorldDesc, root_m: f64, rng: &mut Rng) -> Vec<NodeId> {
    let mut resident = vec![NodeId::new(9, 0, 0)];
    resident.extend((0..9u8).map(|lod| NodeId::new(lod, 0, 0)));
    for lod in 1..7u8 {
        let cells = w.nodes_at(lod).into_iter().filter(|n| w.bounds_m(*n)[0] < root_m).collect::<Vec<_>>();
        let n = cells[rng.index(cells.len())];
        if !resident.contains(&n) {
            resident.push(n);
        }
    }
    resident
}

/// Adds `resident` to the tree and waits for the uploads; their heights.
fn upload_smooth_nodes(
    ctx: &Context,
    tree: &mut GpuQuadtree,
    update: &QuadtreeUpdatePass,
    resident: &[NodeId],
) -> std::collections::HashMap<NodeId, Vec<u16>> {
    // Smooth heights (a few R16 steps per sample), so f32 rounding of
    // the sample position moves the result by far less than a step.
    let mut heights = std::collections::HashMap::new();
    for (i, id) in resident.iter().enumerate() {
        let mut node = fake_node(*id, 0);
        let base = (i as u32 * 997) % 30_000;
        for (k, h) in node.heights.iter_mut().enumerate() {
            let (x, y) = ((k % vista::world::ATLAS_SIDE) as u32, (k / vista::world::ATLAS_SIDE) as u32);
            *h = (base + x * 97 + y * 61) as u16;
        }
        heights.insert(*id, node.heights.clone());
        tree.add(node, 0);
    }
    while tree.waiting() > 0 || tree.has_work() {
        ctx.submit_and_wait(|rec| update.record(rec, tree, None).map(drop)).unwrap();
    }
    heights
}

/// Points over the whole world and beyond it, and densely where the
/// fine LODs are.
fn points_everywhere(rng: &mut Rng) -> Vec<[f32; 2]> {
    let mut points: Vec<[f32; 2]> = Vec::new();
    for _ in 0..2000 {
        let u = [rng.unit(), rng.unit()];
        points.push([(u[0] * 60_000.0 - 5000.0) as f32, (u[1] * 40_000.0 - 5000.0) as f32]);
    }
    for span in [300.0, 5000.0, 30_000.0] {
        for _ in 0..500 {
            points.push([(rng.unit() * span) as f32, (rng.unit() * span) as f32]);
        }
    }
    points
}

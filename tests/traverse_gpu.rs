//! The GPU traversal (both variants) equals the CPU reference as a set for
//! random resident sets and cameras, tiles the world exactly once, and keeps
//! coarser nodes (counting overflow) when its lists are too small.

mod common;

use common::{fake_node, gpu_test, Rng};
use std::collections::BTreeSet;
use vista::gpu::Context;
use vista::gpu_quadtree::GpuQuadtree;
use vista::passes::quadtree_update::QuadtreeUpdatePass;
use vista::passes::traverse::{Traverse, TraverseMode};
use vista::traverse_cpu::{traverse_cpu, TraverseCamera, TraverseParams, TraverseResult};
use vista::world::{NodeId, WorldDesc};

/// 32 x 31 sectors of 128 m, 5 LODs: a 2x2 root grid with a partial row.
fn world() -> WorldDesc {
    WorldDesc { extent_m: [4096.0, 3900.0], height_range_m: [-50.0, 950.0], spacing_m: 1.0, lod_count: 5 }
}

const SLOTS: u32 = 400;

struct Scene {
    tree: GpuQuadtree,
    update: QuadtreeUpdatePass,
    resident: BTreeSet<NodeId>,
    rng: Rng,
}

impl Scene {
    fn new(ctx: &Context, seed: u64) -> Self {
        let mut s = Scene {
            tree: GpuQuadtree::new(ctx, &world(), SLOTS, 1).unwrap(),
            update: QuadtreeUpdatePass::new(ctx).unwrap(),
            resident: BTreeSet::new(),
            rng: Rng(seed),
        };
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
            ctx.submit_and_wait(|rec| self.update.record(rec, &mut self.tree)).unwrap();
            if self.tree.waiting() == 0 {
                break;
            }
        }
    }

    fn random_params(&mut self) -> TraverseParams {
        let w = world();
        let cams = 1 + self.rng.below(3) as usize;
        let cameras = (0..cams)
            .map(|_| {
                let p = [
                    self.rng.below(5000) as f64 - 450.0 + 0.37,
                    self.rng.below(5000) as f64 - 450.0 + 0.61,
                    self.rng.below(2000) as f64 - 100.0,
                ];
                TraverseCamera::perspective(p, 30.0 + self.rng.below(60) as f64, 256 + self.rng.below(1800))
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
        let traverse = Traverse::new(ctx, &world(), SLOTS).unwrap();
        let mut deepest = 0;
        let mut multi_checked = 0;
        for case in 0..1000 {
            scene.mutate(ctx);
            let params = scene.random_params();
            let modes: &[TraverseMode] = if case % 10 == 0 {
                &[TraverseMode::SingleDispatch, TraverseMode::MultiDispatch]
            } else {
                &[TraverseMode::SingleDispatch]
            };
            let expect = traverse_cpu(&scene.tree.shadow, &world(), &params);
            for &mode in modes {
                ctx.submit_and_wait(|rec| {
                    traverse.record(rec, &scene.tree, &params, mode);
                    Ok(())
                })
                .unwrap();
                let (header, got) = traverse.read_result(ctx).unwrap();
                assert_eq!(got, expect, "case {case} {mode:?}: GPU list differs from the CPU reference");
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
            cameras: vec![TraverseCamera::perspective([2000.0, 2000.0, 100.0], 60.0, 2000)],
            target_error_px: 0.1,
        };
        let mut traverse = Traverse::new(ctx, &w, SLOTS).unwrap();
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

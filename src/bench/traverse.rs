//! `vista bench traverse`: one-dispatch vs per-level traversal; GPU times from the frame executor's
//! timestamps, medians over frames after warm-up, variants timed in the same
//! frames so their ratio is measured under the same conditions.

use crate::error::Result;
use crate::frame::profiler::summarize;
use crate::frame::{FrameExecutor, QueueKind};
use crate::gpu::{Context, FrameRing};
use crate::passes::quadtree_update::QuadtreeUpdatePass;
use crate::passes::traverse::{Traverse, TraverseMode};
use crate::terrain::gpu_quadtree::{AtlasSet, GpuQuadtree};
use crate::terrain::selection::{TraverseCamera, TraverseParams};
use crate::world::{bake_node, ErrorTree, HeightSource, NodeId, PayloadFormat, WorldDesc};
use rayon::prelude::*;
use serde::Serialize;
use std::sync::Arc;

#[derive(Debug, Clone, Serialize)]
pub struct TraverseBenchRow {
    /// Nodes resident (asked for `requested`; a small world may have fewer).
    pub requested: u32,
    pub resident: u32,
    pub target_error_px: f32,
    /// Nodes in the final list.
    pub final_nodes: u32,
    pub single_dispatch_ms: f64,
    pub multi_dispatch_ms: f64,
    /// single / multi: below 1 means the one-dispatch walk is faster.
    pub ratio: f64,
}

/// The benchmark camera looks north and 20 degrees down, as the default view.
const BENCH_FORWARD: [f64; 3] = [0.0, 0.939_692_620_785_908_4, -0.342_020_143_325_668_7];

pub struct TraverseBenchConfig {
    pub resident_sets: Vec<u32>,
    pub targets_px: Vec<f32>,
    pub warmup_frames: u32,
    pub frames: u32,
    pub camera_m: [f64; 3],
    pub viewport_height_px: u32,
    /// The world's error tree (`None`: made here, in memory).
    pub errors: Option<Arc<ErrorTree>>,
}

/// `n` nodes around `camera` as a streaming camera would hold them: the
/// roots, then whole child families (the traversal refines a node only when
/// all its valid children are resident), nearest node first.
fn resident_set(world: &WorldDesc, camera: [f64; 3], n: u32) -> Vec<NodeId> {
    let dist = |id: &NodeId| {
        let b = world.bounds_m(*id);
        let dx = (b[0] - camera[0]).max(camera[0] - b[2]).max(0.0);
        let dy = (b[1] - camera[1]).max(camera[1] - b[3]).max(0.0);
        dx.hypot(dy)
    };
    let mut set: Vec<NodeId> = world.roots();
    let mut frontier: Vec<NodeId> = set.clone();
    loop {
        frontier.retain(|id| id.lod > 0);
        frontier.sort_by(|a, b| dist(b).total_cmp(&dist(a)));
        let Some(next) = frontier.pop() else { break };
        let kids = world.valid_children(next);
        if set.len() + kids.len() > n as usize {
            break;
        }
        set.extend(kids.iter().copied());
        frontier.extend(kids);
    }
    set
}

/// A GPU quadtree holding `ids`, baked (with their errors) and uploaded.
fn resident_tree(
    ctx: &Context,
    world: &WorldDesc,
    source: &dyn HeightSource,
    errors: &ErrorTree,
    update: &QuadtreeUpdatePass,
    ids: &[NodeId],
    slots: u32,
) -> Result<GpuQuadtree> {
    let nodes = ids
        .par_iter()
        .map(|id| {
            let mut node = bake_node(source, world, &[], *id);
            errors.attach(&mut node)?;
            Ok(node)
        })
        .collect::<std::result::Result<Vec<_>, crate::world::WorldError>>()?;
    let mut tree = GpuQuadtree::new(ctx, world, slots, 1, AtlasSet::CORE, PayloadFormat::Bc)?;
    for n in nodes {
        tree.add(n, 0);
    }
    while tree.waiting() > 0 {
        ctx.submit_and_wait(|rec| update.record(rec, &mut tree, None).map(drop))?;
    }
    Ok(tree)
}

pub fn bench_traverse(
    ctx: &Context,
    world: &WorldDesc,
    source: Arc<dyn HeightSource>,
    cfg: &TraverseBenchConfig,
) -> Result<Vec<TraverseBenchRow>> {
    let errors = match &cfg.errors {
        Some(e) => Arc::clone(e),
        None => Arc::new(ErrorTree::new(world, Arc::clone(&source), None)?),
    };
    let max = cfg.resident_sets.iter().copied().max().unwrap_or(64);
    let update = QuadtreeUpdatePass::new(ctx, false)?;
    let traverse = Traverse::with_per_level(ctx, world, max)?;
    let mut ring = FrameRing::new(ctx, 1)?;
    let mut rows = Vec::new();
    for &requested in &cfg.resident_sets {
        let ids = resident_set(world, cfg.camera_m, requested);
        log::info!("baking {} nodes for the {requested}-node resident set", ids.len());
        let tree = resident_tree(ctx, world, &*source, &errors, &update, &ids, max)?;
        let resident = tree.shadow.resident_count();
        for &target in &cfg.targets_px {
            let params = TraverseParams {
                cameras: vec![TraverseCamera::perspective(
                    cfg.camera_m,
                    BENCH_FORWARD,
                    60.0,
                    [cfg.viewport_height_px, cfg.viewport_height_px],
                )],
                target_error_px: target,
            };
            let mut exec = FrameExecutor::new(ctx, 1, 4, false)?;
            let mut frames = Vec::new();
            for _ in 0..cfg.warmup_frames + cfg.frames + 1 {
                ring.record(ctx, |rec| {
                    let mut frame = exec.begin(crate::gpu::FrameCommands::One(rec), crate::gpu::QueueMode::Single);
                    frame.pass(Traverse::NAME, false, QueueKind::Compute, |r| {
                        traverse.record(r, &tree, &params, TraverseMode::SingleDispatch)
                    });
                    frame.pass(Traverse::LEVEL_NAME, false, QueueKind::Compute, |r| {
                        traverse.record(r, &tree, &params, TraverseMode::MultiDispatch)
                    });
                    Ok(())
                })?;
                ring.wait_all(ctx)?;
                if let Some(t) = exec.latest() {
                    if t.frame > u64::from(cfg.warmup_frames)
                        && frames.last().is_none_or(|l: &crate::frame::FrameTimings| l.frame < t.frame)
                    {
                        frames.push(t.clone());
                    }
                }
            }
            let s = summarize(&frames);
            let ms = |name| s.iter().find(|p| p.name == name).map_or(f64::NAN, |p| p.median_ms);
            let (single, multi) = (ms(Traverse::NAME), ms(Traverse::LEVEL_NAME));
            let (_, result) = traverse.read_result(ctx)?;
            rows.push(TraverseBenchRow {
                requested,
                resident,
                target_error_px: target,
                final_nodes: result.nodes.len() as u32,
                single_dispatch_ms: single,
                multi_dispatch_ms: multi,
                ratio: single / multi,
            });
        }
    }
    Ok(rows)
}

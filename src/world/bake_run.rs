//! Whole bakes: every node of a region, or of one shard, into a cache
//! folder, each root's error tile first.

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use rayon::prelude::*;

use super::bake::BakeSettings;
use super::cache::{CacheOutcome, MissReason, NodeCache};
use super::error::Result;
use super::errors::PreparedErrors;
use super::holes::Hole;
use super::layout::{NodeId, WorldDesc};
use super::plan::{Limits, WorldPlan};
use super::progress::{Progress, Reporter, Work};
use super::shard::ShardSplit;
use super::source::HeightSource;

/// Valid nodes of every LOD overlapping `region` ([min x, min y, max x,
/// max y] metres; `None` = everything), coarsest LOD first.
pub fn nodes_in_region(world: &WorldDesc, region: Option<[f64; 4]>) -> Vec<NodeId> {
    let mut out = Vec::new();
    for lod in (0..world.lod_count as u8).rev() {
        let s = world.node_size_m(lod);
        let [gx, gy] = world.grid(lod);
        let (x0, y0, x1, y1) = match region {
            None => (0, 0, gx, gy),
            Some(r) => {
                let [ox, oy] = world.grid_origin_m;
                let cell = |v: f64, o: f64, g: u32| (((v - o) / s).floor().max(0.0) as u32).min(g);
                let end = |v: f64, o: f64, g: u32| (((v - o) / s).ceil().max(0.0) as u32).min(g);
                (cell(r[0], ox, gx), cell(r[1], oy, gy), end(r[2], ox, gx), end(r[3], oy, gy))
            }
        };
        for y in y0..y1 {
            for x in x0..x1 {
                out.push(NodeId::new(lod, x, y));
            }
        }
    }
    out
}

/// One node file as a bake left it: what a shard's manifest lists.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NodeFile {
    pub id: NodeId,
    pub bytes: u64,
    /// The file's own trailing crc32 (of every byte before it).
    pub crc32: u32,
}

/// What a [`bake_world`] run did.
#[derive(Clone, Debug, Default)]
pub struct BakeStats {
    /// Nodes per LOD (index = LOD).
    pub nodes_per_lod: Vec<usize>,
    /// Nodes baked now; the rest came from the cache.
    pub baked: usize,
    /// Of those, nodes whose file was there but stale (made from other
    /// inputs over its area: an edit touched it) or damaged.
    pub rebaked: usize,
    pub cached: usize,
    pub seconds: f64,
    /// Bytes of the node files of this region on disk.
    pub bytes_on_disk: u64,
    /// The error tree of the roots over the region, made before the nodes
    /// (its seconds are not in `seconds`).
    pub errors: PreparedErrors,
    /// LOD-0 quads under those roots, inside the world: what the error
    /// tree's time scales with.
    pub error_quads: u64,
    /// Every node file, in bake order.
    pub files: Vec<NodeFile>,
}

/// Bakes (or validates from cache) every valid node of every LOD
/// overlapping `region` into `cache_dir`, in parallel.
pub fn bake_world(
    source: Arc<dyn HeightSource>,
    world: &WorldDesc,
    holes: &[Hole],
    settings: &BakeSettings,
    region: Option<[f64; 4]>,
    cache_dir: &Path,
    progress: impl Into<Progress>,
) -> Result<BakeStats> {
    let cache = NodeCache::with_settings(cache_dir, *world, source, holes.to_vec(), settings.clone())?;
    // Before the node list, which grows with the world.
    let plan = WorldPlan::new(world, region);
    plan.check(&Limits::default())?;
    let nodes = nodes_in_region(world, region);
    let roots: Vec<NodeId> = nodes.iter().filter(|n| n.lod == world.root_lod()).copied().collect();
    let mut stats = bake_nodes(&cache, &nodes, roots, progress.into())?;
    stats.error_quads = plan.error_quads;
    Ok(stats)
}

/// Bakes (or validates from cache) the nodes of shard `index` of `split`
/// into `cache_dir`: the error tiles of the roots it touches, then its
/// nodes. Shards of one split baked into one folder, one after another or
/// all at once, leave the same files as [`bake_world`] of the whole world.
#[allow(clippy::too_many_arguments)]
pub fn bake_shard(
    source: Arc<dyn HeightSource>,
    world: &WorldDesc,
    holes: &[Hole],
    settings: &BakeSettings,
    split: &ShardSplit,
    index: u32,
    cache_dir: &Path,
    progress: impl Into<Progress>,
) -> Result<BakeStats> {
    assert_eq!(split.world(), world, "a split of another world");
    split.check_index(index).map_err(|e| super::WorldError::InvalidConfig(e.to_string()))?;
    let cache = NodeCache::with_settings(cache_dir, *world, source, holes.to_vec(), settings.clone())?;
    WorldPlan::new(world, None).check(&Limits::default())?;
    let nodes = split.nodes(index);
    let mut stats = bake_nodes(&cache, &nodes, split.tiles(index), progress.into())?;
    stats.error_quads = split.error_quads(index) as u64;
    Ok(stats)
}

/// The error tiles of `tiles`, then `nodes` in parallel.
fn bake_nodes(cache: &NodeCache, nodes: &[NodeId], tiles: Vec<NodeId>, progress: Progress) -> Result<BakeStats> {
    // Each root's error tile first, so node bakes never wait for one.
    let errors = cache.errors().prepare_tiles(tiles, progress.clone());
    let start = Instant::now();
    let bar = Reporter::new(progress, nodes.len() as u64, Work::Nodes);
    let outcomes = nodes
        .par_iter()
        .map(|&id| {
            let (_, outcome) = cache.get_or_bake(id)?;
            bar.inc();
            let (bytes, crc32) = cache.file_summary(id)?;
            Ok((NodeFile { id, bytes, crc32 }, outcome))
        })
        .collect::<Result<Vec<_>>>()?;
    bar.finish();
    let world = cache.world();
    let mut stats = BakeStats { nodes_per_lod: vec![0; world.lod_count as usize], errors, ..BakeStats::default() };
    for (file, outcome) in outcomes {
        stats.nodes_per_lod[file.id.lod as usize] += 1;
        stats.bytes_on_disk += file.bytes;
        match outcome {
            CacheOutcome::Hit => stats.cached += 1,
            CacheOutcome::Baked(reason) => {
                stats.baked += 1;
                stats.rebaked += usize::from(reason != MissReason::Missing);
            }
        }
        stats.files.push(file);
    }
    stats.seconds = start.elapsed().as_secs_f64();
    Ok(stats)
}

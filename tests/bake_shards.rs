//! The shard split of `vista bake --shard I/N`: the N shards partition the
//! world's nodes exactly, each holds the roots its nodes need (no shard
//! reads another's output), and their estimated costs are balanced. No GPU.

use std::collections::HashSet;

use std::sync::Arc;

use vista::world::{
    nodes_in_region, ErrorTree, NodeId, ProceduralSource, Progress, ShardSplit, WorldDesc, WorldPlan, UNITS_PER_SHARD,
};

fn world(extent: [f64; 2], spacing: f64, lods: u32) -> WorldDesc {
    WorldDesc { extent_m: extent, spacing_m: spacing, lod_count: lods, ..WorldDesc::default() }
}

fn root_of(w: &WorldDesc, id: NodeId) -> NodeId {
    let k = w.root_lod() - id.lod;
    NodeId::new(w.root_lod(), id.x >> k, id.y >> k)
}

#[test]
fn shards_partition_the_nodes_exactly() {
    // The default world (5 x 5 roots), a single root, a world whose edge
    // cells are partial (3 000 m at 2 m: 12 sectors of 256 m, grids 12, 6,
    // 3, 2, 1), and a wide one with 2 x 1 roots.
    let worlds = [
        WorldDesc::default(),
        world([2048.0; 2], 2.0, 4),
        world([3000.0; 2], 2.0, 5),
        world([60_000.0, 30_000.0], 8.0, 6),
    ];
    for w in worlds {
        let all: HashSet<NodeId> = nodes_in_region(&w, None).into_iter().collect();
        for n in [1, 2, 3, 7, 64] {
            let split = ShardSplit::new(&w, n).unwrap();
            let (mut seen, mut owners) = (HashSet::new(), HashSet::new());
            for i in 0..n {
                let tiles: HashSet<NodeId> = split.tiles(i).into_iter().collect();
                let s = split.split_lod();
                for id in split.nodes(i) {
                    assert!(all.contains(&id), "{w:?}/{n}: shard {i} has {id}, not a node of the world");
                    assert!(seen.insert(id), "{w:?}/{n}: {id} is in two shards");
                    assert_eq!(split.shard_of(id), i, "{w:?}/{n}: shard_of({id})");
                    // Its error tile is made by the shard itself: its root's,
                    // or (at or below the split level) its unit's.
                    let unit = (id.lod <= s).then(|| NodeId::new(s, id.x >> (s - id.lod), id.y >> (s - id.lod)));
                    let own = tiles.contains(&root_of(&w, id)) || unit.is_some_and(|u| tiles.contains(&u));
                    assert!(own, "{w:?}/{n}: shard {i} makes no tile holding {id}");
                }
                // Each root is owned (its whole tile made) by exactly one shard.
                for t in tiles.iter().filter(|t| t.lod == w.root_lod()) {
                    assert!(owners.insert(*t), "{w:?}/{n}: two shards own {t}");
                }
                let plan = split.shard_plan(i, &WorldPlan::new(&w, None));
                assert_eq!(plan.nodes() as usize, split.nodes(i).len(), "{w:?}/{n}: shard {i}'s counted nodes");
                assert!(plan.nodes_per_lod[0] > 0, "{w:?}/{n}: shard {i} has no LOD-0 node");
            }
            assert_eq!(seen.len(), all.len(), "{w:?}/{n}: nodes missing from every shard");
            assert_eq!(owners.len(), w.roots().len(), "{w:?}/{n}: roots no shard owns");
        }
    }
}

#[test]
fn the_split_is_deterministic_and_compact() {
    let w = WorldDesc::default();
    for n in [2, 7, 64] {
        let (a, b) = (ShardSplit::new(&w, n).unwrap(), ShardSplit::new(&w, n).unwrap());
        for i in 0..n {
            assert_eq!(a.nodes(i), b.nodes(i), "{n}: shard {i} differs between two splits");
            // Contiguous runs of a root-major order: a shard owns at most
            // one root beyond its share of them.
            let owned = a.tiles(i).iter().filter(|t| t.lod == w.root_lod()).count() as u32;
            assert!(owned <= 25u32.div_ceil(n) + 1, "{n}: shard {i} owns {owned} roots");
        }
        // The split level has at least UNITS_PER_SHARD cells per shard.
        let g = w.grid(a.split_lod());
        assert!(u64::from(g[0]) * u64::from(g[1]) >= UNITS_PER_SHARD * u64::from(n), "{n}: LOD {}", a.split_lod());
    }
}

#[test]
fn estimated_costs_are_within_15_percent_for_up_to_8_shards() {
    let w = WorldDesc::default();
    let plan = WorldPlan::new(&w, None);
    for n in 1..=8 {
        let split = ShardSplit::new(&w, n).unwrap();
        let costs: Vec<f64> = (0..n).map(|i| split.shard_plan(i, &plan).thread_seconds()).collect();
        let (lo, hi) = costs.iter().fold((f64::MAX, 0f64), |(lo, hi), &c| (lo.min(c), hi.max(c)));
        assert!(hi <= 1.15 * lo, "{n} shards: estimated thread seconds {costs:?}");
        // Each shard pays for the error tiles of every root it touches, so
        // the sum is at least the whole bake's estimate.
        let whole = plan.nodes() as f64 * plan.node_seconds + plan.error_quads as f64 * plan.error_quad_seconds;
        let sum: f64 = costs.iter().sum();
        assert!(sum >= whole * (1.0 - 1e-9), "{n}: {sum} < {whole}");
    }
}

#[test]
fn bad_counts_are_refused_in_the_users_terms() {
    let w = world([2048.0; 2], 2.0, 4);
    for (n, says) in [(0, "1 to"), (65, "only 64 LOD-0 nodes"), (20_000, "1 to")] {
        let e = ShardSplit::new(&w, n).unwrap_err().to_string();
        assert!(e.contains(says) && e.lines().count() == 1, "{n}: {e}");
    }
    let split = ShardSplit::new(&w, 4).unwrap();
    assert!(split.check_index(3).is_ok());
    let e = split.check_index(4).unwrap_err().to_string();
    assert!(e.contains("4/4") && e.contains("0-based"), "{e}");
}

/// A shard's tile of a unit in a root it does not own holds the very
/// numbers of the root's tile there: the shards' node files are then the
/// single bake's, byte for byte.
#[test]
fn a_units_tile_equals_its_roots_tile_there() {
    // 2 048 m at 2 m, 4 LODs: one root of 8 x 8 LOD-0 nodes; 4 096 m with
    // a partial edge (3 000 m) for units cut by the world's edge.
    for w in [world([2048.0; 2], 2.0, 4), world([3000.0, 2600.0], 2.0, 5)] {
        let source = Arc::new(ProceduralSource::new(7, w.extent_m, w.height_range_m).unwrap());
        let whole = ErrorTree::new(&w, source.clone(), None).unwrap();
        for lod in 0..w.root_lod() {
            let [gx, gy] = w.grid(lod);
            let unit = NodeId::new(lod, gx - 1, gy / 2);
            let part = ErrorTree::new(&w, source.clone(), None).unwrap();
            let made = part.prepare_tiles(vec![unit], Progress::Hidden);
            assert_eq!((made.roots, made.below_roots), (0, 1));
            for l in 0..=lod {
                let k = lod - l;
                for y in unit.y << k..((unit.y + 1) << k).min(w.grid(l)[1]) {
                    for x in unit.x << k..((unit.x + 1) << k).min(w.grid(l)[0]) {
                        let id = NodeId::new(l, x, y);
                        assert_eq!(part.node(id).unwrap(), whole.node(id).unwrap(), "{w:?}: {id} under {unit}");
                    }
                }
            }
        }
    }
}

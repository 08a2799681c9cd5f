//! A world's bake split into N shards that batch schedulers run as N
//! independent processes (a Slurm job array, a Kubernetes Indexed Job),
//! writing into one cache layout with no merge step.
//!
//! The unit of work is the subtree under a cell of one level, the *split
//! level*: the coarsest level with at least [`UNITS_PER_SHARD`] cells per
//! shard, so that whole units balance the shards within a few percent.
//! A node at or below the split level belongs to the unit above it; a node
//! above it to the first unit of its root, the one at the root's
//! south-west corner. Units are ordered root by root (row by row), in
//! Morton order inside a root, and each shard takes a contiguous run of
//! them: a shard is a compact piece of the map and shares at most its
//! first and last root with its neighbours.
//!
//! No shard reads another's output: a node's bake reads only the source,
//! and its errors come from an error tile the shard makes itself. The
//! shard holding a root's first unit *owns* the root: it holds the root's
//! coarse nodes, whose numbers need every LOD-0 sample of the root, so it
//! makes the root's whole tile (cached under `DIR/errors` as in any bake).
//! A shard holding later units of a root it does not own makes, per unit,
//! the unit's own tile: levels 0 up to the split level over the unit's
//! area, the same numbers the root's tile holds there (the tree's blocks
//! are aligned to units and a patch's numbers depend only on what lies
//! under it), kept in memory. That part of a root is thus computed twice,
//! by its owner and by the other shard, and the split counts it in the
//! shards' estimated costs ([`ShardPlan::unit_tiles`]).
//!
//! Everything here is arithmetic over units (at most a few hundred per
//! shard), never a list of the world's nodes: a continent's 28 M nodes are
//! split in milliseconds.

use std::fmt;

use super::cache::estimated_file_bytes;
use super::layout::{NodeId, WorldDesc, NODE_QUADS};
use super::plan::WorldPlan;

/// Units per shard the split level is chosen for: a shard's estimated cost
/// is within one unit of its share, so 32 keeps whole-unit rounding near
/// 3 % of a shard.
pub const UNITS_PER_SHARD: u64 = 32;
/// The most shards a world is split into (Kubernetes caps an Indexed Job at
/// 100 000 completions; Slurm's default `MaxArraySize` is 1 001).
pub const MAX_SHARDS: u32 = 10_000;

/// Why a split was refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ShardError {
    #[error("--shard {index}/{count}: the index must be below the shard count (0-based, as Slurm and Kubernetes number tasks)")]
    IndexOutOfRange { index: u32, count: u32 },
    #[error("--shard .../{count}: the shard count must be 1 to {max}")]
    BadCount { count: u32, max: u32 },
    #[error("--shard .../{count}: the world has only {lod0} LOD-0 nodes, fewer than the shards")]
    FewerNodesThanShards { count: u32, lod0: u64 },
}

/// One shard's part of a world.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ShardPlan {
    pub index: u32,
    pub count: u32,
    /// Its units: cells of the split level, with everything under them.
    pub units: u64,
    pub nodes_per_lod: Vec<u64>,
    /// Estimated node file bytes.
    pub disk_bytes: u64,
    /// Roots it owns: it makes their whole error tiles.
    pub roots: u64,
    /// Its units in roots another shard owns: it makes their own tiles
    /// (levels 0 up to the split level), work the owner does too.
    pub unit_tiles: u64,
    /// Estimated single-thread seconds of its nodes and of its error tiles.
    pub node_thread_seconds: f64,
    pub error_thread_seconds: f64,
    /// Threads the wall-time estimate assumes (the plan's).
    pub threads: usize,
}

impl ShardPlan {
    pub fn nodes(&self) -> u64 {
        self.nodes_per_lod.iter().sum()
    }

    pub fn thread_seconds(&self) -> f64 {
        self.node_thread_seconds + self.error_thread_seconds
    }

    /// Estimated wall seconds on the plan's threads.
    pub fn seconds(&self) -> f64 {
        self.thread_seconds() / self.threads.max(1) as f64
    }
}

/// The split of a world into `count` shards.
#[derive(Clone, Debug)]
pub struct ShardSplit {
    world: WorldDesc,
    count: u32,
    split_lod: u8,
    /// Units in shard order (see the module docs).
    units: Vec<NodeId>,
    /// Per unit, the index of its root's first unit.
    first_of_root: Vec<usize>,
    /// Shard `i` holds `units[starts[i]..starts[i + 1]]`.
    starts: Vec<usize>,
}

impl ShardSplit {
    /// Splits `world` (valid) into `count` shards, weighing units by the
    /// built-in per-node and per-quad constants ([`WorldPlan::new`]), never
    /// by timings: every process of a job array must compute the same split.
    pub fn new(world: &WorldDesc, count: u32) -> Result<Self, ShardError> {
        if count == 0 || count > MAX_SHARDS {
            return Err(ShardError::BadCount { count, max: MAX_SHARDS });
        }
        let plan = WorldPlan::new(world, None);
        let lod0 = plan.nodes_per_lod[0];
        if u64::from(count) > lod0 {
            return Err(ShardError::FewerNodesThanShards { count, lod0 });
        }
        let cells = |l: u8| world.grid(l).iter().map(|&g| u64::from(g)).product::<u64>();
        let want = u64::from(count) * UNITS_PER_SHARD;
        let split_lod = (0..=world.root_lod()).rev().find(|&l| cells(l) >= want).unwrap_or(0);
        let units = ordered_units(world, split_lod);
        let mut split =
            ShardSplit { world: *world, count, split_lod, units, first_of_root: Vec::new(), starts: Vec::new() };
        for i in 0..split.units.len() {
            let same = i > 0 && split.root_of(split.units[i - 1]) == split.root_of(split.units[i]);
            let first = if same { split.first_of_root[i - 1] } else { i };
            split.first_of_root.push(first);
        }
        split.starts = split.balance(&plan);
        Ok(split)
    }

    pub fn count(&self) -> u32 {
        self.count
    }

    pub fn split_lod(&self) -> u8 {
        self.split_lod
    }

    pub fn world(&self) -> &WorldDesc {
        &self.world
    }

    /// Shard `index`'s units as a range of the split's unit order.
    pub fn unit_range(&self, index: u32) -> [usize; 2] {
        [self.starts[index as usize], self.starts[index as usize + 1]]
    }

    /// Checks `index` against the count.
    pub fn check_index(&self, index: u32) -> Result<(), ShardError> {
        if index >= self.count {
            return Err(ShardError::IndexOutOfRange { index, count: self.count });
        }
        Ok(())
    }

    /// The shard a valid node belongs to.
    pub fn shard_of(&self, id: NodeId) -> u32 {
        assert!(self.world.is_valid(id), "{id} is not a node of the world");
        let s = self.split_lod;
        let unit = if id.lod <= s {
            NodeId::new(s, id.x >> (s - id.lod), id.y >> (s - id.lod))
        } else {
            let r = self.world.root_lod();
            NodeId::new(s, (id.x >> (r - id.lod)) << (r - s), (id.y >> (r - id.lod)) << (r - s))
        };
        let key = order_key(&self.world, s, unit);
        let pos = self.units.partition_point(|u| order_key(&self.world, s, *u) < key);
        debug_assert_eq!(self.units[pos], unit);
        (self.starts.partition_point(|&st| st <= pos) - 1) as u32
    }

    /// Every node of shard `index`, coarse levels first (as a whole bake
    /// lists them). Panics on an index out of range ([`Self::check_index`]).
    pub fn nodes(&self, index: u32) -> Vec<NodeId> {
        let mut out = Vec::new();
        for lod in (0..self.world.lod_count as u8).rev() {
            for &u in self.shard_units(index) {
                self.unit_nodes_at(u, lod, |id| out.push(id));
            }
        }
        out
    }

    /// The error tiles shard `index` makes before its nodes: the roots it
    /// owns, and its units in roots it does not (see the module docs).
    pub fn tiles(&self, index: u32) -> Vec<NodeId> {
        let [a, b] = self.unit_range(index);
        (a..b)
            .filter_map(|i| match self.first_of_root[i] {
                first if first == i => Some(self.root_of(self.units[i])),
                first if first < a => Some(self.units[i]),
                _ => None,
            })
            .collect()
    }

    /// LOD-0 quads the tiles of shard `index` cover, each counted for the
    /// levels it holds (a unit's tile holds fewer than its root's): what
    /// its error tiles cost, in quads of whole tiles.
    pub fn error_quads(&self, index: u32) -> f64 {
        let root_levels = f64::from(self.world.lod_count);
        self.tiles(index).iter().map(|t| self.node_quads(*t) as f64 * (f64::from(t.lod) + 1.0) / root_levels).sum()
    }

    /// Shard `index`'s figures, its times from `plan`'s per-node and
    /// per-quad estimates (measured or not).
    pub fn shard_plan(&self, index: u32, plan: &WorldPlan) -> ShardPlan {
        let p = plan;
        let mut nodes_per_lod = vec![0u64; self.world.lod_count as usize];
        for &u in self.shard_units(index) {
            for (lod, n) in nodes_per_lod.iter_mut().enumerate() {
                *n += self.unit_count_at(u, lod as u8);
            }
        }
        let tiles = self.tiles(index);
        let roots = tiles.iter().filter(|t| t.lod == self.world.root_lod()).count() as u64;
        let nodes: u64 = nodes_per_lod.iter().sum();
        ShardPlan {
            index,
            count: self.count,
            units: self.shard_units(index).len() as u64,
            disk_bytes: nodes * estimated_file_bytes(p.format),
            roots,
            unit_tiles: tiles.len() as u64 - roots,
            node_thread_seconds: nodes as f64 * p.node_seconds,
            error_thread_seconds: self.error_quads(index) * p.error_quad_seconds,
            nodes_per_lod,
            threads: p.threads,
        }
    }

    fn shard_units(&self, index: u32) -> &[NodeId] {
        &self.units[self.starts[index as usize]..self.starts[index as usize + 1]]
    }

    fn root_of(&self, unit: NodeId) -> NodeId {
        let shift = self.world.root_lod() - unit.lod;
        NodeId::new(self.world.root_lod(), unit.x >> shift, unit.y >> shift)
    }

    /// The cells at `lod` a unit holds, as a clipped rectangle: under it at
    /// or below the split level; above it, every cell of its root if it is
    /// the root's first unit, else none.
    fn unit_cells(&self, u: NodeId, lod: u8) -> [u32; 4] {
        let [gx, gy] = self.world.grid(lod);
        if lod <= u.lod {
            let k = u.lod - lod;
            [u.x << k, u.y << k, ((u.x + 1) << k).min(gx), ((u.y + 1) << k).min(gy)]
        } else {
            // The root's first unit holds every coarser node of the root.
            let r = self.world.root_lod() - u.lod;
            if !(u.x.is_multiple_of(1 << r) && u.y.is_multiple_of(1 << r)) {
                return [0; 4];
            }
            let (root, k) = (self.root_of(u), self.world.root_lod() - lod);
            [root.x << k, root.y << k, ((root.x + 1) << k).min(gx), ((root.y + 1) << k).min(gy)]
        }
    }

    fn unit_count_at(&self, u: NodeId, lod: u8) -> u64 {
        let [x0, y0, x1, y1] = self.unit_cells(u, lod);
        u64::from(x1 - x0) * u64::from(y1 - y0)
    }

    fn unit_nodes_at(&self, u: NodeId, lod: u8, mut f: impl FnMut(NodeId)) {
        let [x0, y0, x1, y1] = self.unit_cells(u, lod);
        for y in y0..y1 {
            for x in x0..x1 {
                f(NodeId::new(lod, x, y));
            }
        }
    }

    /// LOD-0 quads under a node inside the world: what its error tile
    /// costs per level.
    fn node_quads(&self, root: NodeId) -> u64 {
        let [sx, sy] = self.world.sectors().map(u64::from);
        let r = u32::from(root.lod);
        let span = |c: u32, s: u64| ((u64::from(c + 1) << r).min(s)).saturating_sub(u64::from(c) << r);
        span(root.x, sx) * span(root.y, sy) * u64::from(NODE_QUADS).pow(2)
    }

    /// Shard starts: each shard takes units until its cost is nearest its
    /// share of what is left. A unit costs its nodes, plus its root's whole
    /// error tile if it is the root's first unit, plus its own tile if its
    /// root's owner is another shard; the shares include the unit tiles
    /// the later cuts are expected to add, found by iterating until the
    /// split stops changing.
    fn balance(&self, p: &WorldPlan) -> Vec<usize> {
        let levels = f64::from(self.world.lod_count);
        let unit_levels = (f64::from(self.split_lod) + 1.0) / levels;
        let n = self.units.len();
        let mut costs = Costs {
            node: Vec::with_capacity(n),
            root_tile: Vec::with_capacity(n),
            unit_tile: Vec::with_capacity(n),
            first_of_root: self.first_of_root.clone(),
            suffix: vec![0.0; n + 1],
            root_rest: vec![0.0; n + 1],
        };
        for (i, &u) in self.units.iter().enumerate() {
            let nodes: u64 = (0..self.world.lod_count as u8).map(|l| self.unit_count_at(u, l)).sum();
            costs.node.push(nodes as f64 * p.node_seconds);
            let first = self.first_of_root[i] == i;
            let root = self.node_quads(self.root_of(u)) as f64 * p.error_quad_seconds;
            costs.root_tile.push(if first { root } else { 0.0 });
            costs.unit_tile.push(self.node_quads(u) as f64 * unit_levels * p.error_quad_seconds);
        }
        for i in (0..n).rev() {
            costs.suffix[i] = costs.suffix[i + 1] + costs.node[i] + costs.root_tile[i];
            let same_root = i + 1 < n && self.first_of_root[i + 1] == self.first_of_root[i];
            costs.root_rest[i] = costs.unit_tile[i] + if same_root { costs.root_rest[i + 1] } else { 0.0 };
        }
        let mut overhead = 0.0;
        let mut starts = costs.cut(self.count as usize, overhead);
        for _ in 0..16 {
            let duplicated = costs.total(&starts) - costs.rest(0);
            overhead = duplicated / f64::from(self.count - 1).max(1.0);
            let next = costs.cut(self.count as usize, overhead);
            if next == starts {
                break;
            }
            starts = next;
        }
        starts
    }
}

/// Per unit: its nodes' cost, its root's whole tile (on the root's first
/// unit, else 0) and its own tile (paid where another shard owns the root).
struct Costs {
    node: Vec<f64>,
    root_tile: Vec<f64>,
    unit_tile: Vec<f64>,
    first_of_root: Vec<usize>,
    /// Nodes and whole root tiles of units i..
    suffix: Vec<f64>,
    /// Unit tiles of units i.. in unit i's root.
    root_rest: Vec<f64>,
}

impl Costs {
    /// Unit `i`'s cost in a shard starting at `first`.
    fn step(&self, i: usize, first: usize) -> f64 {
        let unowned = self.first_of_root[i] < first;
        self.node[i] + self.root_tile[i] + if unowned { self.unit_tile[i] } else { 0.0 }
    }

    /// Units `i..` as one shard.
    fn rest(&self, i: usize) -> f64 {
        let unowned = i < self.node.len() && self.first_of_root[i] < i;
        self.suffix[i] + if unowned { self.root_rest[i] } else { 0.0 }
    }

    fn total(&self, starts: &[usize]) -> f64 {
        starts.windows(2).map(|w| (w[0]..w[1]).map(|i| self.step(i, w[0])).sum::<f64>()).sum()
    }

    /// Greedy cut into `count` shards, each aiming at the remaining cost
    /// plus `overhead` per cut still to come, over the shards left.
    fn cut(&self, count: usize, overhead: f64) -> Vec<usize> {
        let n = self.node.len();
        let mut starts = vec![0usize];
        let mut i = 0;
        for k in 0..count - 1 {
            let left = count - k;
            let target = (self.rest(i) + overhead * (left - 1) as f64) / left as f64;
            let (first, mut cost) = (i, 0.0);
            // At least one unit, and one left for each shard after this.
            while i < n - (left - 1) {
                let step = self.step(i, first);
                if i > first && cost + 0.5 * step > target {
                    break;
                }
                cost += step;
                i += 1;
            }
            starts.push(i);
        }
        starts.push(n);
        starts
    }
}

impl fmt::Display for ShardPlan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let lods: Vec<String> = self.nodes_per_lod.iter().map(|n| n.to_string()).collect();
        writeln!(
            f,
            "shard {} of {} (0-based): {} nodes (LOD 0.. {}), {} units",
            self.index,
            self.count,
            self.nodes(),
            lods.join(", "),
            self.units
        )?;
        writeln!(
            f,
            "          disk about {}; error tiles of the {} roots it owns and of {} units of roots other shards own",
            super::plan::bytes(self.disk_bytes as f64),
            self.roots,
            self.unit_tiles
        )?;
        write!(
            f,
            "          about {} on {} threads ({} for the nodes, {} for the error tiles)",
            super::plan::duration(self.seconds()),
            self.threads,
            super::plan::duration(self.node_thread_seconds / self.threads.max(1) as f64),
            super::plan::duration(self.error_thread_seconds / self.threads.max(1) as f64)
        )
    }
}

/// Root index (row by row), then the Morton code of the cell in its root.
fn order_key(world: &WorldDesc, split_lod: u8, u: NodeId) -> u64 {
    let k = world.root_lod() - split_lod;
    let gx = u64::from(world.grid(world.root_lod())[0]);
    let root = u64::from(u.y >> k) * gx + u64::from(u.x >> k);
    let mask = (1u32 << k) - 1;
    (root << (2 * k)) | morton(u.x & mask, u.y & mask)
}

fn morton(x: u32, y: u32) -> u64 {
    (0..16).map(|b| (u64::from((x >> b) & 1) << (2 * b)) | (u64::from((y >> b) & 1) << (2 * b + 1))).sum()
}

fn ordered_units(world: &WorldDesc, split_lod: u8) -> Vec<NodeId> {
    let mut units = world.nodes_at(split_lod);
    units.sort_by_key(|&u| order_key(world, split_lod, u));
    units
}

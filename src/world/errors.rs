//! The error tree: for every node and each of its 16 x 16 patches, the
//! largest vertical distance between the surface the GPU draws for it (the
//! diamond-split triangles of its own samples) and the finest surface vista
//! can draw (the Catmull-Rom surface of the LOD-0 samples, tessellated 4x
//! denser than LOD 0: where the refinement below the samples stops), over
//! the patch's whole area, and a bound of its 99th percentile over the
//! patch's LOD-0 quads. Conservative (upper bounds, from exact per-sample
//! gaps and the triangle inequality; [`super::error_tile`]) and monotone by
//! construction: a patch's errors and height range cover those of every
//! finer patch under it, so a test that passes for a patch passes for all
//! its descendants.
//!
//! What the target error bounds is the *selection error*, the larger of the
//! 99th percentile and half the largest error ([`selection_error`]): a patch
//! drawn within a target T px has 99 % of its area within T and all of it
//! within 2 T, which is the promise `vista bench accuracy` checks.
//!
//! A root's numbers need every LOD-0 sample under it, so they are computed
//! a root at a time (in parallel blocks), kept in memory and, with a cache
//! folder, written to `DIR/errors/{world}{base}/lod{k}/{x}_{y}.verr` (zstd,
//! crc32, versioned and keyed like the node files: a tile's key is the
//! source's region hash over the root, so stamping a world recomputes only
//! the roots the stamps touch; `base` is the source before its stamps). A node gets its numbers when
//! it is baked or loaded ([`ErrorTree::attach`]): the first node of a root
//! waits for that root's computation.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::Instant;

use rayon::prelude::*;

use super::error::{Result, WorldError};
use super::error_tile::{compute_root, node_patches, LevelPatches};
use super::hash::Fnv64;
use super::layout::{NodeId, WorldDesc, PATCHES_PER_NODE};
use super::payload::BakedNode;
use super::progress::{Progress, Reporter, Work};
use super::source::HeightSource;

const MAGIC: [u8; 4] = *b"VERR";
/// Bumped whenever the tile layout or the error definition changes.
const TILE_VERSION: u32 = 4;

/// One root's patches of every level (index = LOD).
type Tile = Arc<Vec<LevelPatches>>;

/// Bytes of root tiles an [`ErrorTree`] with a cache folder keeps in memory
/// by default: the least recently used tiles past it are dropped and read
/// again from their file when a node asks (a whole 0.5 m, 10 km world's
/// tree is 315 MiB, a 60 km world's at 10 LODs several GiB).
pub const DEFAULT_HELD_TILE_BYTES: u64 = 96 << 20;

/// Bytes per patch of a level in memory (five f32, two f64).
pub const TILE_BYTES_PER_PATCH: u64 = 5 * 4 + 2 * 8;

fn tile_bytes(tile: &[LevelPatches]) -> u64 {
    tile.iter().map(|l| (l.side * l.side) as u64 * TILE_BYTES_PER_PATCH).sum()
}

/// Root tiles in memory that their file holds too, least recently used
/// first, with their bytes.
#[derive(Default)]
struct Held {
    order: std::collections::VecDeque<(NodeId, u64)>,
    bytes: u64,
}

/// The number a target bounds, from a patch's largest error and its 99th
/// percentile: both halves of the promise (p99 within the target, the
/// largest within twice it) hold where it does.
pub fn selection_error(max_m: f32, p99_m: f32) -> f32 {
    p99_m.max(0.5 * max_m)
}

/// One node's numbers.
#[derive(Clone, Debug, PartialEq)]
pub struct NodeErrors {
    /// Largest patch selection error (m).
    pub node_m: f32,
    /// Per patch: the selection errors ([`selection_error`]) drawn at this
    /// node's level and drawn 2x refined below the samples (LOD 0 only,
    /// else 0), metres. What the renderer reads.
    pub patch_m: Vec<[f32; 2]>,
    /// Per patch: the largest errors, as `patch_m`.
    pub patch_max_m: Vec<[f32; 2]>,
    /// Per patch: the finest surface's height range, R16 (rounded outwards
    /// by one step for the GPU's f32 evaluation).
    pub bounds: Vec<[u16; 2]>,
    /// The largest LOD-0 representation error under the node: LOD 0's
    /// triangles against the finest surface (what the refinement removes).
    pub repr_m: f32,
}

/// What an [`ErrorTree`] has done ([`ErrorTree::counts`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TreeCounts {
    /// Tiles computed (roots', and any below them).
    pub computed: usize,
    /// Root tiles read from the cache folder.
    pub read: usize,
    /// Thread time spent computing them (each tile's own parallel work
    /// counted once, as wall time of the thread that made it).
    pub compute_seconds: f64,
}

/// Per-root error data of one world, computed on first use.
pub struct ErrorTree {
    world: WorldDesc,
    source: Arc<dyn HeightSource>,
    dir: Option<PathBuf>,
    /// The world's hash and the source's id: what [`Self::is_for`] checks.
    keys: [u64; 2],
    /// Tiles by node: the roots', and any made below them.
    roots: Mutex<HashMap<NodeId, Arc<OnceLock<Tile>>>>,
    /// Tiles computed by this tree (not read from the folder).
    computed: AtomicUsize,
    /// A tile could not be cached: reported once, then not tried again.
    unwritable: AtomicBool,
    /// Root tiles that may be dropped (their file holds them) and the
    /// bytes they may take together.
    held: Mutex<Held>,
    held_budget: u64,
    /// A root whose tile is not at hand loads with pending numbers
    /// ([`Self::with_roots_on_demand`]).
    on_demand: bool,
    /// Root tiles read from the folder, and the time spent computing tiles.
    read: AtomicUsize,
    compute_nanos: AtomicU64,
}

impl std::fmt::Debug for ErrorTree {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ErrorTree").field("world", &self.world).field("dir", &self.dir).finish_non_exhaustive()
    }
}

/// What [`ErrorTree::prepare`] did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PreparedErrors {
    pub roots: usize,
    /// Of those, read from the cache folder; the rest were computed.
    pub read: usize,
    /// Tiles of nodes below the roots, computed ([`ErrorTree::prepare_tiles`]).
    pub below_roots: usize,
    pub seconds: f64,
}

impl ErrorTree {
    /// Errors of `world` sampled from `source`; tiles are read from and
    /// written to `cache_dir/errors` when given.
    pub fn new(world: &WorldDesc, source: Arc<dyn HeightSource>, cache_dir: Option<&Path>) -> Result<Self> {
        world.validate()?;
        let keys = [world.hash(), source.id_hash()];
        // A folder per world and base source: a cache shared by several
        // worlds keeps each one's tiles, and stamped versions of one world
        // share the tiles their stamps leave alone.
        let folder = format!("{:016x}{:016x}", keys[0], source.base_id_hash());
        let dir = cache_dir.map(|d| d.join("errors").join(folder));
        Ok(ErrorTree {
            world: *world,
            source,
            dir,
            keys,
            roots: Mutex::new(HashMap::new()),
            computed: AtomicUsize::new(0),
            unwritable: AtomicBool::new(false),
            held: Mutex::new(Held::default()),
            held_budget: DEFAULT_HELD_TILE_BYTES,
            on_demand: false,
            read: AtomicUsize::new(0),
            compute_nanos: AtomicU64::new(0),
        })
    }

    /// The same tree, making a root's tile only when a node below the root
    /// asks for it: a root whose tile is neither in memory nor in the
    /// folder is attached *pending* numbers ([`Self::attach`]): an unknown
    /// (infinite) error and the world's whole height range. Roots are
    /// always resident, so without this the first frame waits for every
    /// root's tile; with it, only the roots a view refines into are made
    /// (streaming wants a pending root's children only in view), and the
    /// terrain attaches a pending root's numbers once its tile is made.
    pub fn with_roots_on_demand(mut self) -> Self {
        self.on_demand = self.world.root_lod() > 0;
        self
    }

    /// Whether roots are made on demand ([`Self::with_roots_on_demand`]).
    pub fn roots_on_demand(&self) -> bool {
        self.on_demand
    }

    /// What the tree has done so far.
    pub fn counts(&self) -> TreeCounts {
        TreeCounts {
            computed: self.computed.load(Ordering::Relaxed),
            read: self.read.load(Ordering::Relaxed),
            compute_seconds: self.compute_nanos.load(Ordering::Relaxed) as f64 * 1e-9,
        }
    }

    /// The same tree keeping at most `bytes` of cached root tiles in memory
    /// (at least the one in use); tiles without a file are always kept.
    pub fn with_held_bytes(mut self, bytes: u64) -> Self {
        self.held_budget = bytes;
        self
    }

    /// Bytes of tiles in memory now.
    pub fn memory_bytes(&self) -> u64 {
        let tiles = self.roots.lock().unwrap_or_else(|e| e.into_inner());
        tiles.values().filter_map(|c| c.get()).map(|t| tile_bytes(t)).sum()
    }

    /// Bytes of one root's tile in memory: every level over the root's
    /// whole area (a border root's too).
    pub fn root_tile_bytes(world: &WorldDesc) -> u64 {
        let (per_side, root) = (u64::from(super::layout::PATCHES_PER_NODE_SIDE), u64::from(world.root_lod()));
        (0..=root).map(|k| (per_side << (root - k)).pow(2)).sum::<u64>() * TILE_BYTES_PER_PATCH
    }

    /// Bytes of every root's tile: what a tree without a cache folder keeps.
    pub fn whole_bytes(world: &WorldDesc) -> u64 {
        let [rx, ry] = world.grid(world.root_lod());
        u64::from(rx) * u64::from(ry) * Self::root_tile_bytes(world)
    }

    /// The error tree of the same world after an edit of its source
    /// (`cache_dir` as for [`Self::new`]): the root tiles made so far that
    /// the edit leaves alone (the source hashes alike over them) come
    /// along, the others are made again when asked for (or read from the
    /// folder, where an earlier run left them).
    pub fn edited(&self, source: Arc<dyn HeightSource>, cache_dir: Option<&Path>) -> Result<ErrorTree> {
        let mut tree = ErrorTree::new(&self.world, source, cache_dir)?.with_held_bytes(self.held_budget);
        tree.on_demand = self.on_demand;
        let root_lod = self.world.root_lod();
        let old = self.roots.lock().unwrap_or_else(|e| e.into_inner());
        let mut kept = tree.roots.lock().unwrap_or_else(|e| e.into_inner());
        let mut files = Vec::new();
        for (id, cell) in old.iter().filter(|(id, _)| id.lod == root_lod) {
            if let Some(tile) = cell.get().filter(|_| self.tile_keys(*id) == tree.tile_keys(*id)) {
                kept.insert(*id, Arc::new(OnceLock::from(Arc::clone(tile))));
                if tree.path(*id).is_some_and(|p| p.is_file()) {
                    files.push((*id, tile_bytes(tile)));
                }
            }
        }
        drop(kept);
        for (id, bytes) in files {
            tree.hold(id, bytes);
        }
        Ok(tree)
    }

    /// Where the root tiles are cached (`None`: in memory only).
    pub fn dir(&self) -> Option<&Path> {
        self.dir.as_deref()
    }

    /// Whether this tree is the error tree of `world` sampled from `source`.
    pub fn is_for(&self, world: &WorldDesc, source: &dyn HeightSource) -> bool {
        self.world == *world && self.keys == [world.hash(), source.id_hash()]
    }

    /// Reads or computes every root's tile now, reporting progress, so that
    /// no node waits for one to be computed later (with a cache folder, the
    /// tiles past the held budget are dropped again and read back from
    /// their files when a node asks). Several processes preparing one world
    /// into one folder share the work: each starts at another root (by
    /// process id) and reads what the others have written meanwhile.
    pub fn prepare(&self, progress: Progress) -> PreparedErrors {
        self.prepare_roots(self.world.roots(), progress)
    }

    /// As [`Self::prepare`], for the tiles of `roots` only.
    pub fn prepare_roots(&self, roots: Vec<NodeId>, progress: Progress) -> PreparedErrors {
        assert!(roots.iter().all(|r| r.lod == self.world.root_lod()), "not roots: {roots:?}");
        self.prepare_tiles(roots, progress)
    }

    /// As [`Self::prepare_roots`], where a tile may also be that of a node
    /// below the roots (a shard's part of a root another shard makes): its
    /// levels 0 up to its LOD over its area, the same numbers as its root's
    /// tile there, kept in memory only (the folder holds whole roots). A
    /// node whose root's tile is not made takes its numbers from such a
    /// tile above it when one is made.
    pub fn prepare_tiles(&self, mut tiles: Vec<NodeId>, progress: Progress) -> PreparedErrors {
        assert!(tiles.iter().all(|r| self.world.is_valid(*r)), "tiles of nodes outside the world: {tiles:?}");
        let start = Instant::now();
        if !tiles.is_empty() {
            let shift = std::process::id() as usize % tiles.len();
            tiles.rotate_left(shift);
        }
        let before = self.computed.load(Ordering::Relaxed);
        let bar = Reporter::new(progress, tiles.len() as u64, Work::ErrorRoots);
        tiles.par_iter().with_max_len(1).for_each(|r| {
            self.tile(*r);
            bar.inc();
        });
        bar.finish();
        let computed = self.computed.load(Ordering::Relaxed) - before;
        let (roots, below) = (tiles.len(), tiles.iter().filter(|t| t.lod < self.world.root_lod()).count());
        PreparedErrors {
            roots: roots - below,
            below_roots: below,
            read: tiles.len().saturating_sub(computed),
            seconds: start.elapsed().as_secs_f64(),
        }
    }

    pub fn world(&self) -> &WorldDesc {
        &self.world
    }

    /// Roots whose tile is neither in memory nor a file of the cache folder
    /// (a file is not read here: an estimate of the work `prepare` does).
    pub fn uncached_roots(&self) -> usize {
        self.world.roots().iter().filter(|r| !self.root_at_hand(**r)).count()
    }

    /// Whether `root`'s tile is in memory or a file of the cache folder:
    /// a node below it gets its numbers without a computation.
    pub fn root_at_hand(&self, root: NodeId) -> bool {
        let made = self.roots.lock().unwrap_or_else(|e| e.into_inner()).get(&root).is_some_and(|c| c.get().is_some());
        made || self.path(root).is_some_and(|p| p.is_file())
    }

    /// The numbers of node `id` (valid in the world); the first call for a
    /// root computes (or reads) that root's tile.
    pub fn node(&self, id: NodeId) -> Result<NodeErrors> {
        if !self.world.is_valid(id) {
            return Err(WorldError::InvalidNode(id));
        }
        let (root, tile) = self.tile_for(id);
        let range = self.world.height_range_m;
        let step = f64::from(range[1] - range[0]) / 65535.0;
        let (mut node_m, mut repr_m) = (0f32, 0f32);
        let l = &tile[usize::from(id.lod)];
        let mut patch_m = Vec::with_capacity(PATCHES_PER_NODE);
        let mut patch_max_m = Vec::with_capacity(PATCHES_PER_NODE);
        let mut bounds = Vec::with_capacity(PATCHES_PER_NODE);
        for p in node_patches(&tile, root, id) {
            let (refine, refine_q) = if id.lod == 0 { (l.refine[p], l.refine_q[p]) } else { (0.0, 0.0) };
            let sel = selection_error(l.error[p], l.error_q[p]);
            patch_m.push([sel, selection_error(refine, refine_q)]);
            patch_max_m.push([l.error[p], refine]);
            node_m = node_m.max(sel);
            repr_m = repr_m.max(l.repr[p]);
            let steps = |z: f64| (z - f64::from(range[0])) / step;
            let lo = (steps(l.lo[p]).floor() - 1.0).clamp(0.0, 65535.0) as u16;
            let hi = (steps(l.hi[p]).ceil() + 1.0).clamp(0.0, 65535.0) as u16;
            bounds.push([lo, hi]);
        }
        Ok(NodeErrors { node_m, patch_m, patch_max_m, bounds, repr_m })
    }

    /// Writes `node`'s errors and bounds into it: `max_error_m`,
    /// `patch_errors`, `patch_min_max`, `min_height` / `max_height` (the
    /// union of the patch ranges) and `repr_error_m`.
    /// With roots on demand, a root whose tile is not at hand gets pending
    /// numbers instead ([`BakedNode::errors_pending`]).
    pub fn attach(&self, node: &mut BakedNode) -> Result<()> {
        if self.on_demand && node.id.lod == self.world.root_lod() && !self.root_at_hand(node.id) {
            attach_pending(node);
            return Ok(());
        }
        let e = self.node(node.id)?;
        node.max_error_m = e.node_m;
        node.repr_error_m = e.repr_m;
        node.min_height = e.bounds.iter().map(|b| b[0]).min().unwrap_or(0);
        node.max_height = e.bounds.iter().map(|b| b[1]).max().unwrap_or(0);
        node.patch_min_max = e.bounds;
        node.patch_errors = e.patch_m;
        Ok(())
    }

    fn root_of(&self, id: NodeId) -> NodeId {
        let shift = self.world.root_lod() - id.lod;
        NodeId::new(self.world.root_lod(), id.x >> shift, id.y >> shift)
    }

    /// The tile holding `id`'s numbers and the node it is of: its root's
    /// if made, else a made tile of a node between them, else its root's,
    /// made now.
    fn tile_for(&self, id: NodeId) -> (NodeId, Tile) {
        let root = self.root_of(id);
        {
            let tiles = self.roots.lock().unwrap_or_else(|e| e.into_inner());
            let made = |n: NodeId| tiles.get(&n).and_then(|c| c.get()).map(Arc::clone);
            let mut above = (id.lod..root.lod).map(|l| NodeId::new(l, id.x >> (l - id.lod), id.y >> (l - id.lod)));
            if let Some(found) = made(root).map(|t| (root, t)).or_else(|| above.find_map(|n| Some((n, made(n)?)))) {
                drop(tiles);
                self.touch(found.0);
                return found;
            }
        }
        (root, self.tile(root))
    }

    /// Marks a held root tile as just used.
    fn touch(&self, root: NodeId) {
        let mut held = self.held.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(i) = held.order.iter().position(|(id, _)| *id == root) {
            let entry = held.order.remove(i).expect("found");
            held.order.push_back(entry);
        }
    }

    /// Counts a root tile that its file holds too, then drops the least
    /// recently used such tiles past the budget (never the newest).
    fn hold(&self, root: NodeId, bytes: u64) {
        let mut held = self.held.lock().unwrap_or_else(|e| e.into_inner());
        held.order.push_back((root, bytes));
        held.bytes += bytes;
        while held.bytes > self.held_budget && held.order.len() > 1 {
            let (old, b) = held.order.pop_front().expect("more than one");
            held.bytes -= b;
            self.roots.lock().unwrap_or_else(|e| e.into_inner()).remove(&old);
        }
    }

    /// A node's tile: from memory, the cache folder (roots only), or
    /// computed now (other threads asking for the same tile wait for it).
    fn tile(&self, root: NodeId) -> Tile {
        let is_root = root.lod == self.world.root_lod();
        let cell = Arc::clone(self.roots.lock().unwrap_or_else(|e| e.into_inner()).entry(root).or_default());
        // Set by the one thread that makes the tile: whether a file holds it.
        let mut in_file = None;
        let tile = Arc::clone(cell.get_or_init(|| {
            if let Some(tile) = is_root.then(|| self.read(root)).flatten() {
                in_file = Some(true);
                self.read.fetch_add(1, Ordering::Relaxed);
                return Arc::new(tile);
            }
            let start = Instant::now();
            let tile = compute_root(&self.world, self.source.as_ref(), root);
            self.compute_nanos.fetch_add(start.elapsed().as_nanos() as u64, Ordering::Relaxed);
            self.computed.fetch_add(1, Ordering::Relaxed);
            in_file = Some(is_root && self.dir.is_some() && !self.unwritable.load(Ordering::Relaxed));
            if in_file == Some(true) {
                if let Err(e) = self.write(root, &tile) {
                    in_file = Some(false);
                    if !self.unwritable.swap(true, Ordering::Relaxed) {
                        log::warn!("{e}; the error tree is not cached");
                    }
                }
            }
            Arc::new(tile)
        }));
        if in_file == Some(true) {
            self.hold(root, tile_bytes(&tile));
        } else if in_file.is_none() {
            self.touch(root);
        }
        tile
    }

    /// The world and what the source is over the root's area (and the
    /// samples around it that its finest surface reads).
    fn tile_keys(&self, root: NodeId) -> [u64; 2] {
        [self.keys[0], self.source.region_hash(super::cache::bake_region(&self.world, root))]
    }

    fn path(&self, root: NodeId) -> Option<PathBuf> {
        let dir = self.dir.as_ref()?;
        Some(dir.join(format!("lod{}", root.lod)).join(format!("{}_{}.verr", root.x, root.y)))
    }

    fn read(&self, root: NodeId) -> Option<Vec<LevelPatches>> {
        let bytes = std::fs::read(self.path(root)?).ok()?;
        let (body, crc) = bytes.split_at(bytes.len().checked_sub(4)?);
        if crc32fast::hash(body) != u32::from_le_bytes(crc.try_into().ok()?) || body.get(..4)? != MAGIC {
            return None;
        }
        let u64_at = |o: usize| body.get(o..o + 8).map(|b| u64::from_le_bytes(b.try_into().unwrap()));
        let version = body.get(4..8).map(|b| u32::from_le_bytes(b.try_into().unwrap()))?;
        if version != TILE_VERSION || [u64_at(8)?, u64_at(16)?] != self.tile_keys(root) || u64_at(24)? != node_key(root)
        {
            return None;
        }
        let raw = zstd::stream::decode_all(&body[32..]).ok()?;
        decode_levels(&raw, root)
    }

    fn write(&self, root: NodeId, tile: &[LevelPatches]) -> Result<()> {
        let Some(path) = self.path(root) else { return Ok(()) };
        let dir = path.parent().expect("tile path has a folder");
        std::fs::create_dir_all(dir).map_err(|e| WorldError::create_dir(dir, e))?;
        let packed = zstd::bulk::compress(&encode_levels(tile), 3).map_err(|e| WorldError::io_write(&path, e))?;
        let mut out = Vec::with_capacity(packed.len() + 36);
        out.extend_from_slice(&MAGIC);
        out.extend_from_slice(&TILE_VERSION.to_le_bytes());
        for k in self.tile_keys(root).into_iter().chain([node_key(root)]) {
            out.extend_from_slice(&k.to_le_bytes());
        }
        out.extend_from_slice(&packed);
        out.extend_from_slice(&crc32fast::hash(&out).to_le_bytes());
        crate::output::write(&path, &out).map_err(|e| WorldError::io_write(&path, e.error))
    }
}

/// A root's numbers before its tile is made: an unknown error (infinite,
/// so the traversal refines it wherever its children are resident and the
/// frame's bound says it is unknown where it is drawn) and the world's
/// whole height range (so culling stays conservative).
fn attach_pending(node: &mut BakedNode) {
    node.max_error_m = f32::INFINITY;
    node.repr_error_m = f32::INFINITY;
    node.patch_errors = vec![[f32::INFINITY, 0.0]; PATCHES_PER_NODE];
    node.patch_min_max = vec![[0, u16::MAX]; PATCHES_PER_NODE];
    node.min_height = 0;
    node.max_height = u16::MAX;
}

fn node_key(id: NodeId) -> u64 {
    Fnv64::new().u64(u64::from(id.lod)).u64(u64::from(id.x)).u64(u64::from(id.y)).finish()
}

/// Little-endian: per level, every patch's error, refine, error_q,
/// refine_q, repr (f32) and lo, hi (f64).
fn encode_levels(levels: &[LevelPatches]) -> Vec<u8> {
    let mut out = Vec::new();
    for l in levels {
        for v in l.error.iter().chain(&l.refine).chain(&l.error_q).chain(&l.refine_q).chain(&l.repr) {
            out.extend_from_slice(&v.to_le_bytes());
        }
        for v in l.lo.iter().chain(&l.hi) {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out
}

fn decode_levels(raw: &[u8], root: NodeId) -> Option<Vec<LevelPatches>> {
    let mut pos = 0;
    let mut take = |n: usize| {
        let s = raw.get(pos..pos + n)?;
        pos += n;
        Some(s)
    };
    let mut levels = Vec::new();
    for k in 0..=root.lod {
        let side = (super::layout::PATCHES_PER_NODE_SIDE as usize) << (root.lod - k);
        let n = side * side;
        let mut f32s = || -> Option<Vec<f32>> {
            Some(take(4 * n)?.chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().unwrap())).collect())
        };
        let (error, refine, error_q, refine_q, repr) = (f32s()?, f32s()?, f32s()?, f32s()?, f32s()?);
        let mut f64s = || -> Option<Vec<f64>> {
            Some(take(8 * n)?.chunks_exact(8).map(|b| f64::from_le_bytes(b.try_into().unwrap())).collect())
        };
        let (lo, hi) = (f64s()?, f64s()?);
        levels.push(LevelPatches { side, error, refine, error_q, refine_q, repr, lo, hi, partial: Vec::new() });
    }
    (pos == raw.len()).then_some(levels)
}

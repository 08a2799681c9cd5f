//! The plan of a world, computed before any work: sectors, nodes per LOD,
//! bytes on disk and on the GPU, and the estimated bake time; checked
//! against [`Limits`] so an absurd world is refused before anything sized by
//! it is allocated. Everything here is arithmetic on the [`WorldDesc`]: no
//! allocation grows with the node count.

use std::time::Instant;

use rayon::prelude::*;

use super::bake::{bake_node_with, BakeSettings};
use super::cache::estimated_file_bytes;
use super::error_tile::compute_block;
use super::holes::Hole;
use super::layout::{NodeId, WorldDesc, MAX_LOD_COUNT, NODE_QUADS};
use super::memory::MemoryReport;
use super::source::HeightSource;
use super::texels::PayloadFormat;

/// Wall time each level of [`WorldPlan::measure_bake`] bakes for at least
/// (unless its batches run out): below about 50 ms, thread start-up and
/// scheduling jitter moved the estimate of Mont Blanc at 1 m (2.5 ms a node)
/// between 12 and 18 minutes.
pub const MIN_TIMED_SECONDS: f64 = 0.05;
/// Most batches per level in [`WorldPlan::measure_bake`].
pub const MAX_SAMPLE_BATCHES: u64 = 8;
/// Default for [`Limits::max_sectors_per_side`]: the largest node texture
/// most GPUs allow (16384 texels a side), and a CPU quadtree shadow of
/// about 700 MiB at that size.
pub const DEFAULT_MAX_SECTORS_PER_SIDE: u64 = 16384;
/// Default cap on a bake's estimated disk size without `--yes`.
pub const DEFAULT_MAX_BAKE_DISK_BYTES: u64 = 64 << 30;
/// Resident slots a plan assumes when none are given (the renderer's
/// default budget).
pub const DEFAULT_SLOTS: u32 = 512;

/// Slots the GPU keeps beyond the residency budget: a reloaded node (an
/// edited source) moves to a fresh slot while frames in flight still read
/// its old one, so a full budget does not stall the reload (fewer where
/// the budget is near the 11-bit limit: [`slot_capacity`]).
pub const RELOAD_SLOTS: u32 = 8;

/// Node slots the GPU resources hold for a residency budget of `slots`
/// (a budget over the 11-bit limit is left as it is, for the plan to
/// refuse).
pub fn slot_capacity(slots: u32) -> u32 {
    let max = crate::shaders::consts::MAX_SLOTS;
    if slots >= max {
        slots
    } else {
        (slots + RELOAD_SLOTS).min(max)
    }
}
/// Single-thread seconds to bake one node when no sample was timed: the
/// whole default procedural world baked and written (`vista bake`, 34 125
/// nodes, BC payloads, zstd) on the 2-core development VM took 513 thread
/// seconds, 15 ms a node. Image sources are cheaper; where the source is
/// at hand, [`WorldPlan::measure_bake`] times it instead.
pub const NODE_BAKE_THREAD_SECONDS: f64 = 0.015;
/// Single-thread seconds of the error tree per LOD-0 quad when nothing is
/// timed: the default (eroded) world's 419 M quads took 70.2 s on the
/// 2-core reference machine's two threads.
pub const ERROR_QUAD_THREAD_SECONDS: f64 = 3.4e-7;

/// What a world may cost. `None` fields are not checked.
#[derive(Clone, Debug, PartialEq)]
pub struct Limits {
    /// Most LOD-0 sectors along either side.
    pub max_sectors_per_side: u64,
    /// Most estimated bytes a bake may write; `None` outside bakes or when
    /// the user accepted the size.
    pub max_bake_disk_bytes: Option<u64>,
    /// The device's `maxImageDimension2D`: the node texture's side.
    pub max_image_dimension_2d: Option<u32>,
    /// The device's `maxImageArrayLayers`: one atlas layer per slot.
    pub max_image_array_layers: Option<u32>,
    /// Most root nodes a renderer holds: a quarter of its slot budget, so
    /// the rest can refine the near field (roots are always resident).
    pub max_roots: Option<u64>,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_sectors_per_side: DEFAULT_MAX_SECTORS_PER_SIDE,
            max_bake_disk_bytes: None,
            max_image_dimension_2d: None,
            max_image_array_layers: None,
            max_roots: None,
        }
    }
}

/// Why a plan was refused. Each message is one line naming the limit and
/// the option that changes it.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PlanError {
    #[error(
        "the world would have {x} x {y} sectors of {sector_m} m; the limit is {limit} a side: raise --spacing or \
         lower --extent (or raise --max-sectors)"
    )]
    TooManySectors { x: u64, y: u64, sector_m: f64, limit: u64 },
    #[error(
        "the bake would write about {} to disk ({nodes} nodes, about {} to bake); the cap is {}: raise --spacing, \
         bake a --region, raise --max-disk GIB or pass --yes",
        bytes(*disk as f64), duration(*seconds), bytes(*cap as f64)
    )]
    BakeTooLarge { disk: u64, nodes: u64, seconds: f64, cap: u64 },
    #[error(
        "the node texture would be {w} x {h} texels ({x} x {y} sectors, {lods} LODs); this device allows {max} a side: \
         raise --spacing, lower --extent or lower --lods"
    )]
    NodeTextureTooLarge { w: u64, h: u64, x: u64, y: u64, lods: u32, max: u32 },
    #[error("{slots} resident slots need {layers} atlas layers; this device allows {max}: lower --slots")]
    TooManyLayers { slots: u32, layers: u64, max: u32 },
    #[error(
        "the world's {x} x {y} root nodes ({lods} LODs, {root_m} m each) would hold {roots} of the {slots} resident \
         slots, more than a quarter, leaving too few to refine near the camera: {fix}"
    )]
    TooManyRoots { x: u64, y: u64, roots: u64, lods: u32, root_m: f64, slots: u32, fix: &'static str },
}

/// Where a plan's bake time comes from.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TimeBasis {
    /// [`NODE_BAKE_THREAD_SECONDS`].
    Constant,
    /// This many nodes baked and timed.
    Measured(usize),
}

/// The cost of a world (or of a region of it), before any of it is made.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct WorldPlan {
    pub world: WorldDesc,
    /// Nodes overlapping this rectangle, metres; `None` = the whole world.
    pub region: Option<[f64; 4]>,
    /// LOD-0 sectors per side of the whole world.
    pub sectors: [u64; 2],
    /// Cells per side of the whole world at each LOD.
    pub grid_per_lod: Vec<[u64; 2]>,
    /// Nodes in the region at each LOD.
    pub nodes_per_lod: Vec<u64>,
    /// Nodes of the whole world.
    pub world_nodes: u64,
    /// Payload format the byte figures are for.
    pub format: PayloadFormat,
    /// Estimated node file bytes of the region (zstd-compressed).
    pub disk_bytes: u64,
    /// Resident slots the GPU and CPU figures are for.
    pub slots: u32,
    /// Payload atlases of the resident slots.
    pub gpu_slot_bytes: u64,
    /// Node texture side (mip 0), as `terrain::quadtree::texture_extent`.
    pub node_texture: [u64; 2],
    /// Node texture with every mip; its CPU shadow is as large.
    pub node_texture_bytes: u64,
    /// Single-thread seconds per baked node, and where that comes from.
    pub node_seconds: f64,
    pub time_basis: TimeBasis,
    /// LOD-0 quads under the roots over the region (inside the world): the
    /// error tree needs every one of them ([`super::ErrorTree`]).
    pub error_quads: u64,
    /// Single-thread seconds of the error tree per LOD-0 quad.
    pub error_quad_seconds: f64,
    /// Bake threads (rayon's pool).
    pub threads: usize,
}

impl WorldPlan {
    /// `world` must be valid ([`WorldDesc::validate`]): its sector count is
    /// then below 2^20 a side, so every figure fits u64.
    pub fn new(world: &WorldDesc, region: Option<[f64; 4]>) -> Self {
        let sectors = world.sectors().map(u64::from);
        let lods = 0..world.lod_count as u8;
        let grid_per_lod: Vec<[u64; 2]> = lods.clone().map(|l| world.grid(l).map(u64::from)).collect();
        let nodes_per_lod: Vec<u64> = lods
            .map(|l| {
                let [x0, y0, x1, y1] = region_cells(world, l, region);
                (x1 - x0) * (y1 - y0)
            })
            .collect();
        let world_nodes = grid_per_lod.iter().map(|g| g[0] * g[1]).sum();
        let format = PayloadFormat::default();
        let disk_bytes = nodes_per_lod.iter().sum::<u64>() * estimated_file_bytes(format);
        // Mip 0 padded to whole roots, as the renderer sizes it.
        let root = world.root_lod();
        let node_texture = world.node_texture_extent().map(u64::from);
        let node_texture_bytes =
            (0..world.lod_count).map(|l| (node_texture[0] >> l) * (node_texture[1] >> l) * 2).sum();
        // The roots over the region, clipped to the world's sectors.
        let [rx0, ry0, rx1, ry1] = region_cells(world, root, region);
        let clip = |c0: u64, c1: u64, s: u64| ((c1 << root).min(s)).saturating_sub(c0 << root);
        let quads = u64::from(NODE_QUADS);
        let error_quads = clip(rx0, rx1, sectors[0]) * quads * clip(ry0, ry1, sectors[1]) * quads;
        let mut plan = WorldPlan {
            world: *world,
            region,
            sectors,
            grid_per_lod,
            nodes_per_lod,
            world_nodes,
            format,
            disk_bytes,
            slots: 0,
            gpu_slot_bytes: 0,
            node_texture,
            node_texture_bytes,
            node_seconds: NODE_BAKE_THREAD_SECONDS,
            time_basis: TimeBasis::Constant,
            error_quads,
            error_quad_seconds: ERROR_QUAD_THREAD_SECONDS,
            threads: rayon::current_num_threads().max(1),
        };
        plan.set_slots(DEFAULT_SLOTS);
        plan
    }

    /// The GPU and CPU figures for `slots` resident nodes.
    pub fn with_slots(mut self, slots: u32) -> Self {
        self.set_slots(slots);
        self
    }

    fn set_slots(&mut self, slots: u32) {
        self.slots = slots;
        self.gpu_slot_bytes = MemoryReport::for_format(slots as usize, self.format).gpu_total() as u64;
    }

    /// The disk and GPU figures for payloads in `format`.
    pub fn with_format(mut self, format: PayloadFormat) -> Self {
        self.format = format;
        self.disk_bytes = self.nodes() * estimated_file_bytes(format);
        self.set_slots(self.slots);
        self
    }

    /// Nodes in the region, every LOD.
    pub fn nodes(&self) -> u64 {
        self.nodes_per_lod.iter().sum()
    }

    /// Estimated wall-clock seconds to bake the region from scratch (cached
    /// nodes only cost a read).
    pub fn bake_seconds(&self) -> f64 {
        self.node_bake_seconds() + self.error_seconds()
    }

    /// The nodes' share of [`Self::bake_seconds`].
    pub fn node_bake_seconds(&self) -> f64 {
        self.nodes() as f64 * self.node_seconds / self.threads as f64
    }

    /// The error tree's share of [`Self::bake_seconds`].
    pub fn error_seconds(&self) -> f64 {
        self.error_quads as f64 * self.error_quad_seconds / self.threads as f64
    }

    /// One line: nodes, disk size, time.
    pub fn summary(&self) -> String {
        format!(
            "{} nodes, about {} on disk, about {} on {} threads",
            self.nodes(),
            bytes(self.disk_bytes as f64),
            duration(self.bake_seconds()),
            self.threads
        )
    }

    /// GPU bytes: resident payload atlases plus the node texture.
    pub fn gpu_bytes(&self) -> u64 {
        self.gpu_slot_bytes + self.node_texture_bytes
    }

    /// Times the bake of nodes of the region, half at LOD 0 and half above
    /// it (a LOD-0 node samples a quarter of the points a coarser one
    /// does), spread over it and baked in parallel as [`super::bake_world`]
    /// does, and weighs the two costs by the region's node counts. Each
    /// level bakes batches of `samples / 2` nodes until `MIN_TIMED_SECONDS`
    /// have passed (cheap nodes jitter) or `MAX_SAMPLE_BATCHES` batches.
    /// Writes nothing to disk.
    pub fn measure_bake(&mut self, source: &dyn HeightSource, holes: &[Hole], settings: &BakeSettings, samples: usize) {
        let coarse_nodes: u64 = self.nodes_per_lod.iter().skip(1).sum();
        let per_batch = if coarse_nodes > 0 { samples / 2 } else { samples } as u64;
        let mut measured = Vec::new();
        for lod in [0u8, 1] {
            if lod == 1 && coarse_nodes == 0 {
                break;
            }
            let [x0, y0, x1, y1] = region_cells(&self.world, lod, self.region);
            if x0 == x1 || y0 == y1 || per_batch == 0 {
                return;
            }
            // Spread over the region's area (Halton 2, 3): a node's cost
            // depends on its ground (lowlands skip the procedural world's
            // mountain octaves), which a diagonal samples poorly.
            let node = |k: u64| {
                let at = |v: f64, lo: u64, hi: u64| lo + ((hi - lo) as f64 * v) as u64;
                NodeId::new(lod, at(halton(k, 2), x0, x1) as u32, at(halton(k, 3), y0, y1) as u32)
            };
            let bake = |id| std::hint::black_box(bake_node_with(source, &self.world, holes, settings, id));
            // One node untimed first: the first touch of a source (an
            // image's pixels, the thread pool) made timings 40 % high.
            bake(node(1));
            let (mut thread_seconds, mut count) = (0.0, 0u64);
            let cells = (x1 - x0) * (y1 - y0);
            while count < cells.min(per_batch * MAX_SAMPLE_BATCHES) {
                let ids: Vec<NodeId> = (count + 1..=(count + per_batch).min(cells)).map(node).collect();
                let start = Instant::now();
                ids.par_iter().for_each(|&id| {
                    bake(id);
                });
                // Busy threads: fewer nodes than threads leave some idle.
                thread_seconds += start.elapsed().as_secs_f64() * self.threads.min(ids.len()) as f64;
                count += ids.len() as u64;
                if thread_seconds >= MIN_TIMED_SECONDS * self.threads as f64 {
                    break;
                }
            }
            measured.push((thread_seconds / count as f64, count));
        }
        let lod0 = self.nodes_per_lod.first().copied().unwrap_or(0) as f64;
        let total = self.nodes().max(1) as f64;
        let coarse_cost = measured.get(1).map_or(measured[0].0, |m| m.0);
        self.node_seconds = (measured[0].0 * lod0 + coarse_cost * coarse_nodes as f64) / total;
        self.time_basis = TimeBasis::Measured(measured.iter().map(|m| m.1 as usize).sum());
        self.measure_errors(source);
    }

    /// Times the error tree on sectors of the region (Halton points, one per
    /// thread at a time, as the tree computes blocks in parallel) until
    /// [`MIN_TIMED_SECONDS`] have passed or [`MAX_SAMPLE_BATCHES`] batches.
    fn measure_errors(&mut self, source: &dyn HeightSource) {
        let [x0, y0, x1, y1] = region_cells(&self.world, 0, self.region);
        if x0 == x1 || y0 == y1 {
            return;
        }
        let root = self.world.root_lod();
        // A block spans at least one quad of the root level, as the tree's
        // blocks do (1024 quads): a level's triangles need their corners.
        let q = (NODE_QUADS as usize).max(1 << root);
        let per = (q / NODE_QUADS as usize) as u64;
        let (x0, y0, x1, y1) = (x0 / per, y0 / per, x1.div_ceil(per), y1.div_ceil(per));
        let sector = |k: u64| {
            let at = |v: f64, lo: u64, hi: u64| (lo + ((hi - lo) as f64 * v) as u64) as usize * q;
            [at(halton(k, 2), x0, x1), at(halton(k, 3), y0, y1)]
        };
        compute_block(&self.world, source, sector(1), q, root);
        let (mut thread_seconds, mut count) = (0.0, 0u64);
        for batch in 0..MAX_SAMPLE_BATCHES {
            let ks: Vec<u64> = (0..self.threads as u64).map(|t| 2 + batch * self.threads as u64 + t).collect();
            let start = Instant::now();
            ks.par_iter().for_each(|&k| compute_block(&self.world, source, sector(k), q, root));
            thread_seconds += start.elapsed().as_secs_f64() * self.threads as f64;
            count += ks.len() as u64;
            if thread_seconds >= MIN_TIMED_SECONDS * self.threads as f64 {
                break;
            }
        }
        self.error_quad_seconds = thread_seconds / (count as f64 * (q * q) as f64);
    }

    /// The first limit this plan breaks, if any.
    pub fn check(&self, limits: &Limits) -> Result<(), PlanError> {
        let [x, y] = self.sectors;
        if x.max(y) > limits.max_sectors_per_side {
            let (sector_m, limit) = (self.world.sector_size_m(), limits.max_sectors_per_side);
            return Err(PlanError::TooManySectors { x, y, sector_m, limit });
        }
        if let Some(max) = limits.max_image_dimension_2d {
            let [w, h] = self.node_texture;
            if w.max(h) > u64::from(max) {
                let lods = self.world.lod_count;
                return Err(PlanError::NodeTextureTooLarge { w, h, x, y, lods, max });
            }
        }
        if let Some(max) = limits.max_image_array_layers {
            // Slot 0 is reserved: one layer more than the GPU's slots.
            let layers = u64::from(slot_capacity(self.slots)) + 1;
            if layers > u64::from(max) {
                return Err(PlanError::TooManyLayers { slots: self.slots, layers, max });
            }
        }
        if let Some(max) = limits.max_roots {
            let [x, y] = self.grid_per_lod[self.world.root_lod() as usize];
            if x * y > max {
                let (lods, root_m) = (self.world.lod_count, self.world.node_size_m(self.world.root_lod()));
                let fix = if lods < MAX_LOD_COUNT {
                    "raise --lods (or --slots)"
                } else {
                    "raise --spacing or lower --extent (the world has the most LODs there can be)"
                };
                return Err(PlanError::TooManyRoots { x, y, roots: x * y, lods, root_m, slots: self.slots, fix });
            }
        }
        if let Some(cap) = limits.max_bake_disk_bytes {
            if self.disk_bytes > cap {
                let (disk, nodes, seconds) = (self.disk_bytes, self.nodes(), self.bake_seconds());
                return Err(PlanError::BakeTooLarge { disk, nodes, seconds, cap });
            }
        }
        Ok(())
    }
}

/// Element `k` of the Halton sequence in `base`: in 0..1, evenly spread.
fn halton(mut k: u64, base: u64) -> f64 {
    let (mut r, mut f) = (0.0, 1.0);
    while k > 0 {
        f /= base as f64;
        r += f * (k % base) as f64;
        k /= base;
    }
    r
}

/// Cell range [x0, y0, x1, y1) at `lod` overlapping `region`, with the
/// arithmetic of [`super::nodes_in_region`] (which lists them).
fn region_cells(world: &WorldDesc, lod: u8, region: Option<[f64; 4]>) -> [u64; 4] {
    let [gx, gy] = world.grid(lod);
    let [x0, y0, x1, y1] = match region {
        None => [0, 0, gx, gy],
        Some(r) => {
            let s = world.node_size_m(lod);
            let [ox, oy] = world.grid_origin_m;
            let cell = |v: f64, o: f64, g: u32| (((v - o) / s).floor().max(0.0) as u32).min(g);
            let end = |v: f64, o: f64, g: u32| (((v - o) / s).ceil().max(0.0) as u32).min(g);
            [cell(r[0], ox, gx), cell(r[1], oy, gy), end(r[2], ox, gx), end(r[3], oy, gy)]
        }
    };
    // An empty range where the region misses the world.
    [x0, y0, x1.max(x0), y1.max(y0)].map(u64::from)
}

/// Human byte count in binary units (`vista plan`, `vista bake`).
pub fn bytes(b: f64) -> String {
    const UNITS: [&str; 5] = ["B", "KiB", "MiB", "GiB", "TiB"];
    let mut v = b;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < UNITS.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 {
        format!("{v:.0} B")
    } else {
        format!("{v:.2} {}", UNITS[u])
    }
}

/// Seconds as the unit a person reads at a glance.
pub(super) fn duration(s: f64) -> String {
    if s < 90.0 {
        format!("{s:.0} s")
    } else if s < 90.0 * 60.0 {
        format!("{:.0} min", s / 60.0)
    } else if s < 48.0 * 3600.0 {
        format!("{:.1} h", s / 3600.0)
    } else {
        format!("{:.1} days", s / 86400.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::nodes_in_region;

    fn world(extent: f64, spacing: f64, lods: u32) -> WorldDesc {
        WorldDesc { extent_m: [extent, extent], spacing_m: spacing, lod_count: lods, ..WorldDesc::default() }
    }

    #[test]
    fn counts_match_the_node_lists() {
        let regions =
            [None, Some([0.0, 0.0, 64.0, 64.0]), Some([100.0, -50.0, 900.0, 333.0]), Some([5e3, 5e3, 6e3, 6e3])];
        for w in [world(2048.0, 2.0, 4), world(1000.0, 1.0, 6), WorldDesc::default()] {
            for region in regions {
                let plan = WorldPlan::new(&w, region);
                let listed = nodes_in_region(&w, region);
                for lod in 0..w.lod_count as u8 {
                    let n = listed.iter().filter(|id| id.lod == lod).count() as u64;
                    assert_eq!(plan.nodes_per_lod[lod as usize], n, "{w:?} {region:?} lod {lod}");
                }
                assert_eq!(plan.world_nodes, nodes_in_region(&w, None).len() as u64);
            }
        }
        // 2048 m at 2 m: 256 m sectors, 8 x 8; LOD k is ceil(8 / 2^k) a side.
        let plan = WorldPlan::new(&world(2048.0, 2.0, 4), None);
        assert_eq!(plan.nodes_per_lod, [64, 16, 4, 1]);
        assert_eq!(plan.disk_bytes, 85 * estimated_file_bytes(PayloadFormat::Bc));
    }

    #[test]
    fn each_limit_is_refused_naming_its_option() {
        let fine = WorldPlan::new(&WorldDesc::default(), None);
        let device = Limits {
            max_bake_disk_bytes: Some(DEFAULT_MAX_BAKE_DISK_BYTES),
            max_image_dimension_2d: Some(16384),
            max_image_array_layers: Some(2048),
            ..Limits::default()
        };
        assert_eq!(fine.check(&device), Ok(()));
        // 0.001 m spacing: 80 000 sectors a side; no allocation to find out.
        let tiny = WorldPlan::new(&WorldDesc { spacing_m: 0.001, ..WorldDesc::default() }, None);
        let e = tiny.check(&Limits::default()).unwrap_err();
        assert!(matches!(e, PlanError::TooManySectors { x: 80000, .. }), "{e}");
        let raised = Limits { max_sectors_per_side: 1 << 20, ..device.clone() };
        let e = tiny.check(&raised).unwrap_err();
        assert!(matches!(e, PlanError::NodeTextureTooLarge { .. }) && e.to_string().contains("--spacing"), "{e}");
        let big = WorldPlan::new(&world(100_000.0, 0.5, 6), None);
        let e = big.check(&device).unwrap_err();
        assert!(e.to_string().contains("--yes") && e.to_string().contains("--region"), "{e}");
        assert_eq!(big.check(&Limits { max_bake_disk_bytes: None, ..device.clone() }), Ok(()));
        let e = fine.clone().with_slots(4000).check(&device).unwrap_err();
        assert!(e.to_string().contains("--slots"), "{e}");
        for e in [tiny.check(&Limits::default()).unwrap_err(), big.check(&device).unwrap_err()] {
            assert_eq!(e.to_string().lines().count(), 1, "{e}");
        }
    }

    #[test]
    fn the_bake_time_comes_from_nodes_of_both_kinds() {
        let w = world(2048.0, 2.0, 4);
        let source = crate::world::ProceduralSource::new(1, w.extent_m, w.height_range_m).unwrap();
        let mut plan = WorldPlan::new(&w, None);
        plan.measure_bake(&source, &[], &BakeSettings::default(), 16);
        // A batch of 8 at LOD 0 and at LOD 1 at least; at most every cell
        // of LOD 1 (16) and 8 batches at LOD 0.
        let TimeBasis::Measured(n) = plan.time_basis else { panic!("not measured: {plan:?}") };
        assert!((16..=64 + 16).contains(&n), "{n} sample nodes");
        assert!(plan.node_seconds.is_finite() && plan.node_seconds > 0.0, "{}", plan.node_seconds);
        // Halton points cover the region: 8 of them hit 8 different cells.
        let cells: std::collections::HashSet<_> =
            (1..=8u64).map(|k| ((8.0 * halton(k, 2)) as u64, (8.0 * halton(k, 3)) as u64)).collect();
        assert_eq!(cells.len(), 8);
    }

    #[test]
    fn the_node_texture_is_one_texel_per_finest_node_padded_to_roots() {
        for w in [world(2048.0, 2.0, 4), world(1000.0, 1.0, 6), WorldDesc::default()] {
            // the finest nodes, padded to whole root nodes
            let step = 1u64 << w.root_lod();
            let padded = w.grid(0).map(|n| u64::from(n).div_ceil(step) * step);
            assert_eq!(WorldPlan::new(&w, None).node_texture, padded);
        }
    }
}

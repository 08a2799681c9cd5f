//! How a [`WorldPlan`] reads to a person (`vista plan`, the refusals).

use super::cache::estimated_file_bytes;
use super::errors::{ErrorTree, DEFAULT_HELD_TILE_BYTES};
use super::plan::*;
use std::fmt;

impl fmt::Display for WorldPlan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let w = &self.world;
        let [sx, sy] = self.sectors;
        writeln!(
            f,
            "sectors:  {sx} x {sy} of {} m ({} x {} m at {} m spacing, {} LODs)",
            w.sector_size_m(),
            w.extent_m[0],
            w.extent_m[1],
            w.spacing_m,
            w.lod_count
        )?;
        match self.region {
            Some(r) => writeln!(f, "region:   {},{} .. {},{} m", r[0], r[1], r[2], r[3])?,
            None => writeln!(f, "region:   whole world")?,
        }
        writeln!(f, "{:>5} {:>19} {:>14} {:>14}", "LOD", "grid", "nodes", "world nodes")?;
        for (lod, (g, n)) in self.grid_per_lod.iter().zip(&self.nodes_per_lod).enumerate() {
            let grid = format!("{} x {}", g[0], g[1]);
            writeln!(f, "{lod:>5} {grid:>19} {n:>14} {:>14}", g[0] * g[1])?;
        }
        writeln!(f, "{:>5} {:>19} {:>14} {:>14}", "total", "", self.nodes(), self.world_nodes)?;
        writeln!(
            f,
            "disk:     {} ({} per node file: {} payloads, zstd at the default world's ratio)",
            bytes(self.disk_bytes as f64),
            bytes(estimated_file_bytes(self.format) as f64),
            self.format
        )?;
        let [tw, th] = self.node_texture;
        writeln!(
            f,
            "GPU:      {} ({} resident slots {}, node texture {tw} x {th} {}); CPU shadow of the node texture {}",
            bytes(self.gpu_bytes() as f64),
            self.slots,
            bytes(self.gpu_slot_bytes as f64),
            bytes(self.node_texture_bytes as f64),
            bytes(self.node_texture_bytes as f64)
        )?;
        let basis = match self.time_basis {
            TimeBasis::Constant => "the built-in per-node constant".to_string(),
            TimeBasis::Measured(n) => format!("{n} sample nodes and sectors of errors computed now"),
        };
        writeln!(
            f,
            "bake:     about {} on {} threads: the error tree about {} ({:.2} us per LOD-0 sample per thread, {} \
             samples under the region's roots), the nodes about {} ({:.1} ms per node per thread); from {basis}; \
             cached nodes and trees are faster",
            duration(self.bake_seconds()),
            self.threads,
            duration(self.error_seconds()),
            1e6 * self.error_quad_seconds,
            self.error_quads,
            duration(self.node_bake_seconds()),
            1000.0 * self.node_seconds
        )?;
        let e = self.error_memory();
        writeln!(
            f,
            "errors:   the error tree's tiles are {} ({} of {} each); computing holds about {} at once ({} on {} \
             threads, each its tile and its file's bytes); a render keeps at most {} of them with a cache folder, \
             all without{}",
            bytes(e.tiles as f64),
            roots(e.roots),
            bytes(e.per_root as f64),
            bytes(e.peak as f64),
            roots(e.at_once),
            self.threads,
            bytes(DEFAULT_HELD_TILE_BYTES as f64),
            if e.peak >= LARGE_ERROR_MEMORY {
                "; more than this machine may have: fewer --lods make smaller roots"
            } else {
                ""
            }
        )
    }
}

fn roots(n: u64) -> String {
    format!("{n} root{}", if n == 1 { "" } else { "s" })
}

/// Memory of the error tree at which the plan and `vista render` warn.
pub const LARGE_ERROR_MEMORY: u64 = 1 << 30;

/// What the error tree of a plan's region takes in memory.
pub struct ErrorMemory {
    pub roots: u64,
    pub per_root: u64,
    /// Every root's tile.
    pub tiles: u64,
    /// Roots computed at once.
    pub at_once: u64,
    /// While computing: `at_once` tiles and their encoded files.
    pub peak: u64,
}

impl WorldPlan {
    /// The error tree's memory over the plan's region.
    pub fn error_memory(&self) -> ErrorMemory {
        let roots = self.nodes_per_lod.last().copied().unwrap_or(0);
        let per_root = ErrorTree::root_tile_bytes(&self.world);
        let at_once = roots.min(self.threads as u64);
        ErrorMemory { roots, per_root, tiles: roots * per_root, at_once, peak: at_once * 2 * per_root }
    }
}

//! How a [`WorldPlan`] reads to a person (`vista plan`, the refusals).

use super::cache::estimated_file_bytes;
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
        )
    }
}

//! Memory accounting for resident node payloads, CPU and GPU side.

use std::fmt;

use super::layout::{CONE_BLOCKS_PER_NODE, PATCHES_PER_NODE, SPLAT_RES};
use super::payload::BakedNode;
use super::texels::{PayloadFormat, TexelKind, ATLAS_TEXELS};

/// One payload kind's size per node.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct PayloadSize {
    pub name: &'static str,
    /// GPU atlas format and layer size.
    pub gpu_format: &'static str,
    /// Bytes in a [`BakedNode`] (vector contents).
    pub cpu_bytes: usize,
    /// Bytes of one atlas layer.
    pub gpu_bytes: usize,
}

/// Per-node payload sizes and totals for `nodes` resident nodes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MemoryReport {
    pub nodes: usize,
    pub kinds: Vec<PayloadSize>,
}

impl MemoryReport {
    /// The report for the default payload format.
    pub fn new(nodes: usize) -> Self {
        Self::for_format(nodes, PayloadFormat::default())
    }

    pub fn for_format(nodes: usize, format: PayloadFormat) -> Self {
        let h = ATLAS_TEXELS;
        let sp = SPLAT_RES * SPLAT_RES;
        let (p, c) = (PATCHES_PER_NODE, CONE_BLOCKS_PER_NODE);
        let (normal, albedo) = (TexelKind::Normal, TexelKind::Albedo);
        let kind = |name, gpu_format, cpu_bytes, gpu_bytes| PayloadSize { name, gpu_format, cpu_bytes, gpu_bytes };
        MemoryReport {
            nodes,
            kinds: vec![
                kind("height", "R16_UNORM 132x132", h * 2, h * 2),
                kind("normal", format.describe(normal), format.layer_bytes(normal), format.layer_bytes(normal)),
                kind("albedo", format.describe(albedo), format.layer_bytes(albedo), format.layer_bytes(albedo)),
                kind("splat", "R8_UINT 65x65", sp, sp),
                kind("patch min/max", "RG16_UINT 16x16", p * 4, p * 4),
                kind("patch cones", "RGBA32F 8x8", c * 16, c * 16),
                kind("patch holes", "R8_UINT 16x16", p, p),
                kind("patch errors", "RG32F 16x16", p * 8, p * 8),
                // A control-map world's words (`with_control`).
                kind("control", "R16_UINT 65x65", 0, 0),
                // The per-triangle rule's vertex numbers (`with_vertex_bounds`).
                kind("vertex bounds", "R32_UINT 132x132", 0, 0),
                // id, min/max, error, representation error; on the GPU the
                // 2 x u32 node description and the f32 LOD error.
                kind("node scalars", "2 x u32 desc + f32 error", 9 + 4 + 4 + 4, 12),
            ],
        }
    }

    /// The report of a control-map world, whose nodes carry control words.
    pub fn with_control(mut self) -> Self {
        let sp = SPLAT_RES * SPLAT_RES * 2;
        let k = self.kinds.iter_mut().find(|k| k.name == "control").expect("the control kind");
        (k.cpu_bytes, k.gpu_bytes) = (sp, sp);
        self
    }

    /// The report of a renderer drawing with the per-triangle rule, whose
    /// nodes carry their vertices' numbers.
    pub fn with_vertex_bounds(mut self) -> Self {
        let b = super::texels::ATLAS_SIDE * super::texels::ATLAS_SIDE * 4;
        let k = self.kinds.iter_mut().find(|k| k.name == "vertex bounds").expect("the vertex bounds kind");
        (k.cpu_bytes, k.gpu_bytes) = (b, b);
        self
    }

    pub fn cpu_bytes_per_node(&self) -> usize {
        self.kinds.iter().map(|k| k.cpu_bytes).sum()
    }

    pub fn gpu_bytes_per_node(&self) -> usize {
        self.kinds.iter().map(|k| k.gpu_bytes).sum()
    }

    pub fn cpu_total(&self) -> usize {
        self.cpu_bytes_per_node() * self.nodes
    }

    pub fn gpu_total(&self) -> usize {
        self.gpu_bytes_per_node() * self.nodes
    }
}

/// Payload bytes actually held by a node (vector contents only).
pub fn node_cpu_bytes(n: &BakedNode) -> usize {
    n.heights.len() * 2
        + n.normals.len()
        + n.albedo.len()
        + n.splat.len()
        + n.control.len() * 2
        + n.patch_min_max.len() * 4
        + n.patch_cones.len() * 16
        + n.patch_holes.len()
        + n.patch_errors.len() * 8
        + n.vertex_bounds.len() * 4
}

fn mib(b: usize) -> f64 {
    b as f64 / (1024.0 * 1024.0)
}

impl fmt::Display for MemoryReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "{:<14} {:<22} {:>10} {:>10} {:>12} {:>12}",
            "payload", "GPU format", "CPU B/node", "GPU B/node", "CPU MiB", "GPU MiB"
        )?;
        writeln!(f, "{}", "-".repeat(85))?;
        for k in &self.kinds {
            writeln!(
                f,
                "{:<14} {:<22} {:>10} {:>10} {:>12.2} {:>12.2}",
                k.name,
                k.gpu_format,
                k.cpu_bytes,
                k.gpu_bytes,
                mib(k.cpu_bytes * self.nodes),
                mib(k.gpu_bytes * self.nodes)
            )?;
        }
        writeln!(f, "{}", "-".repeat(85))?;
        writeln!(
            f,
            "{:<37} {:>10} {:>10} {:>12.2} {:>12.2}",
            format!("total for {} nodes", self.nodes),
            self.cpu_bytes_per_node(),
            self.gpu_bytes_per_node(),
            mib(self.cpu_total()),
            mib(self.gpu_total())
        )
    }
}

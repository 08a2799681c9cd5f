//! What one frame drew: patch counts per culling stage, triangles, nodes per
//! LOD against what the camera wanted, and the streaming counters. Read back
//! after the frames (waits): for tools and tests, not for an engine's frame
//! loop.

use crate::error::Result;
use crate::gpu::Context;
use crate::passes::cull_patches::CullCounters;
use crate::passes::emit_triangles::TriangleListHeader;
use crate::passes::select_patches::SelectHeader;
use crate::reference::wanted_finer_cpu;
use crate::render::renderer::TerrainRenderer;
use crate::scene::view::View;
use crate::terrain::TerrainStats;
use serde::Serialize;

pub use crate::render::telemetry::TRIANGLES_PER_PATCH;

#[derive(Debug, Clone, Serialize)]
pub struct RenderStats {
    /// The per-triangle rule's list header (`None` on the per-patch path,
    /// whose numbers are `patches` and `select`).
    pub triangles: Option<TriangleListHeader>,
    /// Triangles the per-triangle rule's phase 1 list of that frame held
    /// (it grows, frames late, to what the frames emit).
    pub triangle_capacity: Option<u32>,
    pub patches: CullCounters,
    /// Per-patch LOD selection: patches coarsened and refined, seam conflicts.
    pub select: SelectHeader,
    /// The error bound the frame achieved (px): the largest projected
    /// error of any drawn patch; the target when the budget allowed it.
    pub bound_px: f32,
    /// The target it was asked for (px).
    pub target_px: f32,
    /// Patch instances x triangles per patch (hole triangles included: they
    /// are submitted and dropped by the rasterizer).
    pub triangles_drawn: u64,
    pub node_count: u32,
    /// Final nodes drawn, by LOD.
    pub nodes_per_lod: Vec<u32>,
    /// Of those, nodes the camera wants finer whose children are not resident.
    pub wanted_finer_per_lod: Vec<u32>,
    pub overflow: u32,
    pub missing_roots: u32,
    /// Streaming after the frame: residency, failed loads, retries, nodes
    /// given up.
    pub streaming: TerrainStats,
    /// Control-map tiles whose tri-planar background samples at most 1, 2
    /// and 3 planes (`None` without the control-map flavour).
    pub plane_tiles: Option<[u32; 3]>,
    /// Each built effect's numbers by its key (`virtual_texture`,
    /// `grass`, `cliff_meshes`, ...), as its folder reports them.
    #[serde(flatten)]
    pub effects: std::collections::BTreeMap<&'static str, serde_json::Value>,
    /// What `vista render` prints of them, effect by effect.
    #[serde(skip)]
    pub effect_lines: Vec<String>,
}

/// The last recorded frame's numbers; waits for the GPU.
pub fn collect(ctx: &Context, renderer: &TerrainRenderer, view: &View) -> Result<RenderStats> {
    let c = renderer.read_counters(ctx)?;
    let terrain = &renderer.terrain;
    let lods = terrain.world.lod_count as usize;
    let wanted = wanted_finer_cpu(&terrain.tree.shadow, &terrain.world, &view.traverse_params());
    let mut effects = Vec::new();
    for e in renderer.built_effects() {
        effects.extend(e.stats(ctx, &c)?);
    }
    let triangles = match &renderer.triangles {
        Some(t) => Some(t.emit.read_header(ctx)?),
        None => None,
    };
    // The per-triangle rule draws no patch: the patch lists hold nothing of this frame.
    let (patches, select) = match triangles {
        Some(_) => (CullCounters::default(), SelectHeader::default()),
        None => (c.cull, c.select),
    };
    Ok(RenderStats {
        triangles,
        triangle_capacity: renderer.triangles.as_ref().map(|t| t.emit.capacity(false)),
        patches,
        select,
        bound_px: triangles.map_or(c.cull.bound_px, |t| t.bound_px()),
        target_px: view.target_error_px,
        triangles_drawn: triangles.map_or(c.triangles, |t| u64::from(t.drawn())),
        node_count: c.traverse.nodes,
        nodes_per_lod: c.traverse.nodes_per_lod,
        wanted_finer_per_lod: wanted[..lods].to_vec(),
        overflow: c.traverse.overflow,
        missing_roots: c.traverse.missing_roots,
        streaming: terrain.stats(),
        plane_tiles: (renderer.shade.allowed & crate::shaders::consts::FLAVOUR_CONTROL_MAP != 0)
            .then_some(c.plane_tiles),
        effects: effects.iter().map(|e| (e.key, e.value.clone())).collect(),
        effect_lines: effects.into_iter().flat_map(|e| e.lines).collect(),
    })
}

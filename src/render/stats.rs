//! What one frame drew: patch counts per culling stage, triangles, nodes per
//! LOD against what the camera wanted, and the streaming counters. Read back
//! after the frames (waits): for tools and tests, not for an engine's frame
//! loop.

use crate::effects::grass::GrassCounters;
use crate::effects::virtual_texture::{state::VtCounters, VirtualTexture};
use crate::error::Result;
use crate::gpu::Context;
use crate::passes::cull_patches::CullCounters;
use crate::passes::select_patches::SelectHeader;
use crate::reference::wanted_finer_cpu;
use crate::render::renderer::TerrainRenderer;
use crate::scene::view::View;
use crate::shaders::consts::{GRASS_BLADES, GRASS_BLADE_VERTICES};
use crate::terrain::TerrainStats;
use serde::Serialize;

pub use crate::render::telemetry::TRIANGLES_PER_PATCH;

#[derive(Debug, Clone, Serialize)]
pub struct RenderStats {
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
    /// Effect `virtual_texture`: its pages and memory.
    pub virtual_texture: Option<VtStats>,
    /// Effect `grass`: its counters, triangles and memory.
    pub grass: Option<GrassStats>,
    /// Effect `cliff_meshes`: the last build's cells and triangles.
    pub cliff_meshes: Option<crate::effects::cliff_meshes::CliffCounters>,
}

/// Effect `grass` in the last recorded frame.
#[derive(Debug, Clone, Serialize)]
pub struct GrassStats {
    #[serde(flatten)]
    pub counters: GrassCounters,
    /// Triangles of the tufts drawn.
    pub triangles: u64,
    pub memory_bytes: u64,
}

/// The virtual texture after the last recorded frame.
#[derive(Debug, Clone, Serialize)]
pub struct VtStats {
    #[serde(flatten)]
    pub counters: VtCounters,
    /// Share of the requested pages that were resident.
    pub hit_rate: f64,
    pub cache_tiles: u32,
    /// Bytes of the state buffer (sub-textures and indirection), the page
    /// statuses and the cache images.
    pub indirection_bytes: u64,
    pub status_bytes: u64,
    pub cache_bytes: u64,
    /// Effect `decals`: decals drawn into the pages (0: off).
    pub decals: u32,
}

impl VtStats {
    pub fn of(vt: &VirtualTexture) -> VtStats {
        let [indirection_bytes, status_bytes, cache_bytes] = vt.layout().memory_bytes();
        let counters = vt.counters();
        VtStats {
            counters,
            hit_rate: counters.hit_rate(),
            cache_tiles: vt.layout().tile_count(),
            indirection_bytes,
            status_bytes,
            cache_bytes,
            decals: vt.decals().len() as u32,
        }
    }
}

/// The last recorded frame's numbers; waits for the GPU.
pub fn collect(ctx: &Context, renderer: &TerrainRenderer, view: &View) -> Result<RenderStats> {
    let c = renderer.read_counters(ctx)?;
    let terrain = &renderer.terrain;
    let lods = terrain.world.lod_count as usize;
    let wanted = wanted_finer_cpu(&terrain.tree.shadow, &terrain.world, &view.traverse_params());
    Ok(RenderStats {
        patches: c.cull,
        select: c.select,
        bound_px: c.cull.bound_px,
        target_px: view.target_error_px,
        triangles_drawn: c.triangles,
        node_count: c.traverse.nodes,
        nodes_per_lod: c.traverse.nodes_per_lod,
        wanted_finer_per_lod: wanted[..lods].to_vec(),
        overflow: c.traverse.overflow,
        missing_roots: c.traverse.missing_roots,
        streaming: terrain.stats(),
        plane_tiles: (renderer.shade.allowed & crate::shaders::consts::FLAVOUR_CONTROL_MAP != 0)
            .then_some(c.plane_tiles),
        virtual_texture: renderer.virtual_texture.as_ref().map(VtStats::of),
        grass: renderer.near.grass.as_ref().zip(c.grass).map(|(g, counters)| GrassStats {
            counters,
            triangles: u64::from(counters.drawn) * u64::from(GRASS_BLADES * GRASS_BLADE_VERTICES / 3),
            memory_bytes: g.memory().iter().map(|(_, b)| b).sum(),
        }),
        cliff_meshes: match &renderer.near.cliff_meshes {
            Some(c) => Some(c.read(ctx)?.0),
            None => None,
        },
    })
}

//! Every GPU counter of one frame, as the telemetry brings it back
//! (`render::telemetry`): the core passes' and each effect's, raw.

use crate::passes::cull_patches::CullCounters;
use crate::passes::select_patches::SelectHeader;
use crate::scene::effect::Effect;
use serde::Serialize;

/// The traversal's counters of one frame.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct TraverseCounters {
    pub nodes: u32,
    /// Nodes kept coarser because a list was full.
    pub overflow: u32,
    /// Valid roots not resident yet.
    pub missing_roots: u32,
    /// Final nodes per LOD, LOD 0 first.
    pub nodes_per_lod: Vec<u32>,
}

/// Triangles of one patch instance (8x8 quads, 2 each).
pub const TRIANGLES_PER_PATCH: u64 = (crate::world::PATCH_QUADS * crate::world::PATCH_QUADS * 2) as u64;

/// Every GPU counter of one frame.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct FrameCounters {
    /// The renderer's frame number (as `FrameTimings::frame`).
    pub frame: u64,
    pub traverse: TraverseCounters,
    /// Per-patch LOD selection: patches coarsened, refined below LOD 0,
    /// seam conflicts.
    pub select: SelectHeader,
    pub cull: CullCounters,
    /// Instances of each draw: phase 1 solid, phase 1 with holes, phase 2
    /// solid, phase 2 with holes (0 where the list does not exist).
    pub instances: [u32; 4],
    /// Triangles submitted by every draw.
    pub triangles: u64,
    /// Tiles listed per shader variant (index = flavour bits).
    pub tiles: Vec<u32>,
    /// Control-map tiles whose tri-planar background samples at most 1, 2
    /// and 3 planes (the tightened blend).
    pub plane_tiles: [u32; 3],
    /// Each effect's counters (`FrameEffect::counters`), as the GPU wrote
    /// them: the effect reads its own.
    pub effects: Vec<(Effect, Vec<u8>)>,
    /// The per-triangle rule's lists' headers, phase 1's and phase 2's
    /// (zero where phase 2 is not built); None under the patch rule.
    pub triangle_lists: Option<[crate::passes::emit_triangles::TriangleListHeader; 2]>,
}

impl FrameCounters {
    /// The bytes of `effect`'s counters (None: it has none).
    pub fn of(&self, effect: Effect) -> Option<&[u8]> {
        self.effects.iter().find(|(e, _)| *e == effect).map(|(_, b)| &b[..])
    }
}

//! CPU reference of `lod_map`: the LOD of the final node covering each
//! sector. No Vulkan.

use crate::shaders::consts::NO_LOD;
use crate::terrain::quadtree::texture_extent;
use crate::terrain::selection::TraverseResult;
use crate::world::WorldDesc;

/// The LOD map for a final node list: one byte per sector over the node
/// texture's padded extent, NO_LOD where no listed node covers it.
pub fn lod_map_cpu(result: &TraverseResult, world: &WorldDesc) -> Vec<u8> {
    let [w, h] = texture_extent(world);
    let mut map = vec![NO_LOD as u8; (w * h) as usize];
    for (n, _) in &result.nodes {
        let k = 1u32 << n.lod;
        for y in n.y * k..((n.y + 1) * k).min(h) {
            for x in n.x * k..((n.x + 1) * k).min(w) {
                map[(y * w + x) as usize] = n.lod;
            }
        }
    }
    map
}

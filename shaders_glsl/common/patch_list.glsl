// The visible patch list written by cull_patches and drawn by
// terrain_geometry: indexed-indirect draw args first (instance count =
// patches), then per-stage counters, then one uvec2 per patch.
#ifndef VISTA_PATCH_LIST_GLSL
#define VISTA_PATCH_LIST_GLSL

struct PatchListHeader {
    uint index_count;     // VkDrawIndexedIndirectCommand
    uint instance_count;  // = patches drawn
    uint first_index;
    int vertex_offset;
    uint first_instance;
    uint patches_in;      // 64 per listed node
    uint after_frustum;
    uint after_cone;
    uint after_hole;
    uint after_occlusion; // cull_occluded: patches the pyramid left visible
    uint pad1;
    uint pad2;
};

#include "constants.glsl"

// Patch record: x = packed node (node_list.glsl); y = slot | patch index
// (py * 8 + px) | LOD deltas, one per edge in EDGE_* order (constants.glsl).
uint pack_patch(uint slot, uint index, uint deltas) {
    return slot | (index << PATCH_INDEX_SHIFT) | (deltas << PATCH_DELTA_SHIFT);
}
uint patch_slot(uvec2 p) { return bitfieldExtract(p.y, 0, int(SLOT_BITS)); }
uint patch_index(uvec2 p) { return (p.y >> PATCH_INDEX_SHIFT) & PATCH_INDEX_MASK; }
uint patch_delta(uvec2 p, uint edge) {
    return bitfieldExtract(p.y, int(PATCH_DELTA_SHIFT + PATCH_DELTA_BITS * edge), int(PATCH_DELTA_BITS));
}

#endif

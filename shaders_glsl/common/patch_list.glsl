// The visible patch list written by cull_patches and drawn by
// terrain_geometry: indexed-indirect draw args first (instance count =
// patches), then per-stage counters, then one uvec4 per patch.
#ifndef VISTA_PATCH_LIST_GLSL
#define VISTA_PATCH_LIST_GLSL

struct PatchListHeader {
    uint index_count;     // VkDrawIndexedIndirectCommand
    uint instance_count;  // = patches drawn
    uint first_index;
    int vertex_offset;
    uint first_instance;
    uint patches_in;      // 256 per listed node
    uint after_frustum;
    uint after_cone;
    uint after_hole;
    uint after_occlusion; // cull_occluded: patches the pyramid left visible
    uint bound_bits;      // largest projected error (px) of a listed patch, as float bits (atomicMax)
    uint seam_overflow;   // edges whose neighbour is more than MAX_LOD_DELTA coarser (clamped)
};

#include "constants.glsl"

// Patch record: x = packed node (node_list.glsl) the patch is drawn from;
// y = slot | patch index (py * 16 + px) | LOD deltas, one per edge in EDGE_*
// order (constants.glsl); z = refinement level below LOD 0 (0..2) | the
// sub-patch index (row-major over 2^r x 2^r) << PATCH_SUB_SHIFT; w unused.
uint pack_patch(uint slot, uint index, uint deltas) {
    return slot | (index << PATCH_INDEX_SHIFT) | (deltas << PATCH_DELTA_SHIFT);
}
uint pack_refine(uint r, uint sub) { return r | (sub << PATCH_SUB_SHIFT); }
uint patch_slot(uvec4 p) { return bitfieldExtract(p.y, 0, int(SLOT_BITS)); }
uint patch_index(uvec4 p) { return (p.y >> PATCH_INDEX_SHIFT) & PATCH_INDEX_MASK; }
uint patch_delta(uvec4 p, uint edge) {
    return bitfieldExtract(p.y, int(PATCH_DELTA_SHIFT + PATCH_DELTA_BITS * edge), int(PATCH_DELTA_BITS));
}
uint patch_refine(uvec4 p) { return p.z & PATCH_REFINE_MASK; }
uint patch_sub(uvec4 p) { return p.z >> PATCH_SUB_SHIFT; }

#endif

// The traversal's output as every later pass reads it: the header (indirect
// dispatch args, counts) and the packed node reference. One declaration for
// traverse, lod_map, cull_patches and terrain_geometry.
#ifndef VISTA_NODE_LIST_GLSL
#define VISTA_NODE_LIST_GLSL

#include "constants.glsl"

// Packed node reference (constants.glsl NODE_REF_*).
uint pack_node(uint lod, uint x, uint y) { return (lod << NODE_REF_LOD_SHIFT) | (y << NODE_REF_Y_SHIFT) | x; }
uint node_lod(uint n) { return n >> NODE_REF_LOD_SHIFT; }
uint node_x(uint n) { return n & NODE_REF_COORD_MASK; }
uint node_y(uint n) { return (n >> NODE_REF_Y_SHIFT) & NODE_REF_COORD_MASK; }

struct TraverseHeader {
    uint dispatch_x;     // indirect args for lod_map / cull_patches: one workgroup per node
    uint dispatch_y;
    uint dispatch_z;
    uint node_count;
    uint overflow;       // nodes kept coarser because a list was full
    uint missing_roots;  // valid roots not resident yet (coverage gap)
    uint pad0;
    uint pad1;
    uint lod_counts[MAX_LEVELS];
};

#endif

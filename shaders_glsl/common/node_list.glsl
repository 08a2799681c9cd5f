// The traversal's output as every later pass reads it: the header (indirect
// dispatch args, counts) and the packed node reference. One declaration for
// traverse, lod_map, cull_patches and terrain_geometry.
#ifndef VISTA_NODE_LIST_GLSL
#define VISTA_NODE_LIST_GLSL

// Packed node reference: lod (4 bits) << 28 | y (14 bits) << 14 | x (14 bits).
uint pack_node(uint lod, uint x, uint y) { return (lod << 28) | (y << 14) | x; }
uint node_lod(uint n) { return n >> 28; }
uint node_x(uint n) { return n & 0x3FFFu; }
uint node_y(uint n) { return (n >> 14) & 0x3FFFu; }

struct TraverseHeader {
    uint dispatch_x;     // indirect args for lod_map / cull_patches: one workgroup per node
    uint dispatch_y;
    uint dispatch_z;
    uint node_count;
    uint overflow;       // nodes kept coarser because a list was full
    uint missing_roots;  // valid roots not resident yet (coverage gap)
    uint pad0;
    uint pad1;
    uint lod_counts[16];
};

#endif

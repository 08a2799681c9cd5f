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
    uint pad0;
    uint pad1;
    uint pad2;
};

// Patch record: x = packed node (node_list.glsl); y = slot (10 bits) |
// patch index py * 8 + px (6 bits) << 10 | LOD deltas << 16, 4 bits per
// edge: west, east, south, north (bits 16, 20, 24, 28).
const uint EDGE_WEST = 0u;
const uint EDGE_EAST = 1u;
const uint EDGE_SOUTH = 2u;
const uint EDGE_NORTH = 3u;

uint patch_slot(uvec2 p) { return p.y & 0x3FFu; }
uint patch_index(uvec2 p) { return (p.y >> 10) & 0x3Fu; }
uint patch_delta(uvec2 p, uint edge) { return (p.y >> (16u + 4u * edge)) & 0xFu; }

#endif

// The per-triangle rule's index list, written by emit_triangles and drawn
// by terrain_triangles: indexed-indirect draw args first (index count =
// 3 x the triangles kept), the frame's counters, then 3 vertex codes per
// triangle (TRIANGLE_* in constants.glsl).
#ifndef VISTA_TRIANGLE_LIST_GLSL
#define VISTA_TRIANGLE_LIST_GLSL

#include "constants.glsl"

struct TriangleListHeader {
    uint index_count;     // VkDrawIndexedIndirectCommand
    uint instance_count;  // 1
    uint first_index;
    int vertex_offset;
    uint first_instance;
    uint triangles;       // emitted (kept or not)
    uint overflow;        // emitted past the list's capacity (not drawn)
    uint clamped;         // vertices the rule splits whose neighbour node lacks them (drawn unsplit)
    uint forced;          // splits made for a finer neighbour's corners
    uint culled;          // subtrees outside the frustum (not emitted)
    uint bound_bits;      // largest projected error (px) of an unsplit drawn vertex, as float bits (atomicMax)
    uint grid_bound_bits; // the same for the finest grid's cells (the node's own error)
};

// `g`: the point in lattice units (2^-REFINE_LEVELS grid steps).
uint triangle_vertex(uint slot, ivec2 g) {
    return slot | (uint(g.x) << TRIANGLE_X_SHIFT) | (uint(g.y) << TRIANGLE_Y_SHIFT);
}
uint triangle_vertex_slot(uint v) { return bitfieldExtract(v, 0, int(SLOT_BITS)); }
ivec2 triangle_vertex_lattice(uint v) {
    return ivec2((v >> TRIANGLE_X_SHIFT) & TRIANGLE_COORD_MASK, (v >> TRIANGLE_Y_SHIFT) & TRIANGLE_COORD_MASK);
}

#endif

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
    uint unrefined;       // LOD-0 cell halves drawn whole, the fine list full (their node's error in grid_bound_bits)
};

// `g`: the point in lattice units (2^-REFINE_LEVELS grid steps); the
// layout is constants.glsl's TRIANGLE_*.
uint triangle_vertex(uint slot, ivec2 g) {
    uvec2 u = uvec2(g);
    const uint low = (1u << TRIANGLE_LOW_BITS) - 1u;
    uvec2 hi = u >> TRIANGLE_LOW_BITS;
    return (u.x & low) | ((u.y & low) << TRIANGLE_LOW_BITS) | (hi.x << (2u * TRIANGLE_LOW_BITS))
        | (hi.y << (2u * TRIANGLE_LOW_BITS + TRIANGLE_HIGH_BITS)) | (slot << TRIANGLE_SLOT_SHIFT);
}
uint triangle_vertex_slot(uint v) { return v >> TRIANGLE_SLOT_SHIFT; }
ivec2 triangle_vertex_lattice(uint v) {
    int l = int(TRIANGLE_LOW_BITS), h = int(TRIANGLE_HIGH_BITS);
    uint x = bitfieldExtract(v, 0, l) | (bitfieldExtract(v, 2 * l, h) << TRIANGLE_LOW_BITS);
    uint y = bitfieldExtract(v, l, l) | (bitfieldExtract(v, 2 * l + h, h) << TRIANGLE_LOW_BITS);
    return ivec2(x, y);
}

#endif

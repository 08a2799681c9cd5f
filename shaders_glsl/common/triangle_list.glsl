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
    uint holes;           // subtrees inside a patch of holes only (not emitted)
    uint facing_away;     // triangles left whole that face away from the camera (not emitted)
    uint outside;         // triangles left whole outside the frustum, their subtree's box not (not emitted)
};

// The bits above the low byte (high bits of x and y, then the slot) mixed
// into one byte: the low byte is x's and y's low bits XOR this, so codes
// of one window stay apart and points of a coarse cut (low bits all zero)
// spread over the byte too (TRIANGLE_* in constants.glsl says why).
uint triangle_vertex_mix(uint upper) { return (upper * TRIANGLE_MIX_MUL) >> 24u; }

// `g`: the point in lattice units (2^-REFINE_LEVELS grid steps); the
// layout is constants.glsl's TRIANGLE_*.
uint triangle_vertex(uint slot, ivec2 g) {
    uvec2 u = uvec2(g);
    const uint low = (1u << TRIANGLE_LOW_BITS) - 1u;
    uvec2 hi = u >> TRIANGLE_LOW_BITS;
    uint upper = hi.x | (hi.y << TRIANGLE_HIGH_BITS) | (slot << (2u * TRIANGLE_HIGH_BITS));
    uint bottom = (u.x & low) | ((u.y & low) << TRIANGLE_LOW_BITS);
    return (bottom ^ triangle_vertex_mix(upper)) | (upper << (2u * TRIANGLE_LOW_BITS));
}
uint triangle_vertex_slot(uint v) { return v >> TRIANGLE_SLOT_SHIFT; }
ivec2 triangle_vertex_lattice(uint v) {
    int l = int(TRIANGLE_LOW_BITS), h = int(TRIANGLE_HIGH_BITS);
    uint upper = v >> (2u * TRIANGLE_LOW_BITS);
    uint bottom = bitfieldExtract(v, 0, 2 * l) ^ triangle_vertex_mix(upper);
    uint x = bitfieldExtract(bottom, 0, l) | (bitfieldExtract(upper, 0, h) << TRIANGLE_LOW_BITS);
    uint y = bitfieldExtract(bottom, l, l) | (bitfieldExtract(upper, h, h) << TRIANGLE_LOW_BITS);
    return ivec2(x, y);
}

#endif

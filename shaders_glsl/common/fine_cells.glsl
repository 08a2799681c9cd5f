// The fine list: the LOD-0 cell halves emit_triangles' cut reaches, for
// emit_fine to walk below the samples. Its header is emit_fine's indirect
// dispatch (a workgroup per FINE_GROUP_SIZE cells, counted as they are
// appended), then one word a cell half.
#ifndef VISTA_FINE_CELLS_GLSL
#define VISTA_FINE_CELLS_GLSL

#include "constants.glsl"

struct FineCellsHeader {
    uint groups_x;  // VkDispatchIndirectCommand: ceil(cells within the capacity / FINE_GROUP_SIZE)
    uint groups_y;  // 1
    uint groups_z;  // 1
    uint count;     // cell halves appended (past the capacity, EmitPush.fine_capacity, too)
};

// A cell half: its slot, and its index among the node's bintree's
// triangles at depth 2 x EMIT_THREAD_DEPTH (the grid's cell halves).
uint fine_cell(uint slot, uint index) {
    return slot | (index << SLOT_BITS);
}
uint fine_cell_slot(uint c) { return bitfieldExtract(c, 0, int(SLOT_BITS)); }
uint fine_cell_index(uint c) { return c >> SLOT_BITS; }

#endif

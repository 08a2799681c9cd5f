#version 460
#extension GL_GOOGLE_include_directive : require
// The per-triangle rule below a LOD-0 node's samples: one invocation per
// cell half emit_triangles queued in the fine list (an indirect dispatch
// whose size it counted), walking the bisection down to the finest lattice
// on the Catmull-Rom surface (emit_triangles_fine.glsl says what numbers a
// vertex there takes and why the cut stays conforming) and appending what
// it leaves whole to the same index list as emit_triangles' phase. A pass
// of its own so that the workgroups of nodes with nothing to refine do not
// pay for the walk (lavapipe runs a loop's body, masked, even where no
// invocation enters it).
#include "emit_triangles_core.glsl"

layout(local_size_x = FINE_GROUP_SIZE) in;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= min(fine.header.count, pc.fine_capacity)) {
        return;
    }
    uint c = fine.cells[i];
    uint slot = fine_cell_slot(c);
    enter_node(slot_nodes.nodes[slot], slot);
    walk_cell(triangle_at(2u * EMIT_THREAD_DEPTH, fine_cell_index(c)));
    flush();
}

// Procedural cliff meshes (effect cliff_meshes, effects/cliff_meshes):
// what cliff_mesh_build writes and cliff_meshes draws. A cell of the world
// grid whose ground is steep gets a CLIFF_CELL_QUADS^2 patch of the
// terrain pushed outwards along its normal by a world-anchored noise, by
// nothing where the slope is under the threshold, so the mesh leaves the
// height field exactly there: shape the height field cannot hold (bulges,
// overhangs), watertight to it.
#ifndef VISTA_CLIFF_MESH_GLSL
#define VISTA_CLIFF_MESH_GLSL

// The draw's arguments (VkDrawIndexedIndirectCommand), then the counters.
struct CliffHeader {
    uint index_count;
    uint instance_count;  // cells listed (instances drawn)
    uint first_index;
    int vertex_offset;
    uint first_instance;
    uint tested;          // cells within the radius
    uint overflow;        // cliff cells past the capacity (not drawn)
    uint pad;
};

// One vertex: xyz world metres, w the octahedral normal code's bits (x | y << 8).
struct CliffVertex {
    vec4 p;
};

#endif

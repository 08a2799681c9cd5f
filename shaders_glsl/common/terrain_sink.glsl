// Cells of a square of the world grid where another surface replaces the
// height field (effect cliff_meshes' meshed cells): the terrain's fragments
// there are pushed behind by `sink_m` along their normal, so the mesh that
// lies on the height field at its own triangulation wins the depth test
// without a fight, and the terrain still covers every pixel it covered (no
// hole opens where the two triangulations part). An effect writes it; the
// terrain's fragment stage reads it in its SINK variant.
#ifndef VISTA_TERRAIN_SINK_GLSL
#define VISTA_TERRAIN_SINK_GLSL

struct TerrainSinkHeader {
    ivec2 cell0;    // the square's first cell
    uint side;      // cells a side (0: none sunk)
    float cell_m;
    float sink_m;   // how far behind, along the normal (m)
    uint pad0;
    uint pad1;
    uint pad2;
};

// The most the push grows along a grazing ray: the normal's share of the
// ray is clamped to this, so a sunk fragment moves at most sink_m / it.
#define TERRAIN_SINK_MIN_COSINE 0.05

#endif

// The per-variant tile lists of classify_tiles, drawn by gbuffer_tiles:
// first one VkDrawIndirectCommand per variant (6 vertices, one instance per
// tile: the instance count is the append counter), 4 plane counters
// (classify_tiles.comp), then `capacity` tile entries per variant, entry =
// x | y << 16 in tiles.
#ifndef VISTA_TILE_LISTS_GLSL
#define VISTA_TILE_LISTS_GLSL
#include "constants.glsl"

struct TileDrawArgs {
    uint vertex_count;
    uint instance_count;
    uint first_vertex;
    uint first_instance;
};

// The lists' members, for a block declared `buffer TileLists { ... } lists`
// (read-write in classify_tiles, read-only in gbuffer_tiles).
#define TILE_LISTS_MEMBERS                                                         \
    TileDrawArgs args[FLAVOUR_VARIANTS];                                           \
    uint plane_tiles[4]; /* control-map tiles sampling 1, 2, 3 planes; [3] unused */ \
    uint tiles[];

struct TilePush {
    uint tiles_x;
    uint tiles_y;
    uint capacity;  // entries per variant list
    uint force_variant;  // non-zero: every tile with terrain goes to this variant (one-shader mode)
    uint width;     // target size, pixels
    uint height;
    uint pad1;
    uint pad2;
};

#endif

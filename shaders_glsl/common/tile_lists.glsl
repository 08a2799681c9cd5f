// The per-variant tile lists of classify_tiles, drawn by gbuffer_tiles:
// first one VkDrawIndirectCommand per variant (6 vertices, one instance per
// tile: the instance count is the append counter), then `capacity` tile
// entries per variant, entry = x | y << 16 in tiles.
#ifndef VISTA_TILE_LISTS_GLSL
#define VISTA_TILE_LISTS_GLSL
#include "constants.glsl"

struct TileDrawArgs {
    uint vertex_count;
    uint instance_count;
    uint first_vertex;
    uint first_instance;
};

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

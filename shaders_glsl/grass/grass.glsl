// Grass (effect grass): what grass_place writes and grass_draw reads, and
// the per-cell random numbers both the GPU and the CPU twin
// (effects/grass.rs, `place_cpu`) draw from the integer world cell, so a
// tuft never moves when the camera does.
#ifndef VISTA_GRASS_GLSL
#define VISTA_GRASS_GLSL
#include "hashed_noise.glsl"

// One placed tuft.
struct GrassInstance {
    vec4 position;  // xyz: where it stands (world m); w: its height (m, faded)
    ivec2 cell;     // the world cell it belongs to
    uint packed;    // material id | rotation (0..255 of a turn) << 8 | lean (0..255) << 16
    uint normal;    // the terrain's octahedral normal there: x | y << 8
};

// What a material grows (one per material id).
struct GrassRule {
    float density;  // tufts per cell (density per m^2 x cell area), 0..1
    float height;   // height scale of its tufts
    float pad0;
    float pad1;
    vec4 tint;      // rgb: multiplies the pigment; a unused
};

// The draw's arguments (VkDrawIndirectCommand), then the counters.
struct GrassHeader {
    uint vertex_count;
    uint instance_count;  // tufts drawn
    uint first_vertex;
    uint first_instance;
    uint in_range;        // cells within the radius
    uint placed;          // tufts standing on terrain (before culling)
    uint culled_frustum;
    uint culled_hiz;
    uint skipped_occurrence;  // cells in range whose occurrence bit is off
};

// Two 32-bit random words of a cell: its jitter, and its keep, rotation
// and lean.
uvec2 grass_cell_hash(ivec2 cell, uint seed) {
    uvec2 c = uvec2(cell);
    return uvec2(pcg3d_x(uvec3(c, seed)), pcg3d_x(uvec3(c, seed ^ 0x5BD1E995u)));
}

// Where in the cell the tuft stands (0..1 each way): exact in f32, so the
// CPU twin makes the same bits.
vec2 grass_jitter(uint h) {
    return vec2(float(h & 0xFFFFu), float(h >> 16u)) * (1.0 / 65536.0);
}

// The uniform 0..1 number a cell keeps its tuft by (24 bits).
float grass_keep(uint h) {
    return float(h >> 8u) * (1.0 / 16777216.0);
}

#endif

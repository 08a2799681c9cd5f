// The finest surface's heights (Catmull-Rom of a node's samples below
// LOD 0), shared by the patches' vertex (terrain_vertex.glsl) and the
// per-triangle rule's (terrain_triangles.vert) so both place a refined
// vertex with the same arithmetic. The includer declares `height_atlas`
// (the node's R16 heights, samples -2..129) and the `nearest` sampler
// first.
#ifndef VISTA_REFINED_SURFACE_GLSL
#define VISTA_REFINED_SURFACE_GLSL

#include "atlas_texels.glsl"

// R16 height (0..1) of node sample `i` of layer `slot` (-2..129).
float height_texel(uint slot, ivec2 i) {
    return texelFetch(sampler2DArray(height_atlas, nearest), ivec3(atlas_texel(i), int(slot)), 0).r;
}

// Catmull-Rom weights at t in [0, 1]; exactly (0, 1, 0, 0) at 0 and
// (0, 0, 1, 0) at 1, so a vertex on a sample takes its height bit for bit.
vec4 catmull_rom(float t) {
    precise float t2 = t * t;
    precise float t3 = t2 * t;
    precise vec4 w = 0.5 * vec4(-t3 + 2.0 * t2 - t, 3.0 * t3 - 5.0 * t2 + 2.0, -3.0 * t3 + 4.0 * t2 + t, t3 - t2);
    return w;
}

// The 4 x 4 samples around cell `cell` of layer `slot` (row by row from
// the cell's sample (-1, -1)): the Catmull-Rom taps of every point of it.
void cell_taps(uint slot, ivec2 cell, out float taps[16]) {
    for (int k = 0; k < 16; ++k) {
        taps[k] = height_texel(slot, cell + ivec2(k % 4 - 1, k / 4 - 1));
    }
}

// Height (R16 units) of the Catmull-Rom surface over a cell's taps at
// weights wx, wy: along x over the 4 rows, then along y
// (src/world/error_tile.rs evaluates it the same way).
float weigh_taps(float taps[16], vec4 wx, vec4 wy) {
    precise float h = 0.0;
    for (int j = 0; j < 4; ++j) {
        precise float x = wx.x * taps[4 * j] + wx.y * taps[4 * j + 1] + wx.z * taps[4 * j + 2] + wx.w * taps[4 * j + 3];
        h = h + wy[j] * x;
    }
    return h;
}

// Height (R16 units) of the Catmull-Rom surface of a node's samples at
// `fine`, node-local in units of 2^-r samples. The node's far edge is
// cell 127 at t = 1, so the taps stay within samples -1..129.
float refined_height(uint slot, ivec2 fine, uint r) {
    ivec2 cell = min(fine >> int(r), ivec2(127));
    vec2 t = vec2(fine - (cell << int(r))) / float(1u << r);
    float taps[16];
    cell_taps(slot, cell, taps);
    return weigh_taps(taps, catmull_rom(t.x), catmull_rom(t.y));
}

#endif

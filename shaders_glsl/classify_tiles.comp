#version 460
#extension GL_GOOGLE_include_directive : require
// One invocation per 8x8 screen tile: OR the classification bits of its
// pixels (2x2 gathers), skip tiles with no terrain, and append the tile to
// the list of its combined variant (the flavour bits), whose indirect
// instance count is the append counter; a control-map tile also counts how
// many tri-planar planes its pixels sample at most (the plane bits). The classification target is cleared to 0 by the
// geometry pass's load op and every terrain pixel has at least one bit, so
// a zero OR is exactly "no terrain in the tile" without reading the depth
// in a second view.
//
// Why not an invocation per pixel ORing through shared memory: that needs
// two workgroup barriers per tile, and on a CPU driver (lavapipe) a barrier
// switches every SIMD slice of the workgroup, which made classification
// cost over a tenth of the shading it saves. A tile is 16 gathers, which
// GPUs run at the same cost either way. Gathers past the target's edge
// clamp to its last row or column, which belong to the same partial tile.
#include "tile_lists.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform utexture2D classification;
layout(set = 0, binding = 2) uniform sampler nearest;
layout(set = 0, binding = 1, std430) buffer TileLists { TILE_LISTS_MEMBERS } lists;

layout(push_constant, std430) uniform ClassifyPush { TilePush p; } pc;

void main() {
    uvec2 tile = gl_GlobalInvocationID.xy;
    if (tile.x >= pc.p.tiles_x || tile.y >= pc.p.tiles_y) {
        return;
    }
    vec2 texel = 1.0 / vec2(pc.p.width, pc.p.height);
    uint bits = 0u;
    for (uint j = 0u; j < TILE_SIZE; j += 2u) {
        for (uint i = 0u; i < TILE_SIZE; i += 2u) {
            // The shared corner of the 2x2 block at (i, j).
            vec2 corner = vec2(tile * TILE_SIZE + uvec2(i + 1u, j + 1u)) * texel;
            uvec4 q = textureGather(usampler2D(classification, nearest), corner, 0);
            bits |= q.x | q.y | q.z | q.w;
        }
    }
    if (bits != 0u) {
        uint variant = pc.p.force_variant != 0u ? pc.p.force_variant : bits & FLAVOUR_MASK;
        uint i = atomicAdd(lists.args[variant].instance_count, 1u);
        lists.tiles[variant * pc.p.capacity + i] = tile.x | (tile.y << 16u);
        if ((bits & FLAVOUR_CONTROL_MAP) != 0u) {
            uint planes = (bits & CLASS_PLANES_3) != 0u ? 3u : ((bits & CLASS_PLANES_2) != 0u ? 2u : 1u);
            atomicAdd(lists.plane_tiles[planes - 1u], 1u);
        }
    }
}

#version 460
#extension GL_GOOGLE_include_directive : require
// One workgroup per 8x8 screen tile: OR the classification bits of its
// pixels (shared-memory atomics), skip tiles with no terrain, and append the
// tile to the list of its combined variant, whose indirect instance count
// is the append counter. The classification target is cleared to 0 by the
// geometry pass's load op and every terrain pixel has at least one bit, so
// a zero OR is exactly "no terrain stencil in the tile" without reading the
// stencil aspect in a second view.
#include "tile_lists.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform utexture2D classification;
layout(set = 0, binding = 2) uniform sampler nearest;
layout(set = 0, binding = 1, std430) buffer TileLists {
    TileDrawArgs args[FLAVOUR_VARIANTS];
    uint tiles[];
} lists;

layout(push_constant, std430) uniform ClassifyPush { TilePush p; } pc;

shared uint tile_bits;

void main() {
    if (gl_LocalInvocationIndex == 0u) {
        tile_bits = 0u;
    }
    barrier();
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = textureSize(usampler2D(classification, nearest), 0);
    uint bits = all(lessThan(px, size)) ? texelFetch(usampler2D(classification, nearest), px, 0).r : 0u;
    if (bits != 0u) {
        atomicOr(tile_bits, bits);
    }
    barrier();
    if (gl_LocalInvocationIndex == 0u && tile_bits != 0u) {
        uint variant = pc.p.force_variant != 0u ? pc.p.force_variant : tile_bits;
        uint i = atomicAdd(lists.args[variant].instance_count, 1u);
        lists.tiles[variant * pc.p.capacity + i] = gl_WorkGroupID.x | (gl_WorkGroupID.y << 16u);
    }
}

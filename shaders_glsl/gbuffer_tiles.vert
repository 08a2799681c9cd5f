#version 460
#extension GL_GOOGLE_include_directive : require
// One 8x8-pixel quad per listed tile of this pipeline's variant (instance =
// tile), clipped to the target.
#include "tile_lists.glsl"

// The variant: flavour bits (constants.glsl), a specialization constant.
layout(constant_id = 0) const uint VARIANT_BITS = 0u;

layout(set = 0, binding = 1, std430) readonly buffer TileLists { TILE_LISTS_MEMBERS } lists;

#define VISTA_TERRAIN_DECLARE_ONLY
#include "terrain_sample.glsl"
// The fragment shader's block (one push range for both stages).
layout(push_constant, std430) uniform TileDrawPush { TilePush p; VistaTerrain terrain; } pc;

void main() {
    uint variant = VARIANT_BITS;
    uint entry = lists.tiles[variant * pc.p.capacity + uint(gl_InstanceIndex)];
    uvec2 tile = uvec2(entry & 0xFFFFu, entry >> 16u);
    // Two triangles: corners (0,0) (1,0) (0,1) / (1,0) (1,1) (0,1).
    uint v = uint(gl_VertexIndex);
    uvec2 corner = uvec2((v == 1u || v == 3u || v == 4u) ? 1u : 0u, (v == 2u || v == 4u || v == 5u) ? 1u : 0u);
    // Past the target's edge the quad is clipped.
    vec2 pixel = vec2((tile + corner) * TILE_SIZE);
    vec2 ndc = pixel / vec2(pc.p.width, pc.p.height) * 2.0 - 1.0;
    gl_Position = vec4(ndc, 0.0, 1.0);
}

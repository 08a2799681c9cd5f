#version 460
// Sector data: for every sector, SLOT_BITS per LOD = the atlas slot of the
// resident node covering it at that LOD (0 = none), every LOD a world can
// have: LOD k in word k / SECTOR_LODS_PER_WORD of the sector's
// SECTOR_DATA_WORDS. Any shader can then sample the terrain at the finest
// resident detail through terrain_sample.glsl. Rebuilt from the node texture.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 8, local_size_y = 8) in;
#include "constants.glsl"

layout(set = 0, binding = 0) uniform utexture2D node_texture;
layout(set = 0, binding = 1) uniform sampler node_sampler;
layout(set = 0, binding = 2, std430) buffer SectorData { uint words[]; } sector_data;
layout(push_constant, std430) uniform SectorDataPush { uint sectors_x; uint sectors_y; uint lod_count; uint pad; } pc;

void main() {
    uvec2 s = gl_GlobalInvocationID.xy;
    if (s.x >= pc.sectors_x || s.y >= pc.sectors_y) {
        return;
    }
    uint packed[SECTOR_DATA_WORDS];
    for (uint w = 0u; w < SECTOR_DATA_WORDS; ++w) {
        packed[w] = 0u;
    }
    for (uint k = 0u; k < min(pc.lod_count, MAX_NODE_LODS); ++k) {
        uint v = texelFetch(usampler2D(node_texture, node_sampler), ivec2(s >> k), int(k)).r;
        uint slot = v < NODE_INVALID ? v : 0u;
        packed[k / SECTOR_LODS_PER_WORD] |= slot << (SLOT_BITS * (k % SECTOR_LODS_PER_WORD));
    }
    uint base = (s.y * pc.sectors_x + s.x) * SECTOR_DATA_WORDS;
    for (uint w = 0u; w < SECTOR_DATA_WORDS; ++w) {
        sector_data.words[base + w] = packed[w];
    }
}

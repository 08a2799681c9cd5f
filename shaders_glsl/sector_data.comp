#version 460
// Sector data: for every sector, 10 bits per LOD = the atlas slot of the
// resident node covering it at that LOD (0 = none), LODs 0-2 in .x and 3-5
// in .y. Any shader can then sample the terrain at the finest resident
// detail through terrain_sample.glsl. Rebuilt from the node texture.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 8, local_size_y = 8) in;
#include "constants.glsl"

layout(set = 0, binding = 0) uniform utexture2D node_texture;
layout(set = 0, binding = 1) uniform sampler node_sampler;
layout(set = 0, binding = 2, std430) buffer SectorData { uvec2 sectors[]; } sector_data;
layout(push_constant, std430) uniform SectorDataPush { uint sectors_x; uint sectors_y; uint lod_count; uint pad; } pc;

void main() {
    uvec2 s = gl_GlobalInvocationID.xy;
    if (s.x >= pc.sectors_x || s.y >= pc.sectors_y) {
        return;
    }
    uvec2 packed = uvec2(0u);
    for (uint k = 0u; k < min(pc.lod_count, SECTOR_DATA_LODS); ++k) {
        uint v = texelFetch(usampler2D(node_texture, node_sampler), ivec2(s >> k), int(k)).r;
        uint slot = v < NODE_INVALID ? v : 0u;
        uint shift = SLOT_BITS * (k % SECTOR_LODS_PER_WORD);
        if (k < SECTOR_LODS_PER_WORD) {
            packed.x |= slot << shift;
        } else {
            packed.y |= slot << shift;
        }
    }
    sector_data.sectors[s.y * pc.sectors_x + s.x] = packed;
}

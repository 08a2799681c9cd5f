#version 460
#extension GL_GOOGLE_include_directive : require
// Fills the R8 LOD map (one texel per sector) from the final node list: one
// workgroup per listed node (indirect: traverse's dispatch args), its
// threads writing the node's LOD into every sector it covers. The list tiles
// the world exactly once, so no two threads write the same texel.
layout(local_size_x = 64) in;

#include "node_list.glsl"

layout(set = 0, binding = 0, std430) readonly buffer TraverseOutput {
    TraverseHeader header;
    uvec2 nodes[];
} traverse_out;
layout(set = 0, binding = 1, r8ui) uniform writeonly uimage2D lod_map;

void main() {
    uint n = traverse_out.nodes[gl_WorkGroupID.x].x;
    uint lod = node_lod(n), x = node_x(n), y = node_y(n);
    uint k = 1u << lod;
    ivec2 size = imageSize(lod_map);
    for (uint i = gl_LocalInvocationID.x; i < k * k; i += gl_WorkGroupSize.x) {
        ivec2 s = ivec2(x * k + i % k, y * k + i / k);
        if (all(lessThan(s, size))) {
            imageStore(lod_map, s, uvec4(lod));
        }
    }
}

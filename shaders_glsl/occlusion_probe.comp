#version 460
#extension GL_GOOGLE_include_directive : require
// Tests only: runs the occlusion test of cull_occluded (common/hiz_test.glsl)
// on given boxes, so its choices can be compared with the CPU twin.
layout(local_size_x = 64) in;

layout(set = 0, binding = 0, std430) readonly buffer Probes {
    mat4 view_proj;
    uvec4 depth_size;  // xy: the pyramid's source size; z: box count
    vec4 boxes[];      // lo, hi pairs (camera-relative metres)
} probes;
layout(set = 0, binding = 1, std430) buffer Results { uvec2 results[]; } out_;
layout(set = 0, binding = 6) uniform sampler nearest;
layout(set = 0, binding = 10) uniform texture2D hiz;
#include "hiz_test.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= probes.depth_size.z) {
        return;
    }
    uint level;
    bool visible =
        hiz_box_visible(probes.boxes[2u * i].xyz, probes.boxes[2u * i + 1u].xyz, probes.view_proj, probes.depth_size.xy, level);
    out_.results[i] = uvec2(visible ? 1u : 0u, level);
}

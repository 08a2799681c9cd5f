#version 460
#extension GL_GOOGLE_include_directive : require
// One level of the depth pyramid per dispatch, each texel the farthest
// depth (reversed-Z: the minimum) of what it covers. Level 0 reduces the depth target to the next power of two below it: texel i
// covers pixels [i*W/w0, ceil((i+1)*W/w0)), up to 3 a side, none dropped.
// Every later level is an exact 2x2 reduction (clamped where a side is
// already 1). Per-level dispatches rather than one single-pass reduction:
// exact by construction, no cross-workgroup atomics, ~11 tiny dispatches.
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform texture2D depth;
layout(set = 0, binding = 1) uniform sampler nearest;
// The pyramid itself (all mips, GENERAL): level L reads mip L - 1.
layout(set = 0, binding = 2) uniform texture2D pyramid;
layout(set = 0, binding = 3, r32f) uniform writeonly image2D dst;

layout(push_constant, std430) uniform HizPush {
    uvec2 src_size;
    uvec2 dst_size;
    uint level;
    uint pad0;
    uint pad1;
    uint pad2;
} pc;

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(p, pc.dst_size))) {
        return;
    }
    float farthest = 1.0;
    if (pc.level == 0u) {
        uvec2 first = (p * pc.src_size) / pc.dst_size;
        uvec2 end = ((p + 1u) * pc.src_size + pc.dst_size - 1u) / pc.dst_size;
        for (uint y = first.y; y < end.y; ++y) {
            for (uint x = first.x; x < end.x; ++x) {
                farthest = min(farthest, texelFetch(sampler2D(depth, nearest), ivec2(x, y), 0).r);
            }
        }
    } else {
        uvec2 last = pc.src_size - 1u;
        for (uint dy = 0u; dy < 2u; ++dy) {
            for (uint dx = 0u; dx < 2u; ++dx) {
                ivec2 q = ivec2(min(2u * p + uvec2(dx, dy), last));
                farthest = min(farthest, texelFetch(sampler2D(pyramid, nearest), q, int(pc.level) - 1).r);
            }
        }
    }
    imageStore(dst, ivec2(p), vec4(farthest));
}

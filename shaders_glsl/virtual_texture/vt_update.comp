#version 460
// Applies the virtual texture's state writes of one frame (sub-texture
// words, indirection texels; effects/virtual_texture/state.rs), in order:
// a square cleared for a sub-texture and the pages then mapped into it
// touch the same words, so the writes run one after another in a single
// workgroup whose invocations share each write's range.
#extension GL_GOOGLE_include_directive : require
#include "constants.glsl"

layout(local_size_x = 64) in;

struct StateWrite {
    uint start;
    uint count;
    uint value;
    uint pad;
};

layout(set = 0, binding = 0, std430) buffer State { uint words[]; } state;
layout(set = 0, binding = 1, std430) readonly buffer Writes { StateWrite w[]; } writes;

layout(push_constant, std430) uniform VtUpdatePush { uint count; uint pad0; uint pad1; uint pad2; } pc;

void main() {
    for (uint i = 0u; i < pc.count; ++i) {
        // Field by field: a by-value copy out of a block is OpCopyLogical,
        // which naga cannot parse.
        uint start = writes.w[i].start;
        uint count = writes.w[i].count;
        uint value = writes.w[i].value;
        for (uint j = gl_LocalInvocationID.x; j < count; j += gl_WorkGroupSize.x) {
            state.words[start + j] = value;
        }
        memoryBarrierBuffer();
        barrier();
    }
}

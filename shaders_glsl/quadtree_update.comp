#version 460
// Applies one frame's quadtree changes: node-texture texels (value = slot,
// 0xFFFF empty) and node descriptions. The host coalesces the list so no two
// threads write the same texel or slot: the order of threads does not matter.
#extension GL_GOOGLE_include_directive : require
// variants: OCCLUSION
// With OCCLUSION, a slot whose description changes (a node arrived or
// left) also has its patches' visibility bits cleared: a reused slot must
// not inherit the last node's (phase 2 of occlusion culling re-tests them).
layout(local_size_x = 64) in;
#include "constants.glsl"

struct QuadtreeUpdate {
    uint target;  // mip (= LOD) of a texel write, or UPDATE_TARGET_*
    uint coords;  // x | y << 16 for a texel; the slot for a description
    uint word0;
    uint word1;
};

layout(set = 0, binding = 0, std430) readonly buffer Updates { QuadtreeUpdate items[]; } updates;
layout(set = 0, binding = 1, std430) buffer NodeDescs { uvec2 descs[]; } node_descs;
layout(set = 0, binding = 12, std430) buffer NodeErrors { float errors[]; } node_errors;
#ifdef OCCLUSION
layout(set = 0, binding = 13, std430) buffer Visibility { uint words[]; } visibility;
#endif
// One binding per LOD (a storage image view addresses a single mip); the
// host binds mip 0 again for LODs past the world's count.
layout(set = 0, binding = 2, r16ui) uniform writeonly uimage2D node_lod0;
layout(set = 0, binding = 3, r16ui) uniform writeonly uimage2D node_lod1;
layout(set = 0, binding = 4, r16ui) uniform writeonly uimage2D node_lod2;
layout(set = 0, binding = 5, r16ui) uniform writeonly uimage2D node_lod3;
layout(set = 0, binding = 6, r16ui) uniform writeonly uimage2D node_lod4;
layout(set = 0, binding = 7, r16ui) uniform writeonly uimage2D node_lod5;
layout(set = 0, binding = 8, r16ui) uniform writeonly uimage2D node_lod6;
layout(set = 0, binding = 9, r16ui) uniform writeonly uimage2D node_lod7;
layout(set = 0, binding = 10, r16ui) uniform writeonly uimage2D node_lod8;
layout(set = 0, binding = 11, r16ui) uniform writeonly uimage2D node_lod9;

layout(push_constant, std430) uniform QuadtreeUpdatePush { uint count; } pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) {
        return;
    }
    // Field by field: a whole-struct copy becomes OpCopyLogical, which naga
    // does not parse.
    uint target = updates.items[i].target;
    uint coords = updates.items[i].coords;
    uint word0 = updates.items[i].word0;
    if (target == UPDATE_TARGET_DESC) {
        node_descs.descs[coords] = uvec2(word0, updates.items[i].word1);
#ifdef OCCLUSION
        for (uint w = 0u; w < VISIBILITY_WORDS_PER_SLOT; ++w) {
            visibility.words[coords * VISIBILITY_WORDS_PER_SLOT + w] = 0u;
        }
#endif
        return;
    }
    if (target == UPDATE_TARGET_ERROR) {
        node_errors.errors[coords] = uintBitsToFloat(word0);
        return;
    }
    ivec2 p = ivec2(bitfieldExtract(coords, 0, int(HALF_BITS)), coords >> HALF_BITS);
    uvec4 v = uvec4(word0);
    switch (target) {
        case 0u: imageStore(node_lod0, p, v); break;
        case 1u: imageStore(node_lod1, p, v); break;
        case 2u: imageStore(node_lod2, p, v); break;
        case 3u: imageStore(node_lod3, p, v); break;
        case 4u: imageStore(node_lod4, p, v); break;
        case 5u: imageStore(node_lod5, p, v); break;
        case 6u: imageStore(node_lod6, p, v); break;
        case 7u: imageStore(node_lod7, p, v); break;
        case 8u: imageStore(node_lod8, p, v); break;
        case 9u: imageStore(node_lod9, p, v); break;
        default: break;
    }
}

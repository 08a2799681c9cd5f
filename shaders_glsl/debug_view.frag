#version 460
#extension GL_GOOGLE_include_directive : require
// The debug views of `vista view` (passes/debug_view.rs, which holds the
// CPU twin of this shader): over the display image, at terrain pixels, the
// LOD each patch was drawn from (lightened per level refined below LOD 0),
// the shading classification (the mean of its flavours' colours), the
// patch grid's edges (over the lit image), or the occlusion phase that drew
// the pixel. Every colour comes from the host.
#include "constants.glsl"

layout(set = 0, binding = 0) uniform utexture2D patch_info;
layout(set = 0, binding = 1) uniform utexture2D classification;
layout(set = 0, binding = 2) uniform sampler nearest;

layout(push_constant, std430) uniform DebugViewPush {
    // Mode LOD: per LOD modulo 6; CLASSIFICATION: per flavour bit; EDGES:
    // [0] the outline; PHASE: [0] phase 1, [1] phase 2.
    vec4 colours[6];
    uint mode;
    uint pad0;
    uint pad1;
    uint pad2;
} pc;

layout(location = 0) out vec4 colour;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    uint cls = texelFetch(usampler2D(classification, nearest), p, 0).r;
    uint info = texelFetch(usampler2D(patch_info, nearest), p, 0).r;
    // Alpha 0 keeps the picture (the pipeline blends): no terrain, or
    // inside a patch in the edges view. (No `discard`: naga cannot parse
    // the SPIR-V it becomes.)
    colour = vec4(0.0);
    if (cls == 0u) {
        return;
    }
    vec3 c;
    if (pc.mode == DEBUG_VIEW_LOD) {
        uint refine = (info >> PATCH_INFO_REFINE_SHIFT) & 3u;
        c = mix(pc.colours[(info & PATCH_INFO_LOD_MASK) % 6u].rgb, vec3(1.0), 0.25 * float(refine));
    } else if (pc.mode == DEBUG_VIEW_CLASSIFICATION) {
        vec3 sum = vec3(0.0);
        float n = 0.0;
        for (uint b = 0u; b < FLAVOUR_BITS; ++b) {
            if ((cls & (1u << b)) != 0u) {
                sum += pc.colours[b].rgb;
                n += 1.0;
            }
        }
        c = sum / max(n, 1.0);
    } else if (pc.mode == DEBUG_VIEW_EDGES) {
        if ((info >> PATCH_INFO_EDGE_SHIFT) == 0u) {
            return;
        }
        c = pc.colours[0].rgb;
    } else {
        c = pc.colours[(info >> PATCH_INFO_PHASE_SHIFT) & 1u].rgb;
    }
    colour = vec4(c, 1.0);
}

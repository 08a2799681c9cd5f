#version 460
// Page requests of the virtual texture (seed 001, at seed 000's 1/8 size):
// one sample per VT_FEEDBACK_STRIDE^2 block of pixels, its place in the
// block jittered over frames (or, while an offline render settles, every
// pixel: stride 1, so one frame checks what the cycle checks), at terrain pixels classified for the
// virtual-texture flavour. A sample asks for the two levels its footprint
// falls between (what gbuffer_tiles samples) and its region's level 0 (the
// fallback every coarser lookup ends at). Deduplicated without a clear
// pass: each page's status word takes the frame's stamp by atomicExchange
// and only the sample that changed it appends the page, so every page the
// frame sampled is listed once, resident or not (the CPU's LRU needs
// both). The list goes back to the CPU frames late (effects/virtual_texture).
#extension GL_GOOGLE_include_directive : require
#include "terrain_view.glsl"
#include "octahedral.glsl"
#include "reconstruct.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0, std430) readonly buffer View { TerrainView v; } view;
layout(set = 0, binding = 1) uniform texture2D depth_target;
layout(set = 0, binding = 2) uniform utexture2D normals;
layout(set = 0, binding = 3) uniform utexture2D classification;
layout(set = 0, binding = 4) uniform sampler nearest;
layout(set = 0, binding = 5, std430) readonly buffer VtState { uint words[]; } vt_state;
layout(set = 0, binding = 6, std430) buffer Status { uint s[]; } status;
layout(set = 0, binding = 7, std430) buffer Requests {
    uint count;     // pages listed (may exceed the capacity)
    uint pad0;
    uint pad1;
    uint pad2;
    uvec2 e[];      // region, level | x << 4 | y << 12
} requests;

#define VISTA_VT_WORD(i) vt_state.words[i]
#include "virtual_texture.glsl"

layout(push_constant, std430) uniform VtFeedbackPush {
    uvec2 jitter;   // sample's place in its block (pixels)
    uvec2 size;     // target size (pixels)
    uint stamp;     // this frame's status value (never 0)
    uint stride;    // one sample per stride^2 pixels (VT_FEEDBACK_STRIDE or 1)
    uint pad0;
    uint pad1;
} pc;

void request(VtSub s, uint level, uvec2 p) {
    uint window = VISTA_VT_WORD(7u);
    uint texel = vt_indirection_word(s, level, p) - VT_STATE_HEADER - 2u * window * window;
    if (atomicExchange(status.s[texel], pc.stamp) != pc.stamp) {
        uint i = atomicAdd(requests.count, 1u);
        if (i < VT_REQUEST_CAPACITY) {
            requests.e[i] = uvec2(s.region, vt_request_word(level, p));
        }
    }
}

void main() {
    uvec2 px = gl_GlobalInvocationID.xy * pc.stride + pc.jitter;
    if (any(greaterThanEqual(px, pc.size))) {
        return;
    }
    ivec2 q = ivec2(px);
    uint bits = texelFetch(usampler2D(classification, nearest), q, 0).r;
    float depth = texelFetch(sampler2D(depth_target, nearest), q, 0).r;
    if ((bits & FLAVOUR_VIRTUAL_TEXTURE) == 0u || depth <= 0.0) {
        return;
    }
    vec3 nt = oct_decode8(texelFetch(usampler2D(normals, nearest), q, 0).zw);
    vec2 pixel = vec2(px) + 0.5;
    vec3 p = reconstruct_position(view.v.inv_view_proj, pixel, view.v.viewport, depth);
    vec3 ddx, ddy;
    position_derivatives(view.v.inv_view_proj, pixel, view.v.viewport, p, nt, ddx, ddy);
    vec3 world = view.v.camera_world.xyz + p;
    VtSub s = vt_sub_texture(world.xy);
    if (!s.valid) {
        return;
    }
    float level = clamp(vt_level(max(length(ddx.xy), length(ddy.xy)), s.region_m), 0.0, float(s.k));
    uint fine = uint(ceil(level));
    uint coarse = uint(floor(level));
    vec2 within;
    request(s, fine, vt_page(s, world.xy, fine, within));
    if (coarse != fine) {
        request(s, coarse, vt_page(s, world.xy, coarse, within));
    }
    if (coarse != 0u) {
        request(s, 0u, uvec2(0u));
    }
}

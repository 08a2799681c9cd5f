#version 460
// Test probe of the virtual texture (tests/virtual_texture.rs): per world
// point and level, the page gbuffer_tiles would sample (vt_find) and the
// cache texels under it, unfiltered.
#extension GL_GOOGLE_include_directive : require
#include "constants.glsl"

layout(local_size_x = 64) in;

layout(set = 0, binding = 0, std430) readonly buffer VtState { uint words[]; } vt_state;
layout(set = 0, binding = 1, std430) readonly buffer ProbePoints { vec4 p[]; } points;  // x, y, level, unused
layout(set = 0, binding = 2, std430) buffer ProbeResults { uvec4 r[]; } results;
layout(set = 0, binding = 3) uniform texture2D cache_albedo;
layout(set = 0, binding = 4) uniform texture2D cache_detail;
layout(set = 0, binding = 5) uniform sampler nearest;

#define VISTA_VT_WORD(i) vt_state.words[i]
#include "virtual_texture.glsl"

layout(push_constant, std430) uniform VtProbePush { uint count; uint pad0; uint pad1; uint pad2; } pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) {
        return;
    }
    vec2 xy = points.p[i].xy;
    VtSub s = vt_sub_texture(xy);
    if (!s.valid) {
        results.r[i] = uvec4(0u);
        return;
    }
    uint level = min(uint(points.p[i].z), s.k);
    vec2 texel;
    uint found;
    if (!vt_find(s, xy, level, texel, found)) {
        results.r[i] = uvec4(1u, 0u, 0u, s.k);
        return;
    }
    ivec2 t = ivec2(floor(texel));
    vec4 a = texelFetch(sampler2D(cache_albedo, nearest), t, 0);
    vec4 d = texelFetch(sampler2D(cache_detail, nearest), t, 0);
    results.r[i] = uvec4(3u | (found << 8u), packUnorm4x8(a), packUnorm4x8(d), s.k);
}

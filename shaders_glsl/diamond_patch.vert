#version 460
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
// A (n+1)x(n+1)-vertex grid spanning clip space, drawn with the diamond index
// pattern; the vertex `hole_vertex` becomes NaN, which must remove every
// triangle touching it (how terrain holes are cut).
layout(push_constant, std430) uniform DiamondPatchPush {
    uint quads_per_side;
    uint hole_vertex;   // 0xFFFFFFFF = no hole
    uint nan_bits;      // 0x7FC00000: a quiet NaN, passed in so it is made at run time
    uint pad;
} pc;

void main() {
    uint n = pc.quads_per_side;
    uint x = uint(gl_VertexIndex) % (n + 1);
    uint y = uint(gl_VertexIndex) / (n + 1);
    vec2 p = vec2(x, y) / float(n) * 2.0 - 1.0;
    gl_Position = vec4(p, 0.5, 1.0);
    if (uint(gl_VertexIndex) == pc.hole_vertex) {
        gl_Position = vec4(runtime_nan(pc.nan_bits));
    }
}

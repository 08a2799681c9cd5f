#version 460
#extension GL_GOOGLE_include_directive : require
// Tests only: runs gbuffer_tiles' position and derivative reconstruction
// (common/reconstruct.glsl) on given pixels, depths and normal codes, and
// samples a texture whose mip k holds k with the resulting gradients, so the
// mip level the sampler chooses comes back with the derivatives.
layout(local_size_x = 64) in;

layout(set = 0, binding = 0, std430) readonly buffer DerivativeProbes {
    mat4 inv_view_proj;
    vec4 viewport;  // width, height, 1 / width, 1 / height
    vec4 uv_scale;  // x: texture repeats per metre of world x and y
    uvec4 count;    // x: probes
    vec4 probes[];  // xy pixel, z depth, w normal code (x | y << 8) as bits
} in_;
layout(set = 0, binding = 1, std430) buffer DerivativeResults { vec4 results[]; } out_;  // 2 per probe
layout(set = 0, binding = 2) uniform sampler mip_sampler;
layout(set = 0, binding = 3) uniform texture2D mip_levels;
#include "octahedral.glsl"
#include "reconstruct.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= in_.count.x) {
        return;
    }
    vec4 probe = in_.probes[i];
    uint code = floatBitsToUint(probe.w);
    vec3 n = oct_decode_packed(code);
    vec3 p = reconstruct_position(in_.inv_view_proj, probe.xy, in_.viewport, probe.z);
    vec3 ddx, ddy;
    position_derivatives(in_.inv_view_proj, probe.xy, in_.viewport, p, n, ddx, ddy);
    // As sample_material: ground-plane coordinates and their derivatives.
    float k = in_.uv_scale.x;
    float lod = textureGrad(sampler2D(mip_levels, mip_sampler), p.xy * k, ddx.xy * k, ddy.xy * k).r;
    out_.results[2u * i] = vec4(ddx, lod);
    out_.results[2u * i + 1u] = vec4(ddy, 0.0);
}

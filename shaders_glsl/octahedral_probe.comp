#version 460
#extension GL_GOOGLE_include_directive : require
// Tests only: encodes unit vectors with octahedral.glsl's oct_encode8 (the
// code terrain_geometry writes the normal target with) and decodes the codes
// back, so the CPU twin can be compared code for code.
layout(local_size_x = 64) in;

layout(set = 0, binding = 0, std430) readonly buffer OctahedralProbes {
    uvec4 count;     // x: vectors
    vec4 vectors[];  // xyz: the vector
} in_;
// Per vector: x the code (x | y << 8), yzw the decoded vector's bits.
layout(set = 0, binding = 1, std430) buffer OctahedralResults { uvec4 results[]; } out_;
#include "octahedral.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= in_.count.x) {
        return;
    }
    uvec2 code = oct_encode8(in_.vectors[i].xyz);
    vec3 decoded = oct_decode8(code);
    out_.results[i] = uvec4(code.x | (code.y << 8u), floatBitsToUint(decoded));
}

#version 460
// One triangle whose clip-space corners come from push constants.
layout(push_constant, std430) uniform SmokeTrianglePush { vec4 corners[3]; } pc;

void main() {
    gl_Position = pc.corners[gl_VertexIndex];
}

#version 460
// Plane 0 red, plane 1 green: the read-back colour says which plane won.
layout(location = 0) flat in uint plane;
layout(location = 0) out vec4 color;

void main() {
    color = plane == 0u ? vec4(1.0, 0.0, 0.0, 1.0) : vec4(0.0, 1.0, 0.0, 1.0);
}

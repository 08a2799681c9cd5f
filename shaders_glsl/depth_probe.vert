#version 460
// Stability case 2 (stability/depth.rs): two horizontal planes below the
// camera, instance 0 at z = z0, instance 1 at z = z1, each a square of
// half-size `half_m` around the camera, transformed exactly as terrain
// vertices are: camera-relative metres through view_proj (reversed-Z,
// infinite far plane).
layout(push_constant, std430) uniform DepthProbePush {
    mat4 view_proj;
    vec4 planes;  // x: z0, y: z1 (camera-relative m), z: half size (m), w: unused
} pc;

layout(location = 0) flat out uint plane;

void main() {
    // Two triangles: corners (0,0) (1,0) (0,1) (1,0) (1,1) (0,1).
    const uvec2 corner[6] = uvec2[6](uvec2(0, 0), uvec2(1, 0), uvec2(0, 1), uvec2(1, 0), uvec2(1, 1), uvec2(0, 1));
    vec2 c = vec2(corner[gl_VertexIndex]) * 2.0 - 1.0;
    float z = gl_InstanceIndex == 0 ? pc.planes.x : pc.planes.y;
    gl_Position = pc.view_proj * vec4(c * pc.planes.z, z, 1.0);
    plane = uint(gl_InstanceIndex);
}

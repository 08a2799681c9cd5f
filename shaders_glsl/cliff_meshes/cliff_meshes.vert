#version 460
#extension GL_GOOGLE_include_directive : require
// Procedural cliff meshes (effect cliff_meshes): every cell cliff_mesh_build
// listed, ONE indexed indirect draw (instance = cell, its vertices by
// index), into the geometry pass.
#include "constants.glsl"
#include "terrain_view.glsl"
#include "octahedral.glsl"
#include "cliff_mesh.glsl"

layout(set = 0, binding = 0, std430) readonly buffer View { TerrainView v; } view;
layout(set = 0, binding = 1, std430) readonly buffer CliffVertices { CliffVertex v[]; } vertices;

layout(location = 0) out vec3 rel_pos;
layout(location = 1) out vec3 normal;

void main() {
    const uint SIDE = CLIFF_CELL_QUADS + 1u;
    vec4 p = vertices.v[uint(gl_InstanceIndex) * SIDE * SIDE + uint(gl_VertexIndex)].p;
    uint code = floatBitsToUint(p.w);
    normal = oct_decode_packed(code);
    rel_pos = p.xyz - view.v.camera_world.xyz;
    gl_Position = view.v.view_proj * vec4(rel_pos, 1.0);
}

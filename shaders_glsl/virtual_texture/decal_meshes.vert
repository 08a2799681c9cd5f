#version 460
#extension GL_GOOGLE_include_directive : require
// Displacement decals (effect decals, effects/virtual_texture/decal_mesh.rs):
// every displacement decal's grid mesh in one indexed draw, in the
// geometry pass. A vertex stands on the terrain's height at its xy
// (terrain_sample.glsl, so the mesh follows the resident LOD) raised by its
// own height; its normal is the terrain's tilted by that height's
// gradient. The tile passes shade it like terrain, from the same virtual
// texture pages as the ground around it.
#include "terrain_view.glsl"

struct DecalMeshVertex {
    vec4 position;  // x, y (world m); z: height above the terrain (m)
    vec4 gradient;  // xy: that height's gradient
};

layout(set = 0, binding = 0, std430) readonly buffer View { TerrainView v; } view;
layout(set = 0, binding = 1, std430) readonly buffer DecalMeshVertices { DecalMeshVertex v[]; } vertices;
layout(set = 0, binding = 2, std430) readonly buffer SectorData { uint words[]; } sector_data;
layout(set = 0, binding = 3) uniform texture2DArray height_atlas;
layout(set = 0, binding = 4) uniform texture2DArray normal_atlas;
layout(set = 0, binding = 5) uniform sampler nearest;

#define VISTA_SECTOR_WORD(i) sector_data.words[i]
#define VISTA_HEIGHT_ATLAS height_atlas
#define VISTA_NORMAL_ATLAS normal_atlas
#define VISTA_ATLAS_SAMPLER nearest
#define VISTA_NO_MATERIAL_QUERY
#define VISTA_TERRAIN pc.terrain
#define VISTA_TERRAIN_DECLARE_ONLY
#include "terrain_sample.glsl"

layout(push_constant, std430) uniform DecalMeshPush { VistaTerrain terrain; } pc;

#undef VISTA_TERRAIN_DECLARE_ONLY
#include "terrain_sample.glsl"

layout(location = 0) out vec3 rel_pos;
layout(location = 1) out vec3 normal;

void main() {
    vec4 p = vertices.v[gl_VertexIndex].position;
    vec2 g = vertices.v[gl_VertexIndex].gradient.xy;
    float ground;
    vec3 n;
    vista_terrain_height(p.xy, ground);
    vista_terrain_normal(p.xy, n);
    // The surface z = ground + raise: gradients add.
    vec2 slope = -n.xy / max(n.z, 1e-3) + g;
    normal = normalize(vec3(-slope, 1.0));
    rel_pos = vec3(p.xy - view.v.camera_world.xy, ground + p.z - view.v.camera_world.z);
    gl_Position = view.v.view_proj * vec4(rel_pos, 1.0);
}

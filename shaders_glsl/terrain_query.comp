#version 460
#extension GL_GOOGLE_include_directive : require
// Terrain queries for an engine (and the test of terrain_sample.glsl):
// height, normal and material at a list of world points, and whether
// terrain was found there at all.
layout(local_size_x = 64) in;

layout(set = 0, binding = 0, std430) readonly buffer SectorData { uint words[]; } sector_data;
layout(set = 0, binding = 1) uniform texture2DArray height_atlas;
layout(set = 0, binding = 2) uniform texture2DArray normal_atlas;
layout(set = 0, binding = 3) uniform utexture2DArray splat_atlas;
layout(set = 0, binding = 4) uniform sampler atlas_sampler;
layout(set = 0, binding = 5, std430) readonly buffer QueryPoints { vec2 points[]; } query_points;
// x: height (m), yzw: normal; material id and found (1/0) in the separate array.
layout(set = 0, binding = 6, std430) buffer QueryResults { vec4 results[]; } query_results;
layout(set = 0, binding = 7, std430) buffer QueryMaterials { uvec2 materials[]; } query_materials;

#define VISTA_SECTOR_WORD(i) sector_data.words[i]
#define VISTA_HEIGHT_ATLAS height_atlas
#define VISTA_NORMAL_ATLAS normal_atlas
#define VISTA_SPLAT_ATLAS splat_atlas
#define VISTA_ATLAS_SAMPLER atlas_sampler
#define VISTA_TERRAIN pc.terrain
#define VISTA_TERRAIN_DECLARE_ONLY
#include "terrain_sample.glsl"

layout(push_constant, std430) uniform TerrainQueryPush { VistaTerrain terrain; uint count; uint pad0; uint pad1; uint pad2; } pc;

#undef VISTA_TERRAIN_DECLARE_ONLY
#include "terrain_sample.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) {
        return;
    }
    vec2 p = query_points.points[i];
    float height;
    vec3 normal;
    uint material;
    bool found = vista_terrain_height(p, height);
    vista_terrain_normal(p, normal);
    vista_terrain_material(p, material);
    query_results.results[i] = vec4(height, normal);
    query_materials.materials[i] = uvec2(material, found ? 1u : 0u);
}

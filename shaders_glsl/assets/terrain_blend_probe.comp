#version 460
#extension GL_GOOGLE_include_directive : require
// Test probe of terrain_blend.glsl (tests/assets.rs): per vertex (world
// position, normal, colour, blend height), what vista_blend_to_terrain
// gives, as the asset pass's vertex shader calls it.
#include "constants.glsl"

layout(local_size_x = 64) in;

layout(set = 0, binding = 0, std430) readonly buffer SectorData { uint words[]; } sector_data;
layout(set = 0, binding = 1) uniform texture2DArray height_atlas;
layout(set = 0, binding = 2) uniform texture2DArray normal_atlas;
layout(set = 0, binding = 3) uniform texture2DArray albedo_atlas;
layout(set = 0, binding = 4) uniform sampler nearest;
layout(set = 0, binding = 5) uniform sampler linear_clamp;
// Per vertex: position + blend height, normal, colour.
layout(set = 0, binding = 6, std430) readonly buffer BlendInputs { vec4 v[]; } inputs;
// Per vertex: normal + weight, colour.
layout(set = 0, binding = 7, std430) buffer BlendResults { vec4 r[]; } results;

#define VISTA_SECTOR_WORD(i) sector_data.words[i]
#define VISTA_HEIGHT_ATLAS height_atlas
#define VISTA_NORMAL_ATLAS normal_atlas
#define VISTA_ALBEDO_ATLAS albedo_atlas
#define VISTA_ATLAS_SAMPLER nearest
#define VISTA_LINEAR_SAMPLER linear_clamp
#define VISTA_NO_MATERIAL_QUERY
#define VISTA_TERRAIN pc.terrain
#define VISTA_TERRAIN_DECLARE_ONLY
#include "terrain_sample.glsl"

layout(push_constant, std430) uniform BlendProbePush { VistaTerrain terrain; uint count; uint pad0; uint pad1; uint pad2; } pc;

#undef VISTA_TERRAIN_DECLARE_ONLY
#include "terrain_sample.glsl"
#include "terrain_blend.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) {
        return;
    }
    vec4 p = inputs.v[3u * i];
    VistaBlend b = vista_blend_to_terrain(p.xyz, inputs.v[3u * i + 1u].xyz, inputs.v[3u * i + 2u].rgb, p.w);
    results.r[2u * i] = vec4(b.normal, b.weight);
    results.r[2u * i + 1u] = vec4(b.albedo, 1.0);
}

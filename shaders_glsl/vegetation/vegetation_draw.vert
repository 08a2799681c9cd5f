#version 460
#extension GL_GOOGLE_include_directive : require
// Trees and bushes (effect vegetation) into the G-buffer: one indexed
// indirect draw per mesh kind and LOD, of the instances vegetation_cull
// kept (gl_InstanceIndex counts from the draw's first instance, its region
// of the visible list). An instance stands on its ground height (the
// source's, `vista vegetate`'s; the trunk reaches 5 % of its height below
// it), turned by its yaw; the trunk takes the bark's colour, the crown its
// type's times its tint; the vertices near the ground blend into the
// terrain's normal and colour (terrain_blend.glsl, as the assets do).
#include "constants.glsl"
#include "terrain_view.glsl"
#include "vegetation.glsl"

layout(set = 0, binding = 0, std430) readonly buffer View { TerrainView v; } view;
layout(set = 0, binding = 1, std430) readonly buffer VegVertices { VegetationVertex v[]; } vertices;
layout(set = 0, binding = 2, std430) readonly buffer VegInstances { VegetationInstance i[]; } instances;
layout(set = 0, binding = 3, std430) readonly buffer VegTypes { VegetationType t[]; } types;
layout(set = 0, binding = 4, std430) readonly buffer VegVisible { uint i[]; } visible;
layout(set = 0, binding = 5, std430) readonly buffer SectorData { uint words[]; } sector_data;
layout(set = 0, binding = 6) uniform texture2DArray height_atlas;
layout(set = 0, binding = 7) uniform texture2DArray normal_atlas;
layout(set = 0, binding = 8) uniform texture2DArray albedo_atlas;
layout(set = 0, binding = 9) uniform sampler nearest;
layout(set = 0, binding = 10) uniform sampler linear_clamp;

#define VISTA_NO_MATERIAL_QUERY
#define VISTA_SECTOR_WORD(i) sector_data.words[i]
#define VISTA_HEIGHT_ATLAS height_atlas
#define VISTA_NORMAL_ATLAS normal_atlas
#define VISTA_ALBEDO_ATLAS albedo_atlas
#define VISTA_ATLAS_SAMPLER nearest
#define VISTA_LINEAR_SAMPLER linear_clamp
#define VISTA_TERRAIN pc.terrain
#define VISTA_TERRAIN_DECLARE_ONLY
#include "terrain_sample.glsl"

layout(push_constant, std430) uniform VegetationDrawPush {
    VistaTerrain terrain;
    float blend_height_m;  // the blend into the terrain fades out over this height
    uint pad0;
    uint pad1;
    uint pad2;
} pc;

#undef VISTA_TERRAIN_DECLARE_ONLY
#include "terrain_sample.glsl"
#include "assets/terrain_blend.glsl"

layout(location = 0) out vec3 albedo;
layout(location = 1) out vec3 normal;

void main() {
    // Member by member: a whole-struct load is OpCopyLogical, which naga cannot parse.
    uint i = visible.i[gl_InstanceIndex];
    uint ty = instances.i[i].type_id;
    vec3 foot = vec3(instances.i[i].x, instances.i[i].y, instances.i[i].z);
    float yaw = instances.i[i].yaw;
    vec4 mp = vertices.v[gl_VertexIndex].position;
    vec4 mn = vertices.v[gl_VertexIndex].normal;
    vec3 lp = mp.xyz * (types.t[ty].height_m * instances.i[i].scale);
    vec2 cs = vec2(cos(yaw), sin(yaw));
    vec3 wp = foot + vec3(cs.x * lp.x - cs.y * lp.y, cs.y * lp.x + cs.x * lp.y, lp.z);
    vec3 wn = vec3(cs.x * mn.x - cs.y * mn.y, cs.y * mn.x + cs.x * mn.y, mn.z);
    vec3 tint = unpackUnorm4x8(instances.i[i].tint).rgb;
    vec3 own = mn.w > 0.5 ? types.t[ty].crown.rgb * tint : vec3(0.13, 0.09, 0.06);
    VistaBlend b = vista_blend_to_terrain(wp, wn, own, pc.blend_height_m);
    albedo = b.albedo;
    normal = b.normal;
    gl_Position = view.v.view_proj * vec4(wp - view.v.camera_world.xyz, 1.0);
}

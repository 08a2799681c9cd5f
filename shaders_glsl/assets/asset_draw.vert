#version 460
#extension GL_GOOGLE_include_directive : require
// The example asset pass (effect assets): rocks and trunks from the
// scene's list, each set on the terrain's height at its origin (sampled
// here, so it follows the resident LOD), and every vertex blended into the
// terrain's normal and colour near the ground through terrain_blend.glsl,
// the include an engine's own asset shaders use. One indexed instanced
// draw per mesh kind. MATERIALS (effect splat, splat mode): the terrain's
// colour is the splat blend over a 0.5 m footprint, as the near ground is
// shaded; without it, the baked albedo.
// variants: MATERIALS
#include "constants.glsl"
#include "terrain_view.glsl"
#include "asset.glsl"

layout(set = 0, binding = 0, std430) readonly buffer View { TerrainView v; } view;
layout(set = 0, binding = 1, std430) readonly buffer AssetVertices { AssetVertex v[]; } vertices;
layout(set = 0, binding = 2, std430) readonly buffer AssetInstances { AssetInstance i[]; } instances;
layout(set = 0, binding = 3, std430) readonly buffer SectorData { uint words[]; } sector_data;
layout(set = 0, binding = 4) uniform texture2DArray height_atlas;
layout(set = 0, binding = 5) uniform texture2DArray normal_atlas;
layout(set = 0, binding = 6) uniform texture2DArray albedo_atlas;
layout(set = 0, binding = 7) uniform sampler nearest;
layout(set = 0, binding = 8) uniform sampler linear_clamp;
#ifdef MATERIALS
#include "materials/materials.glsl"
layout(set = 0, binding = 9) uniform utexture2DArray splat_atlas;
layout(set = 0, binding = 10, std430) readonly buffer Materials { TerrainMaterial m[]; } materials;
layout(set = 0, binding = 11) uniform texture2DArray detail_albedo;
layout(set = 0, binding = 12) uniform texture2DArray detail_normal;
layout(set = 0, binding = 13) uniform texture2DArray detail_height;
layout(set = 0, binding = 14) uniform sampler detail_sampler;
#define VISTA_SPLAT_ATLAS splat_atlas
#else
#define VISTA_NO_MATERIAL_QUERY
#endif

#define VISTA_SECTOR_WORD(i) sector_data.words[i]
#define VISTA_HEIGHT_ATLAS height_atlas
#define VISTA_NORMAL_ATLAS normal_atlas
#define VISTA_ALBEDO_ATLAS albedo_atlas
#define VISTA_ATLAS_SAMPLER nearest
#define VISTA_LINEAR_SAMPLER linear_clamp
#define VISTA_TERRAIN pc.terrain
#define VISTA_TERRAIN_DECLARE_ONLY
#include "terrain_sample.glsl"

layout(push_constant, std430) uniform AssetDrawPush {
    VistaTerrain terrain;
    uint instance_base;     // this draw's first instance
    float blend_height_m;   // the blend into the terrain fades out over this height
    uint pad0;
    uint pad1;
} pc;

#undef VISTA_TERRAIN_DECLARE_ONLY
#include "terrain_sample.glsl"
#ifdef MATERIALS
#include "materials/splat_blend.glsl"
#define VISTA_BLEND_COLOUR(p) splat_blend(p, vec2(0.5, 0.0), vec2(0.0, 0.5)).albedo
#endif
#include "terrain_blend.glsl"

layout(location = 0) out vec3 albedo;
layout(location = 1) out vec3 normal;

void main() {
    uint at = pc.instance_base + uint(gl_InstanceIndex);
    vec4 place = instances.i[at].place;
    vec3 own = instances.i[at].albedo.rgb;
    vec3 lp = vertices.v[gl_VertexIndex].position.xyz * place.w;
    vec3 ln = vertices.v[gl_VertexIndex].normal.xyz;
    float ground;
    vista_terrain_height(place.xy, ground);
    vec2 cs = vec2(cos(place.z), sin(place.z));
    vec3 wp = vec3(place.xy + vec2(cs.x * lp.x - cs.y * lp.y, cs.y * lp.x + cs.x * lp.y), ground + lp.z);
    vec3 wn = vec3(cs.x * ln.x - cs.y * ln.y, cs.y * ln.x + cs.x * ln.y, ln.z);
    VistaBlend b = vista_blend_to_terrain(wp, wn, own, pc.blend_height_m);
    albedo = b.albedo;
    normal = b.normal;
    gl_Position = view.v.view_proj * vec4(wp - view.v.camera_world.xyz, 1.0);
}

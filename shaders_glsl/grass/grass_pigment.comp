#version 460
#extension GL_GOOGLE_include_directive : require
// The grass pigment map (seed 004): a top-down render of the near
// terrain's albedo around the camera, which colours every grass tuft so
// the grass takes the ground's hue. Per texel, the splat material blend
// (splat_blend.glsl, as the splat flavour and the virtual texture's pages
// make it) at the texel's centre with the texel's footprint as the
// derivatives, so the detail textures are read at the mip that averages a
// texel. Stored as the albedo's square root (an 8-bit gamma of 2, as the
// virtual texture's pages); alpha 1 where terrain was found. DECALS
// (effect decals): every decal blended over it in scene order, as
// vt_pages blends them into the pages.
// variants: DECALS
#include "constants.glsl"
#include "materials/materials.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0, std430) readonly buffer SectorData { uint words[]; } sector_data;
layout(set = 0, binding = 1) uniform texture2DArray height_atlas;
layout(set = 0, binding = 2) uniform texture2DArray normal_atlas;
layout(set = 0, binding = 3) uniform utexture2DArray splat_atlas;
layout(set = 0, binding = 4, std430) readonly buffer Materials { TerrainMaterial m[]; } materials;
layout(set = 0, binding = 5) uniform texture2DArray detail_albedo;
layout(set = 0, binding = 6) uniform texture2DArray detail_normal;
layout(set = 0, binding = 7) uniform texture2DArray detail_height;
layout(set = 0, binding = 8) uniform sampler detail_sampler;
layout(set = 0, binding = 9) uniform sampler nearest;
layout(set = 0, binding = 10, rgba8) uniform writeonly image2D pigment;
#ifdef DECALS
#include "virtual_texture/decal.glsl"
layout(set = 0, binding = 11, std430) readonly buffer Decals { Decal d[]; } decals;
layout(set = 0, binding = 12, std430) readonly buffer DecalPoints { vec4 p[]; } decal_points;
layout(set = 0, binding = 13) uniform texture2DArray decal_textures;
layout(set = 0, binding = 14) uniform sampler decal_clamp;
layout(set = 0, binding = 15) uniform sampler decal_repeat;
// The decals touching this pass's square: grass_place's first, grass_pigment's from DECAL_MAX.
layout(set = 0, binding = 16, std430) readonly buffer GrassDecals { uint i[]; } grass_decals;
#include "virtual_texture/decal_shapes.glsl"
#endif

#define VISTA_SECTOR_WORD(i) sector_data.words[i]
#define VISTA_HEIGHT_ATLAS height_atlas
#define VISTA_NORMAL_ATLAS normal_atlas
#define VISTA_SPLAT_ATLAS splat_atlas
#define VISTA_ATLAS_SAMPLER nearest
#define VISTA_TERRAIN pc.terrain
#define VISTA_TERRAIN_DECLARE_ONLY
#include "terrain_sample.glsl"

layout(push_constant, std430) uniform GrassPigmentPush {
    VistaTerrain terrain;
    vec2 origin_m;  // the map's south-west corner (world m)
    float texel_m;
    uint decal_count;  // DECALS: the decals touching the map (grass_decals), in scene order
} pc;

#undef VISTA_TERRAIN_DECLARE_ONLY
#include "terrain_sample.glsl"
#include "materials/splat_blend.glsl"

void main() {
    uvec2 t = gl_GlobalInvocationID.xy;
    if (t.x >= GRASS_PIGMENT_TEXELS || t.y >= GRASS_PIGMENT_TEXELS) {
        return;
    }
    vec2 xy = pc.origin_m + (vec2(t) + 0.5) * pc.texel_m;
    float h;
    bool found = vista_terrain_height(xy, h);
    vec3 albedo = vec3(0.0);
    if (found) {
        albedo = splat_blend(xy, vec2(pc.texel_m, 0.0), vec2(0.0, pc.texel_m)).albedo;
#ifdef DECALS
        for (uint k = 0u; k < pc.decal_count; ++k) {
            uint di = grass_decals.i[DECAL_MAX + k];
            vec4 c = decal_colour(di, xy, pc.texel_m);
            albedo = mix(albedo, c.rgb, c.a * decals.d[di].opacity);
        }
#endif
    }
    imageStore(pigment, ivec2(t), vec4(sqrt(max(albedo, vec3(0.0))), found ? 1.0 : 0.0));
}

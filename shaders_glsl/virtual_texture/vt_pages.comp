#version 460
// Renders the virtual texture's pages of one frame into the physical
// cache (seed 001's tile update): per texel of a page's padded tile, the
// splat material blend (splat_blend.glsl, as gbuffer_tiles' splat flavour
// makes it) at the texel's world point, with the texel's footprint as the
// derivatives. The border texels are the material just beyond the page's
// edge, so bilinear filtering at a page edge reads the neighbouring
// ground, not another tile. Albedo is stored as its square root (an
// 8-bit gamma of 2: dark ground keeps its steps small); the detail image
// holds the tangent (x 1/4, around 0.5), the dominant material and 1.
// DECALS: then the decals touching the page (the job's list, in order) are
// alpha-blended over the albedo and roughness (effects/virtual_texture/decals.rs).
// variants: DECALS
#extension GL_GOOGLE_include_directive : require
#include "constants.glsl"
#include "materials/materials.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

// 1: each texel holds its position code instead of the material (tests):
// albedo (region & 255, region >> 8, page x, page y) / 255, detail
// (level, texel x, texel y, 255) / 255, texels counted in the padded tile.
layout(constant_id = 0) const uint POSITION_CODE = 0u;

layout(set = 0, binding = 0, std430) readonly buffer VtState { uint words[]; } vt_state;
struct PageJob {
    uint tile;
    uint region;
    uint page;   // level | x << 4 | y << 12
    uint decals; // first index in job_decals | count << DECAL_COUNT_SHIFT
};
layout(set = 0, binding = 1, std430) readonly buffer PageJobs { PageJob j[]; } jobs;
layout(set = 0, binding = 2, rgba8) uniform writeonly image2D cache_albedo;
layout(set = 0, binding = 3, rgba8) uniform writeonly image2D cache_detail;
layout(set = 0, binding = 4, std430) readonly buffer SectorData { uint words[]; } sector_data;
layout(set = 0, binding = 5) uniform texture2DArray height_atlas;
layout(set = 0, binding = 6) uniform texture2DArray normal_atlas;
layout(set = 0, binding = 7) uniform utexture2DArray splat_atlas;
layout(set = 0, binding = 8, std430) readonly buffer Materials { TerrainMaterial m[]; } materials;
layout(set = 0, binding = 9) uniform texture2DArray detail_albedo;
layout(set = 0, binding = 10) uniform texture2DArray detail_normal;
layout(set = 0, binding = 11) uniform texture2DArray detail_height;
layout(set = 0, binding = 12) uniform sampler detail_sampler;
layout(set = 0, binding = 13) uniform sampler nearest;

#ifdef DECALS
#include "decal.glsl"
layout(set = 0, binding = 14, std430) readonly buffer Decals { Decal d[]; } decals;
layout(set = 0, binding = 15, std430) readonly buffer DecalPoints { vec4 p[]; } decal_points;
layout(set = 0, binding = 16, std430) readonly buffer JobDecals { uint i[]; } job_decals;
layout(set = 0, binding = 17) uniform texture2DArray decal_textures;
layout(set = 0, binding = 18) uniform sampler decal_clamp;
layout(set = 0, binding = 19) uniform sampler decal_repeat;
#endif

#define VISTA_SECTOR_WORD(i) sector_data.words[i]
#define VISTA_HEIGHT_ATLAS height_atlas
#define VISTA_NORMAL_ATLAS normal_atlas
#define VISTA_SPLAT_ATLAS splat_atlas
#define VISTA_ATLAS_SAMPLER nearest
#define VISTA_TERRAIN pc.terrain
#define VISTA_TERRAIN_DECLARE_ONLY
#include "terrain_sample.glsl"

layout(push_constant, std430) uniform VtPagesPush { VistaTerrain terrain; } pc;

#undef VISTA_TERRAIN_DECLARE_ONLY
#include "terrain_sample.glsl"
#include "materials/splat_blend.glsl"

const uint PADDED = VT_TILE_TEXELS + 2u * VT_TILE_BORDER;

#ifdef DECALS
#include "decal_shapes.glsl"

void blend_decals(uint word, vec2 xy, float texel_m, inout vec3 albedo, inout float roughness) {
    uint first = word & ((1u << DECAL_COUNT_SHIFT) - 1u);
    uint count = word >> DECAL_COUNT_SHIFT;
    for (uint k = 0u; k < count; ++k) {
        uint di = job_decals.i[first + k];
        vec4 c = decal_colour(di, xy, texel_m);
        if (c.a <= 0.0) {
            continue;
        }
        float w = c.a * decals.d[di].opacity;
        albedo = mix(albedo, c.rgb, w);
        float rough = decals.d[di].roughness;
        if (rough >= 0.0) {
            roughness = mix(roughness, rough, w);
        }
    }
}
#endif

void main() {
    uvec2 texel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(texel, uvec2(PADDED)))) {
        return;
    }
    uint job = gl_WorkGroupID.z;
    uint tile = jobs.j[job].tile;
    uint region = jobs.j[job].region;
    uint page = jobs.j[job].page;
    uint level = page & VT_REQ_LEVEL_MASK;
    uvec2 p = uvec2((page >> VT_REQ_X_SHIFT) & VT_REQ_COORD_MASK, (page >> VT_REQ_Y_SHIFT) & VT_REQ_COORD_MASK);
    uint regions_x = vt_state.words[0];
    float region_m = uintBitsToFloat(vt_state.words[4]);
    vec2 origin = vec2(uvec2(region % regions_x, region / regions_x)) * region_m;
    float page_m = region_m / float(1u << level);
    float texel_m = page_m / float(VT_TILE_TEXELS);
    vec2 xy = origin + vec2(p) * page_m + (vec2(texel) - float(VT_TILE_BORDER) + 0.5) * texel_m;
    uint tiles_x = vt_state.words[3];
    ivec2 at = ivec2(uvec2(tile % tiles_x, tile / tiles_x) * PADDED + texel);
    // A variable, not a constant expression: naga reads no SpecConstantOp.
    uint coded = POSITION_CODE;
    if (coded != 0u) {
        imageStore(cache_albedo, at, vec4(float(region & 255u), float((region >> 8u) & 255u), float(p.x), float(p.y)) / 255.0);
        imageStore(cache_detail, at, vec4(float(level), float(texel.x), float(texel.y), 255.0) / 255.0);
        return;
    }
    SplatBlend b = splat_blend(xy, vec2(texel_m, 0.0), vec2(0.0, texel_m));
#ifdef DECALS
    blend_decals(jobs.j[job].decals, xy, texel_m, b.albedo, b.roughness);
#endif
    imageStore(cache_albedo, at, vec4(sqrt(clamp(b.albedo, 0.0, 1.0)), b.roughness));
    imageStore(cache_detail, at, vec4(clamp(b.tangent * 0.25 + 0.5, 0.0, 1.0), float(b.dominant) / 255.0, 1.0));
}

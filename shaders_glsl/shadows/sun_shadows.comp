#version 460
#extension GL_GOOGLE_include_directive : require
// variants: CANOPY
// Sun shadow textures of the nodes in the job list (one per z workgroup):
// per texel, how far above the terrain there the sun's shadow reaches,
// max_i(H(p + u t_i) - t_i tan(elevation)) - H(p), and the t_i that sets
// it, over steps towards the
// sun, H being the finest resident height anywhere (sector data), so a
// ridge in another node casts its shadow here. The march ends where the ray
// clears the world's highest point or at the reach. CANOPY (effect
// vegetation): H adds the trees' and bushes' tops above the ground there
// (effects/vegetation/canopy.rs), so they cast too.
layout(local_size_x = 8, local_size_y = 8) in;

#include "constants.glsl"
#include "sun_shadow.glsl"

struct SunShadowJob {
    uint slot;
    uint lod;
    uint x;
    uint y;
};

layout(set = 0, binding = 0, std430) readonly buffer SectorData { uint words[]; } sector_data;
layout(set = 0, binding = 1) uniform texture2DArray height_atlas;
layout(set = 0, binding = 2) uniform sampler nearest;
layout(set = 0, binding = 3, rg32f) uniform writeonly image2DArray shadow_atlas;
layout(set = 0, binding = 4, std430) readonly buffer Jobs { SunShadowJob jobs[]; } jobs;
#ifdef CANOPY
layout(set = 0, binding = 5, std430) readonly buffer CanopyHeights { uint words[]; } canopy;
#endif

#define VISTA_SECTOR_WORD(i) sector_data.words[i]
#define VISTA_HEIGHT_ATLAS height_atlas
#define VISTA_NORMAL_ATLAS height_atlas
#define VISTA_ATLAS_SAMPLER nearest
#define VISTA_NO_MATERIAL_QUERY
#define VISTA_TERRAIN pc.terrain
#define VISTA_TERRAIN_DECLARE_ONLY
#include "terrain_sample.glsl"

// sun: xy the horizontal unit vector towards the sun, z tan(elevation), w
// the reach (m); params: steps, texture side, jobs, unused; canopy (CANOPY):
// xy its cell (0, 0)'s corner (m), z cells per metre, w the tallest (m);
// canopy_grid: xy its cells, z the nearest distance the march reads it at.
layout(push_constant, std430) uniform SunShadowPush {
    VistaTerrain terrain;
    vec4 sun;
    uvec4 params;
    vec4 canopy_map;
    vec4 canopy_grid;
} pc;

#undef VISTA_TERRAIN_DECLARE_ONLY
#include "terrain_sample.glsl"

#ifdef CANOPY
// Cell c's height (f16 pairs, the first in the low bits); none off the grid.
float canopy_cell(ivec2 c) {
    if (any(lessThan(c, ivec2(0))) || any(greaterThanEqual(c, ivec2(pc.canopy_grid.xy)))) {
        return 0.0;
    }
    uint i = uint(c.y) * uint(pc.canopy_grid.x) + uint(c.x);
    vec2 pair = unpackHalf2x16(canopy.words[i >> 1u]);
    return (i & 1u) == 0u ? pair.x : pair.y;
}

// Bilinear between cell centres (by hand: a sampler's weights may be
// quantised, the CPU twin's are not).
float canopy_at(vec2 p) {
    vec2 g = (p - pc.canopy_map.xy) * pc.canopy_map.z - 0.5;
    vec2 f = floor(g);
    vec2 w = g - f;
    ivec2 c = ivec2(f);
    float south = mix(canopy_cell(c), canopy_cell(c + ivec2(1, 0)), w.x);
    float north = mix(canopy_cell(c + ivec2(0, 1)), canopy_cell(c + ivec2(1, 1)), w.x);
    return mix(south, north, w.y);
}
#endif

void main() {
    uint side = pc.params.y;
    uvec2 t = gl_GlobalInvocationID.xy;
    if (gl_WorkGroupID.z >= pc.params.z || any(greaterThanEqual(t, uvec2(side)))) {
        return;
    }
    // Field by field: a struct copied out of a block is OpCopyLogical,
    // which naga cannot parse.
    uint z = gl_WorkGroupID.z;
    uint slot = jobs.jobs[z].slot;
    float spacing = pc.terrain.spacing_m * float(1u << jobs.jobs[z].lod);
    vec2 origin = vec2(jobs.jobs[z].x, jobs.jobs[z].y) * (128.0 * spacing)
                + vec2(pc.terrain.grid_origin_x_m, pc.terrain.grid_origin_y_m);
    vec2 p = origin + sun_shadow_texel_local(vec2(t), side) * spacing;
    float h0;
    float result = SUN_SHADOW_NONE;
    float at = 0.0;
    float rise = pc.sun.z;
    if (vista_terrain_height(p, h0)) {
        float ceiling = pc.terrain.height_lo + pc.terrain.height_range;
#ifdef CANOPY
        ceiling += pc.canopy_map.w;
#endif
        float last = rise > 0.0 ? min(pc.sun.w, (ceiling - h0) / rise) : pc.sun.w;
        for (uint i = 0u; i < pc.params.x && last > spacing; ++i) {
            float d = sun_shadow_step(i, pc.params.x, spacing, last);
            float h;
            vec2 q = p + pc.sun.xy * d;
            bool found = vista_terrain_height(q, h);
#ifdef CANOPY
            // Not within a cell and a half: there the interpolated canopy
            // and the texels between which lighting_resolve reads the
            // threshold stand above a crown's own sunlit side.
            if (d >= pc.canopy_grid.z) {
                h += canopy_at(q);
            }
#endif
            if (found && h - d * rise > result) {
                result = h - d * rise;
                at = d;
            }
        }
    }
    // Relative to the ground: between texels the ground curves, the
    // shadow's depth below it hardly (an absolute height, interpolated
    // across a valley, would rise above the ground and shadow a lit slope).
    float depth = result == SUN_SHADOW_NONE ? SUN_SHADOW_NONE : result - h0;
    imageStore(shadow_atlas, ivec3(t, slot), vec4(depth, at, 0.0, 0.0));
}

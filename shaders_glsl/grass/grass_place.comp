#version 460
#extension GL_GOOGLE_include_directive : require
// variants: HIZ DECALS OCCURRENCE
// Grass placement (effect grass, seed 004's procedural distribution by
// material): one thread per world cell of the square around the camera.
// A cell within the radius keeps one tuft with its material's probability
// (the rule table), at a point jittered by the cell's own hash, on the
// terrain's height and normal there (terrain_sample.glsl: the finest
// resident node); none where no terrain is found, in a hole (the albedo's
// alpha, when holes are on) or where the material grows nothing. Tufts
// shrink to nothing over the last fade metres of the radius. Those left
// after frustum and (HIZ) depth-pyramid culling are appended to the one
// indirect draw of grass_draw; the header counts each fate. DECALS (effect
// decals): a decal's coverage at the tuft thins its material's
// probability in proportion, so nothing grows on a road. OCCURRENCE
// (`vista vegetate`'s maps, seed 004): a cell whose occurrence bit is off
// is skipped before any terrain is read, and counted.
#include "constants.glsl"
#include "terrain_view.glsl"
#include "octahedral.glsl"
#include "grass.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0, std430) readonly buffer View { TerrainView v; } view;
layout(set = 0, binding = 1, std430) readonly buffer SectorData { uint words[]; } sector_data;
layout(set = 0, binding = 2) uniform texture2DArray height_atlas;
layout(set = 0, binding = 3) uniform texture2DArray normal_atlas;
layout(set = 0, binding = 4) uniform utexture2DArray splat_atlas;
layout(set = 0, binding = 5) uniform texture2DArray albedo_atlas;
layout(set = 0, binding = 6) uniform sampler nearest;
layout(set = 0, binding = 7, std430) readonly buffer Rules { GrassRule r[]; } rules;
layout(set = 0, binding = 8, std430) buffer Header { GrassHeader h; } header;
layout(set = 0, binding = 9, std430) buffer Instances { GrassInstance i[]; } instances;
#ifdef HIZ
layout(set = 0, binding = 10) uniform texture2D hiz;
#include "hiz_test.glsl"
#endif
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
#ifdef OCCURRENCE
// Rows of bits, south first, (occ_width + 31) / 32 words a row.
layout(set = 0, binding = 17, std430) readonly buffer Occurrence { uint words[]; } occurrence;
#endif

#define VISTA_SECTOR_WORD(i) sector_data.words[i]
#define VISTA_HEIGHT_ATLAS height_atlas
#define VISTA_NORMAL_ATLAS normal_atlas
#define VISTA_SPLAT_ATLAS splat_atlas
#define VISTA_ATLAS_SAMPLER nearest
#define VISTA_TERRAIN pc.terrain
#define VISTA_TERRAIN_DECLARE_ONLY
#include "terrain_sample.glsl"

layout(push_constant, std430) uniform GrassPlacePush {
    VistaTerrain terrain;
    ivec2 cell0;         // the square's first cell
    uint side;           // cells a side
    uint flags;          // GRASS_FLAG_*
    float cell_m;
    float radius_m;
    float fade_m;        // the tufts shrink over the radius' last fade_m
    float height_m;      // a tuft's height before its rule's and hash's scale
    uvec2 depth_size;    // the depth target the pyramid was built from
    uint seed;
    float reach_m;       // how far a blade reaches sideways, per metre of height
    uint decal_count;    // DECALS: the decals touching the square (grass_decals)
    float occ_per_m;     // OCCURRENCE: 1 / an occurrence cell's side (a product rounds
                         // exactly, a quotient need not: the CPU twin's bits), the map's cells
    uint occ_width;
    uint occ_height;
} pc;

#undef VISTA_TERRAIN_DECLARE_ONLY
#include "terrain_sample.glsl"

// Whether the nearest sample of the finest node covering `p` is a hole.
bool in_hole(vec2 p) {
    VistaNodeHit h = vista_find_node(p);
    ivec2 t = atlas_texel(ivec2(round(h.local)));
    return texelFetch(sampler2DArray(albedo_atlas, nearest), ivec3(t, int(h.slot)), 0).a < 0.5;
}

#ifdef OCCURRENCE
// Whether the occurrence map lets grass grow at `p` (outside it: no).
bool occurs(vec2 p) {
    vec2 c = floor(p * pc.occ_per_m);
    if (c.x < 0.0 || c.y < 0.0 || c.x >= float(pc.occ_width) || c.y >= float(pc.occ_height)) {
        return false;
    }
    uint i = uint(c.x);
    uint word = occurrence.words[uint(c.y) * ((pc.occ_width + 31u) / 32u) + i / 32u];
    return ((word >> (i % 32u)) & 1u) != 0u;
}
#endif

#include "frustum_box.glsl"

void main() {
    uvec2 g = gl_GlobalInvocationID.xy;
    if (g.x >= pc.side || g.y >= pc.side) {
        return;
    }
    ivec2 cell = pc.cell0 + ivec2(g);
    uvec2 h = grass_cell_hash(cell, pc.seed);
    vec2 p = (vec2(cell) + grass_jitter(h.x)) * pc.cell_m;
    vec2 camera = view.v.camera_world.xy;
    float d = distance(p, camera);
    if (!(d < pc.radius_m)) {
        return;
    }
    atomicAdd(header.h.in_range, 1u);
#ifdef OCCURRENCE
    if (!occurs(p)) {
        atomicAdd(header.h.skipped_occurrence, 1u);
        return;
    }
#endif
    uint material;
    float z;
    vec3 n;
    if (!vista_terrain_material(p, material) || !vista_terrain_height(p, z)) {
        return;
    }
    float density = rules.r[material].density;
#ifdef DECALS
    // Over the cell's footprint: a decal's soft edge thins the grass.
    for (uint k = 0u; k < pc.decal_count; ++k) {
        uint di = grass_decals.i[k];
        density *= 1.0 - decal_colour(di, p, pc.cell_m).a * decals.d[di].opacity;
    }
#endif
    if (!(grass_keep(h.y) < density)) {
        return;
    }
    if ((pc.flags & GRASS_FLAG_HOLES) != 0u && in_hole(p)) {
        return;
    }
    vista_terrain_normal(p, n);
    atomicAdd(header.h.placed, 1u);
    // 0.75..1.25 of the rule's height, shrinking to 0 at the radius.
    float variation = 0.75 + 0.5 * float((h.x * 0x85EBCA6Bu) >> 24u) / 255.0;
    float fade = clamp((pc.radius_m - d) / max(pc.fade_m, 1e-6), 0.0, 1.0);
    float height = pc.height_m * rules.r[material].height * variation * fade;
    vec3 rel = vec3(p - camera, z - view.v.camera_world.z);
    float reach = height * pc.reach_m;
    vec3 lo = rel - vec3(reach, reach, 0.0);
    vec3 hi = rel + vec3(reach, reach, height);
    if ((pc.flags & GRASS_FLAG_FRUSTUM) != 0u && box_outside_frustum(lo, hi)) {
        atomicAdd(header.h.culled_frustum, 1u);
        return;
    }
#ifdef HIZ
    uint level;
    if ((pc.flags & GRASS_FLAG_HIZ) != 0u && !hiz_box_visible(lo, hi, view.v.view_proj, pc.depth_size, level)) {
        atomicAdd(header.h.culled_hiz, 1u);
        return;
    }
#endif
    uint slot = atomicAdd(header.h.instance_count, 1u);
    uvec2 code = oct_encode8(n);
    uint lean = (h.x * 0x9E3779B9u) >> 24u;
    // Member by member: a whole-struct store is OpCopyLogical, which naga cannot parse.
    instances.i[slot].position = vec4(p, z, height);
    instances.i[slot].cell = cell;
    instances.i[slot].packed = material | ((h.y & 0xFFu) << 8u) | (lean << 16u);
    instances.i[slot].normal = code.x | (code.y << 8u);
}

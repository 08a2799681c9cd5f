// Sample vista's terrain at any world position, from any shader (ours or an
// engine's), through the sector data: the finest resident LOD covering the
// point, bilinear over that node's R16 height samples.
//
// Before including, define:
//   VISTA_SECTOR(i)          -> uvec2: sector data entry i (row-major)
//   VISTA_HEIGHT_ATLAS       -> a texture2DArray of R16_UNORM heights (layer = slot)
//   VISTA_NORMAL_ATLAS       -> a texture2DArray of RGBA8 normals
//   VISTA_SPLAT_ATLAS        -> a utexture2DArray of R8_UINT material ids
//   VISTA_ATLAS_SAMPLER      -> a sampler (nearest)
//   VISTA_TERRAIN            -> an lvalue of type VistaTerrain (e.g. a push-constant
//                               member), read in place: a by-value copy out of a
//                               block is OpCopyLogical, which naga cannot parse
// Include once with VISTA_TERRAIN_DECLARE_ONLY defined to get the struct for
// your block, then again without it for the functions (terrain_query.comp).
#ifndef VISTA_TERRAIN_STRUCT
#define VISTA_TERRAIN_STRUCT

struct VistaTerrain {
    float sector_size_m;   // LOD-0 node side
    float spacing_m;       // LOD-0 sample spacing (node side / 128)
    uint sectors_x;        // sector-data row length
    uint sectors_y;
    uint lod_count;        // min(world LODs, 6)
    float height_lo;
    float height_range;    // hi - lo
    uint pad;
};
#endif

#if !defined(VISTA_TERRAIN_DECLARE_ONLY) && !defined(VISTA_TERRAIN_SAMPLE_GLSL)
#define VISTA_TERRAIN_SAMPLE_GLSL
#include "constants.glsl"
#include "atlas_texels.glsl"

struct VistaNodeHit {
    uint slot;   // 0 = nothing resident covers the point
    uint lod;
    vec2 local;  // sample coordinates inside the node, 0..128
};

VistaNodeHit vista_find_node(vec2 p) {
    ivec2 s = clamp(ivec2(floor(p / VISTA_TERRAIN.sector_size_m)), ivec2(0), ivec2(VISTA_TERRAIN.sectors_x - 1u, VISTA_TERRAIN.sectors_y - 1u));
    uvec2 d = VISTA_SECTOR(uint(s.y) * VISTA_TERRAIN.sectors_x + uint(s.x));
    VistaNodeHit hit = VistaNodeHit(0u, 0u, vec2(0.0));
    for (uint k = 0u; k < VISTA_TERRAIN.lod_count; ++k) {
        uint slot = bitfieldExtract(k < SECTOR_LODS_PER_WORD ? d.x : d.y, int(SLOT_BITS * (k % SECTOR_LODS_PER_WORD)), int(SLOT_BITS));
        if (slot != 0u) {
            float node = VISTA_TERRAIN.sector_size_m * float(1u << k);
            vec2 origin = floor(p / node) * node;
            hit = VistaNodeHit(slot, k, clamp((p - origin) / (VISTA_TERRAIN.spacing_m * float(1u << k)), vec2(0.0), vec2(128.0)));
            break;
        }
    }
    return hit;
}

float vista_height_texel(uint slot, ivec2 i) {
    return texelFetch(sampler2DArray(VISTA_HEIGHT_ATLAS, VISTA_ATLAS_SAMPLER), ivec3(i, int(slot)), 0).r;
}

// Height in metres (NaN-free: 0 when nothing is resident).
float vista_terrain_height(vec2 p) {
    VistaNodeHit h = vista_find_node(p);
    if (h.slot == 0u) {
        return 0.0;
    }
    ivec2 i0 = min(ivec2(floor(h.local)), ivec2(127));
    vec2 f = h.local - vec2(i0);
    float a = mix(vista_height_texel(h.slot, i0), vista_height_texel(h.slot, i0 + ivec2(1, 0)), f.x);
    float b = mix(vista_height_texel(h.slot, i0 + ivec2(0, 1)), vista_height_texel(h.slot, i0 + ivec2(1, 1)), f.x);
    return VISTA_TERRAIN.height_lo + mix(a, b, f.y) * VISTA_TERRAIN.height_range;
}

// Unit normal (z up) at the nearest sample.
vec3 vista_terrain_normal(vec2 p) {
    VistaNodeHit h = vista_find_node(p);
    if (h.slot == 0u) {
        return vec3(0.0, 0.0, 1.0);
    }
    vec4 t = texelFetch(sampler2DArray(VISTA_NORMAL_ATLAS, VISTA_ATLAS_SAMPLER), ivec3(atlas_texel(ivec2(round(h.local))), int(h.slot)), 0);
    vec2 xy = atlas_normal_xy(t);
    return vec3(xy, sqrt(max(1.0 - dot(xy, xy), 0.0)));
}

#ifndef VISTA_NO_MATERIAL_QUERY
// Material id at the nearest splat texel (65x65 per node). Define
// VISTA_NO_MATERIAL_QUERY where no splat atlas is bound.
uint vista_terrain_material(vec2 p) {
    VistaNodeHit h = vista_find_node(p);
    if (h.slot == 0u) {
        return 0u;
    }
    ivec2 i = ivec2(round(h.local * 0.5));
    return texelFetch(usampler2DArray(VISTA_SPLAT_ATLAS, VISTA_ATLAS_SAMPLER), ivec3(i, int(h.slot)), 0).r;
}

#endif

#endif

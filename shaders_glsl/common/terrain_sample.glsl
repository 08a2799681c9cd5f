// Sample vista's terrain at any world position, from any shader (ours or an
// engine's), through the sector data: the finest resident LOD covering the
// point, bilinear over that node's R16 height samples. Every query says
// whether terrain was found: outside the world extent, or where no resident
// node covers the point, it returns false and a neutral value, never a
// plausible-looking 0 m.
//
// Before including, define:
//   VISTA_SECTOR_WORD(i)     -> uint: word i of the sector data (sector s
//                               holds words s * SECTOR_DATA_WORDS onwards)
//   VISTA_HEIGHT_ATLAS       -> a texture2DArray of R16_UNORM heights (layer = slot)
//   VISTA_NORMAL_ATLAS       -> a texture2DArray of RGBA8 normals
//   VISTA_SPLAT_ATLAS        -> a utexture2DArray of R8_UINT material ids
//   VISTA_ATLAS_SAMPLER      -> a sampler (nearest)
// and, for vista_terrain_albedo only:
//   VISTA_ALBEDO_ATLAS       -> a texture2DArray of the baked albedo (linear RGB)
//   VISTA_LINEAR_SAMPLER     -> a sampler (linear, clamped)
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
    uint lod_count;        // world LODs (<= MAX_NODE_LODS)
    float height_lo;
    float height_range;    // hi - lo
    float extent_x_m;      // world extent: outside it nothing is found
    float extent_y_m;
    float grid_origin_x_m; // where LOD-0 sample (0, 0) lies (a height map's first post, or 0)
    float grid_origin_y_m;
    uint pad;
};
#endif

#if !defined(VISTA_TERRAIN_DECLARE_ONLY) && !defined(VISTA_TERRAIN_SAMPLE_GLSL)
#define VISTA_TERRAIN_SAMPLE_GLSL
#include "constants.glsl"
#include "atlas_texels.glsl"

struct VistaNodeHit {
    bool found;  // false: outside the extent or nothing resident covers the point
    uint slot;
    uint lod;
    vec2 local;  // sample coordinates inside the node, 0..128
};

VistaNodeHit vista_find_node(vec2 p) {
    VistaNodeHit hit = VistaNodeHit(false, 0u, 0u, vec2(0.0));
    if (!(all(greaterThanEqual(p, vec2(0.0))) && p.x < VISTA_TERRAIN.extent_x_m && p.y < VISTA_TERRAIN.extent_y_m)) {
        return hit;
    }
    // Grid coordinates: metres from LOD-0 sample (0, 0).
    p -= vec2(VISTA_TERRAIN.grid_origin_x_m, VISTA_TERRAIN.grid_origin_y_m);
    if (any(lessThan(p, vec2(0.0)))) {
        return hit;
    }
    uvec2 s = min(uvec2(floor(p / VISTA_TERRAIN.sector_size_m)), uvec2(VISTA_TERRAIN.sectors_x - 1u, VISTA_TERRAIN.sectors_y - 1u));
    uint base = (s.y * VISTA_TERRAIN.sectors_x + s.x) * SECTOR_DATA_WORDS;
    for (uint k = 0u; k < min(VISTA_TERRAIN.lod_count, MAX_NODE_LODS); ++k) {
        uint word = VISTA_SECTOR_WORD(base + k / SECTOR_LODS_PER_WORD);
        uint slot = bitfieldExtract(word, int(SLOT_BITS * (k % SECTOR_LODS_PER_WORD)), int(SLOT_BITS));
        if (slot != 0u) {
            float node = VISTA_TERRAIN.sector_size_m * float(1u << k);
            vec2 origin = floor(p / node) * node;
            hit = VistaNodeHit(true, slot, k, clamp((p - origin) / (VISTA_TERRAIN.spacing_m * float(1u << k)), vec2(0.0), vec2(128.0)));
            break;
        }
    }
    return hit;
}

// The 2 x 2 texels around `p` of a map with one texel per two samples
// (65 x 65 per node: splat, control) in the finest resident node: the
// first texel and layer in `base` (the others at +x, +y, +xy), and their
// bilinear weights in that order; false where no node covers `p`.
bool vista_map_texels(vec2 p, out ivec3 base, out vec4 weights) {
    base = ivec3(0);
    weights = vec4(1.0, 0.0, 0.0, 0.0);
    VistaNodeHit hit = vista_find_node(p);
    if (!hit.found) {
        return false;
    }
    vec2 t = hit.local * 0.5;
    ivec2 i0 = min(ivec2(floor(t)), ivec2(int(SPLAT_TEXELS) - 2));
    vec2 f = clamp(t - vec2(i0), 0.0, 1.0);
    base = ivec3(i0, int(hit.slot));
    weights = vec4((1.0 - f.x) * (1.0 - f.y), f.x * (1.0 - f.y), (1.0 - f.x) * f.y, f.x * f.y);
    return true;
}

// R16 height of node sample `i` (the layer has a 2-sample border).
float vista_height_texel(uint slot, ivec2 i) {
    return texelFetch(sampler2DArray(VISTA_HEIGHT_ATLAS, VISTA_ATLAS_SAMPLER), ivec3(atlas_texel(i), int(slot)), 0).r;
}

// Whether terrain covers `p`; its height in metres there (0 where not).
bool vista_terrain_height(vec2 p, out float height_m) {
    height_m = 0.0;
    VistaNodeHit h = vista_find_node(p);
    if (!h.found) {
        return false;
    }
    ivec2 i0 = min(ivec2(floor(h.local)), ivec2(127));
    vec2 f = h.local - vec2(i0);
    float a = mix(vista_height_texel(h.slot, i0), vista_height_texel(h.slot, i0 + ivec2(1, 0)), f.x);
    float b = mix(vista_height_texel(h.slot, i0 + ivec2(0, 1)), vista_height_texel(h.slot, i0 + ivec2(1, 1)), f.x);
    height_m = VISTA_TERRAIN.height_lo + mix(a, b, f.y) * VISTA_TERRAIN.height_range;
    return true;
}

// Whether terrain covers `p`; its unit normal (z up) at the nearest sample
// (straight up where not).
bool vista_terrain_normal(vec2 p, out vec3 normal) {
    normal = vec3(0.0, 0.0, 1.0);
    VistaNodeHit h = vista_find_node(p);
    if (!h.found) {
        return false;
    }
    vec4 t = texelFetch(sampler2DArray(VISTA_NORMAL_ATLAS, VISTA_ATLAS_SAMPLER), ivec3(atlas_texel(ivec2(round(h.local))), int(h.slot)), 0);
    vec2 xy = atlas_normal_xy(t);
    normal = vec3(xy, sqrt(max(1.0 - dot(xy, xy), 0.0)));
    return true;
}

#ifdef VISTA_ALBEDO_ATLAS
// Whether terrain covers `p`; its baked albedo there (linear RGB, filtered
// over the finest resident node's albedo layer: the far atlas flavour's
// colour; mid grey where not).
bool vista_terrain_albedo(vec2 p, out vec3 albedo) {
    albedo = vec3(0.5);
    VistaNodeHit h = vista_find_node(p);
    if (!h.found) {
        return false;
    }
    vec3 uvw = vec3(atlas_texel_uv(h.local), float(h.slot));
    albedo = textureLod(sampler2DArray(VISTA_ALBEDO_ATLAS, VISTA_LINEAR_SAMPLER), uvw, 0.0).rgb;
    return true;
}
#endif

#ifndef VISTA_NO_MATERIAL_QUERY
// Whether terrain covers `p`; its material id at the nearest splat texel
// (65x65 per node; 0 where not). Define VISTA_NO_MATERIAL_QUERY where no
// splat atlas is bound.
bool vista_terrain_material(vec2 p, out uint id) {
    id = 0u;
    VistaNodeHit h = vista_find_node(p);
    if (!h.found) {
        return false;
    }
    ivec2 i = ivec2(round(h.local * 0.5));
    id = texelFetch(usampler2DArray(VISTA_SPLAT_ATLAS, VISTA_ATLAS_SAMPLER), ivec3(i, int(h.slot)), 0).r;
    return true;
}

#endif

#endif

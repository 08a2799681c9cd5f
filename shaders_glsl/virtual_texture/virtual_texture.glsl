// Addressing of the adaptive virtual texture (effects/virtual_texture): a
// world point's region and sub-texture, the level a screen footprint asks
// for, and the indirection texel of a page. The includer defines
// VISTA_VT_WORD(i), word i of the state buffer (constants.glsl lays it out).
#ifndef VISTA_VIRTUAL_TEXTURE_GLSL
#define VISTA_VIRTUAL_TEXTURE_GLSL
#include "constants.glsl"

struct VtSub {
    bool valid;
    uint region;
    uint k;          // finest level
    uvec2 offset;    // square in the indirection's mip 0
    vec2 origin;     // region's south-west corner (world m)
    float region_m;
};

VtSub vt_sub_texture(vec2 xy) {
    VtSub s;
    s.valid = false;
    s.region_m = uintBitsToFloat(VISTA_VT_WORD(4u));
    uvec2 n = uvec2(VISTA_VT_WORD(0u), VISTA_VT_WORD(1u));
    vec2 c = floor(xy / s.region_m);
    if (any(lessThan(c, vec2(0.0))) || any(greaterThanEqual(c, vec2(n)))) {
        return s;
    }
    uvec2 r = uvec2(c);
    s.region = r.x + r.y * n.x;
    // The window's slot of the region: empty, or another region's.
    uint window = VISTA_VT_WORD(7u);
    uint slot = r.x % window + (r.y % window) * window;
    uint w = VISTA_VT_WORD(VT_STATE_HEADER + slot);
    if (w == VT_NONE || VISTA_VT_WORD(VT_STATE_HEADER + window * window + slot) != s.region) {
        return s;
    }
    s.valid = true;
    s.k = w >> VT_SUB_K_SHIFT;
    s.offset = uvec2(w & VT_SUB_COORD_MASK, (w >> VT_SUB_Y_SHIFT) & VT_SUB_COORD_MASK);
    s.origin = c * s.region_m;
    return s;
}

// The level whose texels match a footprint of `footprint_m` metres (finer
// levels are larger; not clamped).
float vt_level(float footprint_m, float region_m) {
    return log2(region_m / (float(VT_TILE_TEXELS) * max(footprint_m, 1e-9)));
}

// The page of `level` holding `xy`, and where in it (0..1).
uvec2 vt_page(VtSub s, vec2 xy, uint level, out vec2 within) {
    float page_m = s.region_m / float(1u << level);
    vec2 t = (xy - s.origin) / page_m;
    uvec2 p = min(uvec2(max(floor(t), vec2(0.0))), uvec2((1u << level) - 1u));
    within = t - vec2(p);
    return p;
}

// Word index of the indirection texel of page `p` of `level` (<= s.k).
uint vt_indirection_word(VtSub s, uint level, uvec2 p) {
    uint side = VISTA_VT_WORD(2u);
    uint m = s.k - level;
    uint offset = 0u;
    for (uint i = 0u; i < m; ++i) {
        offset += (side >> i) * (side >> i);
    }
    uint window = VISTA_VT_WORD(7u);
    uvec2 t = (s.offset >> m) + p;
    return VT_STATE_HEADER + 2u * window * window + offset + t.y * (side >> m) + t.x;
}

// The page holding `xy` at `level` (<= s.k), or at the nearest coarser
// level resident: its tile's first texel in the cache past the border
// (texels), the point's place in the page (texels, 0..VT_TILE_TEXELS)
// and the level found; false where no level is. Filtering from `local`
// gives the same result wherever the tile lies (the cache's absolute
// coordinates round differently from tile to tile).
bool vt_find_tile(VtSub s, vec2 xy, uint level, out uvec2 corner, out vec2 local, out uint found) {
    for (int l = int(level); l >= 0; --l) {
        vec2 within;
        uvec2 p = vt_page(s, xy, uint(l), within);
        uint tile = VISTA_VT_WORD(vt_indirection_word(s, uint(l), p));
        if (tile == VT_NONE) {
            continue;
        }
        uint tiles_x = VISTA_VT_WORD(3u);
        uint padded = VT_TILE_TEXELS + 2u * VT_TILE_BORDER;
        corner = uvec2(tile % tiles_x, tile / tiles_x) * padded + VT_TILE_BORDER;
        local = within * float(VT_TILE_TEXELS);
        found = uint(l);
        return true;
    }
    corner = uvec2(0u);
    local = vec2(0.0);
    found = 0u;
    return false;
}

// As vt_find_tile, the texel coordinate in the cache in one.
bool vt_find(VtSub s, vec2 xy, uint level, out vec2 texel, out uint found) {
    uvec2 corner;
    vec2 local;
    bool hit = vt_find_tile(s, xy, level, corner, local, found);
    texel = vec2(corner) + local;
    return hit;
}

uint vt_request_word(uint level, uvec2 p) {
    return level | (p.x << VT_REQ_X_SHIFT) | (p.y << VT_REQ_Y_SHIFT);
}

#endif

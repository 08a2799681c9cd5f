// The normal and albedo atlas layers (src/world/texels.rs): texel t holds
// node sample t - ATLAS_BORDER, and normal texels keep x in alpha and y in
// green (BC3's two best channels), smoothness in red.
#ifndef VISTA_ATLAS_TEXELS_GLSL
#define VISTA_ATLAS_TEXELS_GLSL

#include "constants.glsl"

// Texel of node sample `s` (0..128 per axis).
ivec2 atlas_texel(ivec2 s) {
    return s + ivec2(int(ATLAS_BORDER));
}

// Filtering coordinates of the point `s` in node samples (0..128).
vec2 atlas_texel_uv(vec2 s) {
    return (s + float(ATLAS_BORDER) + 0.5) / float(ATLAS_TEXTURE_SIDE);
}

// Baked as n * 127.5 + 127.5 in 8 bits: UNORM u = n / 2 + 1 / 2.
vec2 atlas_normal_xy(vec4 t) {
    return t.ag * 2.0 - 1.0;
}

float atlas_smoothness(vec4 t) {
    return t.r;
}

#endif

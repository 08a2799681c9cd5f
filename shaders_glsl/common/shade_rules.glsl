// Which shading flavours a terrain pixel needs, and how much of each: the
// classification rule of terrain_geometry.frag and the blend weights of
// gbuffer_tiles.frag, one function so both agree. Every threshold is a field
// of the view (scene/shading.rs), not a literal here.
//
//   c  = cliff share from the geometric normal's z (cliffs effect only)
//   f  = far-atlas share from view depth (1 everywhere without splat)
//   fc = far-cliff share from view depth
//   near cliff = c (1 - fc), far cliff = c fc, splat = (1 - c)(1 - f),
//   far atlas = (1 - c) f: the shares sum to 1 and a pixel needs exactly
//   the flavours with a positive share. The near material flavour ("splat"
//   here) is the control-map or the virtual-texture flavour where the
//   scene allows that one.
//
// A control-map pixel also records how many tri-planar planes its
// background samples (CLASS_PLANES_*), from the same decoded normal code
// gbuffer_tiles reads.
#ifndef VISTA_SHADE_RULES_GLSL
#define VISTA_SHADE_RULES_GLSL
#include "constants.glsl"

float ramp(float x, float lo, float hi) {
    return clamp((x - lo) / max(hi - lo, 1e-6), 0.0, 1.0);
}

// Shares in flavour-bit order: x unused (the virtual texture's share is
// the near material's, `splat`), y far atlas, z near cliff, w far cliff; splat in
// `splat`.
vec4 flavour_shares(float depth_m, float normal_z, vec4 bands, vec4 slope, uint allowed, out float splat) {
    float c = (allowed & FLAVOUR_NEAR_CLIFF) != 0u ? ramp(slope.x - normal_z, 0.0, slope.x - slope.y) : 0.0;
    float f = (allowed & (FLAVOUR_SPLAT | FLAVOUR_CONTROL_MAP | FLAVOUR_VIRTUAL_TEXTURE)) != 0u ? ramp(depth_m, bands.x, bands.y) : 1.0;
    float fc = ramp(depth_m, bands.z, bands.w);
    splat = (1.0 - c) * (1.0 - f);
    return vec4(0.0, (1.0 - c) * f, c * (1.0 - fc), c * fc);
}

uint flavour_bits(vec4 shares, float splat, uint allowed) {
    uint near = (allowed & FLAVOUR_CONTROL_MAP) != 0u ? FLAVOUR_CONTROL_MAP
              : ((allowed & FLAVOUR_VIRTUAL_TEXTURE) != 0u ? FLAVOUR_VIRTUAL_TEXTURE : FLAVOUR_SPLAT);
    uint bits = 0u;
    bits |= shares.y > 0.0 ? FLAVOUR_FAR_ATLAS : 0u;
    bits |= shares.z > 0.0 ? FLAVOUR_NEAR_CLIFF : 0u;
    bits |= shares.w > 0.0 ? FLAVOUR_FAR_CLIFF : 0u;
    bits |= splat > 0.0 ? near : 0u;
    return bits;
}

// Planes of the tightened tri-planar blend at normal `n` (1 to 3): those
// whose abs(n) component exceeds `tighten` (the dominant one at least).
uint tri_planar_planes(vec3 n, float tighten) {
    bvec3 on = greaterThan(abs(n), vec3(tighten));
    return max(uint(on.x) + uint(on.y) + uint(on.z), 1u);
}

// The classification's plane bits for `planes` (1 to 3).
uint plane_bits(uint planes) {
    return (planes >= 2u ? CLASS_PLANES_2 : 0u) | (planes >= 3u ? CLASS_PLANES_3 : 0u);
}

#endif

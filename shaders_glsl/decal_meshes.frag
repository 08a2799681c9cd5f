#version 460
#extension GL_GOOGLE_include_directive : require
// A displacement decal's mesh in the geometry pass: what terrain_geometry
// writes for terrain (the classification by its normal and depth, the
// normal codes, no patch info), so gbuffer_tiles shades it as terrain.
#include "terrain_view.glsl"
#include "octahedral.glsl"
#include "shade_rules.glsl"

layout(set = 0, binding = 0, std430) readonly buffer View { TerrainView v; } view;

layout(location = 0) in vec3 rel_pos;
layout(location = 1) in vec3 normal;
layout(location = 0) out uint classification;
layout(location = 1) out uvec4 normals;
layout(location = 2) out uint patch_info;

void main() {
    vec3 geometric = normalize(normal);
    vec3 t = cross(dFdx(rel_pos), dFdy(rel_pos));
    float tl = length(t);
    vec3 triangle = tl > 0.0 ? t / tl : geometric;
    triangle = dot(triangle, rel_pos) > 0.0 ? -triangle : triangle;
    float depth_m = 1.0 / gl_FragCoord.w;
    float splat;
    vec4 shares = flavour_shares(depth_m, geometric.z, view.v.shade_bands, view.v.shade_slope, view.v.shade_flags.x, splat);
    uvec2 code = oct_encode8(geometric);
    classification = flavour_bits(shares, splat, view.v.shade_flags.x);
    normals = uvec4(code, oct_encode8(triangle));
    patch_info = 0u;
}

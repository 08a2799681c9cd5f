// What the geometry pass writes for a surface the tile passes shade as
// terrain, for meshes drawn beside the height field (decal_meshes,
// cliff_meshes): the classification from the surface's normal and view
// depth (shade_rules.glsl, as terrain_geometry.frag), the two normal
// codes (the mesh's smooth normal as the geometric one, the triangle's
// from the screen derivatives) and no patch info.
#ifndef VISTA_GEOMETRY_OUTPUTS_GLSL
#define VISTA_GEOMETRY_OUTPUTS_GLSL
#include "terrain_view.glsl"
#include "octahedral.glsl"
#include "shade_rules.glsl"

layout(set = 0, binding = 0, std430) readonly buffer View { TerrainView v; } view;

layout(location = 0) in vec3 rel_pos;
layout(location = 1) in vec3 normal;
layout(location = 0) out uint classification;
layout(location = 1) out uvec4 normals;
layout(location = 2) out uint patch_info;

void write_geometry() {
    vec3 geometric = normalize(normal);
    vec3 t = cross(dFdx(rel_pos), dFdy(rel_pos));
    float tl = length(t);
    vec3 triangle = tl > 0.0 ? t / tl : geometric;
    triangle = dot(triangle, rel_pos) > 0.0 ? -triangle : triangle;
    float depth_m = 1.0 / gl_FragCoord.w;
    float splat;
    vec4 shares = flavour_shares(depth_m, geometric.z, view.v.shade_bands, view.v.shade_slope, view.v.shade_flags.x, splat);
    classification = flavour_bits(shares, splat, view.v.shade_flags.x);
    normals = uvec4(oct_encode8(geometric), oct_encode8(triangle));
    patch_info = 0u;
}

#endif

// The terrain's fragment stage in the geometry pass of the G-buffer tile
// shading (terrain_geometry.frag, terrain_triangles.frag): besides depth and the
// engine's terrain stencil bit (pipeline state, where asked for), each pixel records which shading
// flavours it needs (classification, shade_rules.glsl) and two octahedral
// normals as 8-bit codes: the node's baked (smooth, geometric) normal and
// the normal of the triangle drawn, from the screen derivatives of its
// position. gbuffer_tiles shades from these; nothing is lit here. The
// patch info (level, refinement, phase, grid edge) is for the debug views.
#ifndef VISTA_TERRAIN_FRAGMENT_GLSL
#define VISTA_TERRAIN_FRAGMENT_GLSL

#include "terrain_view.glsl"
#include "octahedral.glsl"
#include "atlas_texels.glsl"
#include "shade_rules.glsl"

layout(set = 0, binding = 0, std430) readonly buffer View { TerrainView v; } view;
layout(set = 0, binding = 5) uniform texture2DArray normal_atlas;
layout(set = 0, binding = 6) uniform sampler linear_clamp;

layout(location = 0) in vec2 atlas_uv;
layout(location = 1) flat in uint atlas_layer;
layout(location = 2) in vec3 rel_pos;
layout(location = 3) flat in uint patch_code;
layout(location = 4) in vec2 patch_uv;
layout(location = 0) out uint classification;
layout(location = 1) out uvec4 normals;
layout(location = 2) out uint patch_info;

#ifdef SINK
#include "terrain_sink.glsl"
layout(set = 0, binding = 7, std430) readonly buffer Sink { TerrainSinkHeader h; uint bits[]; } sink;
// Only ever farther (reversed-Z: smaller), so early depth rejection holds.
layout(depth_less) out float gl_FragDepth;

// This fragment's depth, pushed behind by the sink along its normal where
// its world cell is sunk (the view ray's share of the normal clamped).
float sunk_depth(vec3 normal) {
    vec2 world = view.v.camera_world.xy + rel_pos.xy;
    ivec2 c = ivec2(floor(world / sink.h.cell_m)) - sink.h.cell0;
    uint side = sink.h.side;
    if (any(lessThan(c, ivec2(0))) || any(greaterThanEqual(c, ivec2(side)))) {
        return gl_FragCoord.z;
    }
    uint i = uint(c.y) * side + uint(c.x);
    if ((sink.bits[i >> 5u] & (1u << (i & 31u))) == 0u) {
        return gl_FragCoord.z;
    }
    float d = length(rel_pos);
    float along = sink.h.sink_m / max(abs(dot(normal, rel_pos / d)), TERRAIN_SINK_MIN_COSINE);
    vec4 clip = view.v.view_proj * vec4(rel_pos * ((d + along) / d), 1.0);
    return min(clip.z / clip.w, gl_FragCoord.z);
}
#endif

void main() {
    vec3 uvw = vec3(atlas_uv, float(atlas_layer));
    vec2 nxy = atlas_normal_xy(texture(sampler2DArray(normal_atlas, linear_clamp), uvw));
    vec3 geometric = normalize(vec3(nxy, sqrt(max(1.0 - dot(nxy, nxy), 0.0))));
#ifdef SINK
    gl_FragDepth = sunk_depth(geometric);
#endif
    vec3 t = cross(dFdx(rel_pos), dFdy(rel_pos));
    float tl = length(t);
    // Degenerate derivatives (a sliver seen edge-on): the baked normal.
    vec3 triangle = tl > 0.0 ? t / tl : geometric;
    // Face the camera (the camera sits at the origin of rel_pos).
    triangle = dot(triangle, rel_pos) > 0.0 ? -triangle : triangle;
    float depth_m = 1.0 / gl_FragCoord.w;
    float splat;
    vec4 shares = flavour_shares(depth_m, geometric.z, view.v.shade_bands, view.v.shade_slope, view.v.shade_flags.x, splat);
    uint allowed = view.v.shade_flags.x;
    uvec2 code = oct_encode8(geometric);
    classification = flavour_bits(shares, splat, allowed);
    if ((classification & FLAVOUR_CONTROL_MAP) != 0u) {
        classification |= plane_bits(tri_planar_planes(oct_decode8(code), view.v.control.x));
    }
    normals = uvec4(code, oct_encode8(triangle));
    // Within a pixel of the patch grid's edge (the debug views' outlines).
    vec2 edge = min(patch_uv, 1.0 - patch_uv) / max(fwidth(patch_uv), vec2(1e-6));
    patch_info = patch_code | (uint(min(edge.x, edge.y) < 1.0) << PATCH_INFO_EDGE_SHIFT);
}

#endif

// The terrain vertex: one instanced indirect draw of a 17x17-vertex patch per
// listed patch (instance = patch record). Edge vertices next to a coarser
// neighbour snap to its grid and take the height there, so shared edges are
// bit-identical. With TERRAIN_HOLES defined (terrain_holes.vert, the draw of
// the patches that have holes) a hole vertex becomes NaN, made at run time,
// and its triangles vanish; terrain_geometry.vert has no hole test at all.
#ifndef VISTA_TERRAIN_VERTEX_GLSL
#define VISTA_TERRAIN_VERTEX_GLSL
#include "common.glsl"
#include "node_list.glsl"
#include "terrain_view.glsl"
#include "patch_list.glsl"
#include "atlas_texels.glsl"

// Patches per node side and quads per patch side (world layout).
layout(constant_id = 1) const uint PATCHES_PER_SIDE = 8u;
layout(constant_id = 2) const uint PATCH_QUADS = 16u;

layout(set = 0, binding = 0, std430) readonly buffer View { TerrainView v; } view;
layout(set = 0, binding = 1, std430) readonly buffer PatchList {
    PatchListHeader header;
    uvec2 patches[];
} patch_list;
layout(set = 0, binding = 2) uniform texture2DArray height_atlas;
layout(set = 0, binding = 4) uniform sampler nearest;
#ifdef TERRAIN_HOLES
// Hole mask: the albedo's alpha (below 0.5 = hole).
layout(set = 0, binding = 3) uniform texture2DArray albedo_atlas;

layout(push_constant, std430) uniform HolesPush {
    uint nan_bits;  // a quiet NaN's bits, passed in so no compiler folds it
    uint pad0;
    uint pad1;
    uint pad2;
} pc;
#endif

layout(location = 0) out vec2 atlas_uv;
layout(location = 1) flat out uint atlas_layer;
// Camera-relative position: its screen derivatives give the triangle normal.
layout(location = 2) out vec3 rel_pos;

// Nearest point of the grid 2^delta coarser, ties toward the lower one.
uint snap(uint i, uint delta) {
    if (delta == 0u) {
        return i;
    }
    uint half_step = 1u << (delta - 1u);
    return ((i + half_step - 1u) >> delta) << delta;
}

void main() {
    // Spec constants read into variables: expressions of spec constants
    // alone become OpSpecConstantOp, which naga cannot parse.
    uint per_side = PATCHES_PER_SIDE, quads = PATCH_QUADS;
    uvec2 p = patch_list.patches[gl_InstanceIndex];
    uint n = p.x, slot = patch_slot(p), index = patch_index(p);
    uint side = quads + 1u;
    uint i = uint(gl_VertexIndex) % side, j = uint(gl_VertexIndex) / side;
    uint si = i, sj = j;
    if (j == 0u) {
        si = snap(i, patch_delta(p, EDGE_SOUTH));
    } else if (j == quads) {
        si = snap(i, patch_delta(p, EDGE_NORTH));
    }
    if (i == 0u) {
        sj = snap(j, patch_delta(p, EDGE_WEST));
    } else if (i == quads) {
        sj = snap(j, patch_delta(p, EDGE_EAST));
    }
    uvec2 pxy = uvec2(index % per_side, index / per_side);
    ivec2 local = ivec2(pxy * quads + uvec2(si, sj));
    uint lod = node_lod(n);
    ivec2 g = (ivec2(node_x(n), node_y(n)) * int(per_side * quads) + local) << lod;
    float h = texelFetch(sampler2DArray(height_atlas, nearest), ivec3(atlas_texel(local), int(slot)), 0).r;
    precise float z = view.v.height_lo + h * view.v.height_range - view.v.camera_z;
    vec3 rel = vec3(view_rel_xy(g, view.v.camera_sample, view.v.camera_frac, view.v.spacing_m), z);
    gl_Position = view.v.view_proj * vec4(rel, 1.0);
    rel_pos = rel;
#ifdef TERRAIN_HOLES
    if (texelFetch(sampler2DArray(albedo_atlas, nearest), ivec3(atlas_texel(local), int(slot)), 0).a < 0.5) {
        gl_Position = vec4(runtime_nan(pc.nan_bits));
    }
#endif
    atlas_uv = atlas_texel_uv(vec2(local));
    atlas_layer = slot;
}

#endif

// The terrain vertex: one instanced indirect draw of a 9x9-vertex patch per
// listed patch (instance = patch record). A patch refined below LOD 0 is 4
// or 16 sub-patches of the same grid whose vertices lie on the Catmull-Rom
// surface of the node's samples (the finest surface the error tree
// measures against). Edge vertices next to a coarser neighbour snap to its
// grid and take the height there, so shared edges are bit-identical: every
// step of the position, to gl_Position, is `precise`, so terrain_geometry
// and terrain_holes (which include this same code) cannot be compiled into
// different arithmetic (`invariant gl_Position` would say the same, but
// lavapipe's SPIR-V reader warns about the decoration on gl_PerVertex). With TERRAIN_HOLES defined
// (terrain_holes.vert, the draw of the patches that have holes) a hole
// vertex becomes NaN, made at run time, and its triangles vanish;
// terrain_geometry.vert has no hole test at all.
#ifndef VISTA_TERRAIN_VERTEX_GLSL
#define VISTA_TERRAIN_VERTEX_GLSL
#include "common.glsl"
#include "node_list.glsl"
#include "terrain_view.glsl"
#include "patch_list.glsl"
#include "atlas_texels.glsl"

// Patches per node side and quads per patch side (world layout).
layout(constant_id = 1) const uint PATCHES_PER_SIDE = 16u;
layout(constant_id = 2) const uint PATCH_QUADS = 8u;

layout(set = 0, binding = 0, std430) readonly buffer View { TerrainView v; } view;
layout(set = 0, binding = 1, std430) readonly buffer PatchList {
    PatchListHeader header;
    uvec4 patches[];
} patch_list;
layout(set = 0, binding = 2) uniform texture2DArray height_atlas;
layout(set = 0, binding = 4) uniform sampler nearest;
#ifdef TERRAIN_HOLES
// Hole mask: the albedo's alpha (below 0.5 = hole).
layout(set = 0, binding = 3) uniform texture2DArray albedo_atlas;
#endif

layout(push_constant, std430) uniform TerrainDrawPush {
    uint nan_bits;  // a quiet NaN's bits, passed in so no compiler folds it (holes)
    uint phase;     // 0: phase 1's draw, 1: occlusion culling's phase 2
    uint pad0;
    uint pad1;
} pc;

layout(location = 0) out vec2 atlas_uv;
layout(location = 1) flat out uint atlas_layer;
// Camera-relative position: its screen derivatives give the triangle normal.
layout(location = 2) out vec3 rel_pos;
// For the debug views (debug_view.frag): the patch's level (PATCH_INFO_*
// bits) and where in its grid the vertex lies (0..1; 0 or 1 on an edge).
layout(location = 3) flat out uint patch_code;
layout(location = 4) out vec2 patch_uv;

// Nearest point of the grid 2^delta coarser, ties toward the lower one.
uint snap(uint i, uint delta) {
    if (delta == 0u) {
        return i;
    }
    uint half_step = 1u << (delta - 1u);
    return ((i + half_step - 1u) >> delta) << delta;
}

#include "refined_surface.glsl"

void main() {
    // Spec constants read into variables: expressions of spec constants
    // alone become OpSpecConstantOp, which naga cannot parse.
    uint per_side = PATCHES_PER_SIDE, quads = PATCH_QUADS;
    uvec4 p = patch_list.patches[gl_InstanceIndex];
    uint n = p.x, slot = patch_slot(p), index = patch_index(p);
    uint r = patch_refine(p), sub = patch_sub(p);
    uint side = quads + 1u;
    uint i = uint(gl_VertexIndex) % side, j = uint(gl_VertexIndex) / side;
    uvec2 pxy = uvec2(index % per_side, index / per_side);
    uint lod = node_lod(n);
    ivec2 node = ivec2(node_x(n), node_y(n));
    // Node-local vertex index in units of 2^-r samples (r = 0: samples).
    uint subs = 1u << r;
    uvec2 f = ((pxy * quads) << r) + uvec2(sub % subs, sub / subs) * quads + uvec2(i, j);
    // 0 unless stitching is switched off (tests that show the seams open).
    uint on = uint(view.v.lod_params.w == 0.0);
    // Snapped in node coordinates: a neighbour more than log2(quads) levels
    // coarser has its vertices beyond this patch's corners (the node's
    // side is a multiple of its grid, so they stay inside the node).
    uvec2 s = f;
    if (j == 0u) {
        s.x = snap(f.x, patch_delta(p, EDGE_SOUTH) * on);
    } else if (j == quads) {
        s.x = snap(f.x, patch_delta(p, EDGE_NORTH) * on);
    }
    if (i == 0u) {
        s.y = snap(f.y, patch_delta(p, EDGE_WEST) * on);
    } else if (i == quads) {
        s.y = snap(f.y, patch_delta(p, EDGE_EAST) * on);
    }
    ivec2 fine = ivec2(s);
    precise float h;
    precise vec3 rel;
    if (r == 0u) {
        ivec2 g = (node * int(per_side * quads) + fine) << lod;
        h = height_texel(slot, fine);
        rel.xy = view_rel_xy(g, view.v.camera_sample, view.v.camera_frac, view.v.spacing_m);
    } else {
        // Only LOD-0 nodes refine.
        ivec2 g = ((node * int(per_side * quads)) << int(r)) + fine;
        h = refined_height(slot, fine, r);
        rel.xy = view_rel_xy_fine(g, r, view.v.camera_sample, view.v.camera_frac, view.v.spacing_m);
    }
    precise float z = view.v.height_lo + h * view.v.height_range - view.v.camera_z;
    rel.z = z;
    precise vec4 clip = view.v.view_proj * vec4(rel, 1.0);
    gl_Position = clip;
    rel_pos = rel;
    vec2 local = vec2(fine) / float(subs);
#ifdef TERRAIN_HOLES
    // Below LOD 0 a vertex takes the hole flag of its nearest sample.
    ivec2 near = ivec2(floor(local + 0.5));
    if (texelFetch(sampler2DArray(albedo_atlas, nearest), ivec3(atlas_texel(near), int(slot)), 0).a < 0.5) {
        gl_Position = vec4(runtime_nan(pc.nan_bits));
    }
#endif
    atlas_uv = atlas_texel_uv(local);
    atlas_layer = slot;
    patch_code = lod | (r << PATCH_INFO_REFINE_SHIFT) | (pc.phase << PATCH_INFO_PHASE_SHIFT);
    patch_uv = vec2(i, j) / float(quads);
}

#endif

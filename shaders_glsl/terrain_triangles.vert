#version 460
#extension GL_GOOGLE_include_directive : require
// The per-triangle rule's draw: one indexed-indirect draw of the list
// emit_triangles wrote, whose indices are vertex codes (slot and grid
// point, triangle_list.glsl): the vertex pulls its node from the slot and
// its height from the node's layer; a point between the samples (a LOD-0
// node refined below them) lies on the Catmull-Rom surface, as the
// patches' refined vertices do. A grid point two nodes share has the same
// LOD-0 sample index and the same R16 height in both, a refined point on a
// border the same taps with weights 0 and 1, and every step to
// gl_Position is `precise` (terrain_vertex.glsl says why), so shared edges
// are bit-identical. A hole vertex (below the samples: its nearest
// sample's flag) becomes NaN (made at run time) and its triangles vanish.
#include "common.glsl"
#include "node_list.glsl"
#include "terrain_view.glsl"
#include "atlas_texels.glsl"
#include "triangle_list.glsl"

layout(constant_id = 0) const uint NODE_SIDE = 128u;

layout(set = 0, binding = 0, std430) readonly buffer View { TerrainView v; } view;
layout(set = 0, binding = 1, std430) readonly buffer SlotNodes { uint nodes[]; } slot_nodes;
layout(set = 0, binding = 2) uniform texture2DArray height_atlas;
// Hole mask: the albedo's alpha (below 0.5 = hole).
layout(set = 0, binding = 3) uniform texture2DArray albedo_atlas;
layout(set = 0, binding = 4) uniform sampler nearest;

#include "refined_surface.glsl"

layout(push_constant, std430) uniform TrianglesPush {
    uint nan_bits;  // a quiet NaN's bits, passed in so no compiler folds it (holes)
    uint pad0;
    uint pad1;
    uint pad2;
} pc;

layout(location = 0) out vec2 atlas_uv;
layout(location = 1) flat out uint atlas_layer;
layout(location = 2) out vec3 rel_pos;
layout(location = 3) flat out uint patch_code;
layout(location = 4) out vec2 patch_uv;

void main() {
    uint code = uint(gl_VertexIndex);
    uint slot = triangle_vertex_slot(code);
    // Lattice units: 2^-REFINE_LEVELS grid steps.
    ivec2 fine = triangle_vertex_lattice(code);
    uint n = slot_nodes.nodes[slot];
    uint lod = node_lod(n);
    // A spec constant read into a variable first: naga cannot parse the
    // conversion as a spec constant expression.
    uint side_u = NODE_SIDE;
    int side = int(side_u);
    int r = int(REFINE_LEVELS);
    ivec2 node = ivec2(node_x(n), node_y(n));
    bool on_grid = ((fine.x | fine.y) & ((1 << r) - 1)) == 0;
    // The nearest grid point (the point itself on the grid).
    ivec2 p = (fine + ((1 << r) >> 1)) >> r;
    precise float h;
    precise vec3 rel;
    if (on_grid) {
        ivec2 g = (node * side + p) << int(lod);
        h = texelFetch(sampler2DArray(height_atlas, nearest), ivec3(atlas_texel(p), int(slot)), 0).r;
        rel.xy = view_rel_xy(g, view.v.camera_sample, view.v.camera_frac, view.v.spacing_m);
    } else {
        // Only LOD-0 nodes refine below their grid.
        ivec2 g = ((node * side) << r) + fine;
        h = refined_height(slot, fine, uint(r));
        rel.xy = view_rel_xy_fine(g, uint(r), view.v.camera_sample, view.v.camera_frac, view.v.spacing_m);
    }
    precise float z = view.v.height_lo + h * view.v.height_range - view.v.camera_z;
    rel.z = z;
    precise vec4 clip = view.v.view_proj * vec4(rel, 1.0);
    gl_Position = clip;
    if (texelFetch(sampler2DArray(albedo_atlas, nearest), ivec3(atlas_texel(p), int(slot)), 0).a < 0.5) {
        gl_Position = vec4(runtime_nan(pc.nan_bits));
    }
    rel_pos = rel;
    vec2 local = vec2(fine) / float(1 << r);
    atlas_uv = atlas_texel_uv(local);
    atlas_layer = slot;
    patch_code = lod | ((on_grid ? 0u : REFINE_LEVELS) << PATCH_INFO_REFINE_SHIFT);
    patch_uv = local / float(side);
}

#version 460
#extension GL_GOOGLE_include_directive : require
// The per-triangle rule's draw: one indexed-indirect draw of the list
// emit_triangles wrote, whose indices are vertex codes (slot and grid
// point, triangle_list.glsl): the vertex pulls its node from the slot and
// its height from the node's layer. A grid point two nodes share has the
// same LOD-0 sample index and the same R16 height in both, and every step
// to gl_Position is `precise` (terrain_vertex.glsl says why), so shared
// edges are bit-identical. A hole vertex becomes NaN (made at run time)
// and its triangles vanish.
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
    ivec2 p = triangle_vertex_grid(code);
    uint n = slot_nodes.nodes[slot];
    uint lod = node_lod(n);
    // A spec constant read into a variable first: naga cannot parse the
    // conversion as a spec constant expression.
    uint side_u = NODE_SIDE;
    int side = int(side_u);
    ivec2 g = (ivec2(node_x(n), node_y(n)) * side + p) << int(lod);
    precise float h = texelFetch(sampler2DArray(height_atlas, nearest), ivec3(atlas_texel(p), int(slot)), 0).r;
    precise vec3 rel;
    rel.xy = view_rel_xy(g, view.v.camera_sample, view.v.camera_frac, view.v.spacing_m);
    precise float z = view.v.height_lo + h * view.v.height_range - view.v.camera_z;
    rel.z = z;
    precise vec4 clip = view.v.view_proj * vec4(rel, 1.0);
    gl_Position = clip;
    if (texelFetch(sampler2DArray(albedo_atlas, nearest), ivec3(atlas_texel(p), int(slot)), 0).a < 0.5) {
        gl_Position = vec4(runtime_nan(pc.nan_bits));
    }
    rel_pos = rel;
    atlas_uv = atlas_texel_uv(vec2(p));
    atlas_layer = slot;
    patch_code = lod;
    patch_uv = vec2(p) / float(side);
}

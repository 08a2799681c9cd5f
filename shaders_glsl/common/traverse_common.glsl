// Shared by traverse.comp (one dispatch, lists in shared memory) and
// traverse_level.comp (one dispatch per LOD): node packing, inputs, the LOD
// criterion and the output layout, so both variants decide identically.
#ifndef VISTA_TRAVERSE_COMMON_GLSL
#define VISTA_TRAVERSE_COMMON_GLSL

#include "node_list.glsl"

layout(set = 0, binding = 0) uniform utexture2D node_texture;
layout(set = 0, binding = 1) uniform sampler node_sampler;
layout(set = 0, binding = 2, std430) readonly buffer NodeDescs { uvec2 descs[]; } node_descs;
layout(set = 0, binding = 3, std430) readonly buffer NodeErrors { float errors[]; } node_errors;
layout(set = 0, binding = 4, std430) buffer TraverseOutput {
    TraverseHeader header;
    uvec2 nodes[];  // (packed node, slot)
} traverse_out;

layout(push_constant, std430) uniform TraversePush {
    vec4 cameras[MAX_CAMERAS];  // xyz: position (world m); w: pixels per unit of tan (viewport_h / (2 tan(fov_y/2)))
    uint camera_count;
    float target_error_px;
    float sector_size_m;
    uint lod_count;
    uint root_grid_x;
    uint root_grid_y;
    float height_lo;
    float height_scale;  // metres per R16 step: (hi - lo) / 65535, computed on the host
    uint list_capacity;  // entries per level list (<= the shader's fixed bound)
    uint final_capacity; // entries of traverse_out.nodes
    uint current_lod;    // traverse_level.comp only (LEVEL_FINALIZE: write the cull dispatch)
    uint pad;
} pc;

uint node_value(uint lod, uint x, uint y) {
    return texelFetch(usampler2D(node_texture, node_sampler), ivec2(x, y), int(lod)).r;
}

// Projected vertical error in pixels against the target, for any camera:
// err * w / dist > target, compared squared. Only correctly rounded
// operations (add, mul, ldexp), no contraction, so the CPU reference
// (src/reference/traverse.rs) makes bit-identical decisions.
bool wants_refine(uint lod, uint x, uint y, uint slot) {
    uvec2 d = node_descs.descs[slot];
    precise float size = pc.sector_size_m * float(1u << lod);
    precise vec3 bmin = vec3(float(x) * size, float(y) * size, pc.height_lo + float(bitfieldExtract(d.x, 0, int(HALF_BITS))) * pc.height_scale);
    precise vec3 bmax = vec3(bmin.x + size, bmin.y + size, pc.height_lo + float(d.x >> HALF_BITS) * pc.height_scale);
    int bias = bitfieldExtract(int(d.y), int(DESC_BIAS_SHIFT), int(DESC_BIAS_BITS));
    precise float err = ldexp(node_errors.errors[slot], bias);
    precise float target_sq = pc.target_error_px * pc.target_error_px;
    for (uint c = 0; c < pc.camera_count; ++c) {
        precise vec3 p = pc.cameras[c].xyz;
        precise vec3 o = max(max(bmin - p, p - bmax), vec3(0.0));
        precise float d2 = max(o.x * o.x + o.y * o.y + o.z * o.z, 1e-6);
        precise float lhs = err * pc.cameras[c].w;
        if (lhs * lhs > target_sq * d2) {
            return true;
        }
    }
    return false;
}

// Children of a node that can be drawn instead of it: 0 = keep the node
// (LOD 0, a child not resident, or no refinement wanted); else the count of
// valid children, whose packed refs are written to `kids`.
uint refinable_children(uint n, uint slot, out uint kids[4]) {
    uint lod = node_lod(n);
    if (lod == 0u) {
        return 0u;
    }
    uint x = node_x(n), y = node_y(n), count = 0u;
    for (uint j = 0u; j < 2u; ++j) {
        for (uint i = 0u; i < 2u; ++i) {
            uint cx = 2u * x + i, cy = 2u * y + j;
            uint v = node_value(lod - 1u, cx, cy);
            if (v == NODE_EMPTY) {
                return 0u;
            }
            if (v != NODE_INVALID) {
                kids[count++] = pack_node(lod - 1u, cx, cy);
            }
        }
    }
    if (count == 0u || !wants_refine(lod, x, y, slot)) {
        return 0u;
    }
    return count;
}

void emit_final(uint n, uint slot) {
    uint i = atomicAdd(traverse_out.header.node_count, 1u);
    atomicAdd(traverse_out.header.lod_counts[node_lod(n)], 1u);
    if (i < pc.final_capacity) {
        traverse_out.nodes[i] = uvec2(n, slot);
    }
}

#endif

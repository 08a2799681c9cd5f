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
    vec4 cameras[MAX_CAMERAS];   // xyz: position (grid metres); w: pixels per unit of tan (viewport_h / (2 tan(fov_y/2)))
    vec4 forwards[MAX_CAMERAS];  // xyz: the camera's unit forward axis; w: 1 / cos^2 of its frustum's widest angle to it
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
    float box_pad;       // added around a node's square, in node sides (the per-triangle rule: 1 / NODE_QUADS)
} pc;

uint node_value(uint lod, uint x, uint y) {
    return texelFetch(usampler2D(node_texture, node_sampler), ivec2(x, y), int(lod)).r;
}

// Projected vertical error in pixels against the target, for any camera.
// A vertical error e at p projects to at most e f |p| / z(p)^2 pixels (the
// largest singular value of the perspective Jacobian, z along the forward
// axis), so over the node's box it is at most e f k / d: d the box's
// distance, k = |v|^2 / z(v)^2 for the box's worst corner v (the angle to
// the forward axis is quasi-convex), never above the frustum's widest (and
// that for a corner behind the camera). Refine when e f k > t d for some
// corner and e f k_frustum > t d, compared squared. Only correctly rounded
// operations (add, mul, ldexp), no contraction, so the CPU reference
// (src/reference/traverse.rs) makes bit-identical decisions.
bool wants_refine(uint lod, uint x, uint y, uint slot) {
    uvec2 d = node_descs.descs[slot];
    precise float size = pc.sector_size_m * float(1u << lod);
    precise float grow = pc.box_pad * size;
    precise vec2 corner = vec2(float(x) * size, float(y) * size);
    precise vec3 bmin = vec3(corner - grow, pc.height_lo + float(bitfieldExtract(d.x, 0, int(HALF_BITS))) * pc.height_scale);
    precise vec3 bmax = vec3(corner + size + grow, pc.height_lo + float(d.x >> HALF_BITS) * pc.height_scale);
    int bias = bitfieldExtract(int(d.y), int(DESC_BIAS_SHIFT), int(DESC_BIAS_BITS));
    precise float err = ldexp(node_errors.errors[slot], bias);
    precise float target_sq = pc.target_error_px * pc.target_error_px;
    for (uint c = 0; c < pc.camera_count; ++c) {
        precise vec3 p = pc.cameras[c].xyz;
        precise vec3 f = pc.forwards[c].xyz;
        precise vec3 o = max(max(bmin - p, p - bmax), vec3(0.0));
        precise float d2 = max(o.x * o.x + o.y * o.y + o.z * o.z, 1e-6);
        precise float lhs = err * pc.cameras[c].w;
        precise float widest = lhs * pc.forwards[c].w;
        if (!(widest * widest > target_sq * d2)) {
            continue;
        }
        for (uint k = 0u; k < 8u; ++k) {
            precise vec3 v = vec3((k & 1u) != 0u ? bmax.x : bmin.x, (k & 2u) != 0u ? bmax.y : bmin.y,
                                  (k & 4u) != 0u ? bmax.z : bmin.z) - p;
            precise float z = v.x * f.x + v.y * f.y + v.z * f.z;
            precise float l2 = v.x * v.x + v.y * v.y + v.z * v.z;
            precise float a = lhs * l2;
            precise float zz = z * z;
            if (z <= 0.0 || a * a > target_sq * d2 * (zz * zz)) {
                return true;
            }
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

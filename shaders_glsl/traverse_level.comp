#version 460
#extension GL_GOOGLE_include_directive : require
// Reference variant of `traverse`: one dispatch per LOD, lists in global
// memory, each level writing the indirect arguments of the next. Same
// decisions (traverse_common.glsl), kept for the benchmark and tests.
layout(local_size_x = 64) in;
#include "traverse_common.glsl"

struct LevelArgs {
    uint x;
    uint y;
    uint z;
    uint count;  // entries of this level's list
};

// The host zeroes `x`/`count` and sets y = z = 1 before the first level.
layout(set = 0, binding = 5, std430) buffer TraverseLevels {
    LevelArgs levels[MAX_LEVELS];
    uint items[];  // level l's list at items[l * list_capacity ...]
} traverse_levels;

void push_level(uint l, uint n_kids, uint kids[4], uint n, uint slot) {
    uint cur = traverse_levels.levels[l].count;
    while (cur + n_kids <= pc.list_capacity) {
        uint prev = atomicCompSwap(traverse_levels.levels[l].count, cur, cur + n_kids);
        if (prev == cur) {
            for (uint c = 0u; c < n_kids; ++c) {
                traverse_levels.items[l * pc.list_capacity + cur + c] = kids[c];
            }
            atomicMax(traverse_levels.levels[l].x, (cur + n_kids + gl_WorkGroupSize.x - 1u) / gl_WorkGroupSize.x);
            return;
        }
        cur = prev;
    }
    atomicAdd(traverse_out.header.overflow, 1u);
    emit_final(n, slot);
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint lod = pc.current_lod;
    if (lod == LEVEL_FINALIZE) {
        if (i == 0u) {
            traverse_out.header.dispatch_x = min(traverse_out.header.node_count, pc.final_capacity);
            traverse_out.header.dispatch_y = 1u;
            traverse_out.header.dispatch_z = 1u;
        }
        return;
    }
    uint n;
    if (lod == pc.lod_count - 1u) {
        if (i >= pc.root_grid_x * pc.root_grid_y) {
            return;
        }
        uint x = i % pc.root_grid_x, y = i / pc.root_grid_x;
        uint v = node_value(lod, x, y);
        if (v == NODE_EMPTY) {
            atomicAdd(traverse_out.header.missing_roots, 1u);
            return;
        }
        if (v == NODE_INVALID) {
            return;
        }
        n = pack_node(lod, x, y);
    } else {
        if (i >= traverse_levels.levels[lod].count) {
            return;
        }
        n = traverse_levels.items[lod * pc.list_capacity + i];
    }
    uint slot = node_value(lod, node_x(n), node_y(n));
    uint kids[4];
    uint k = refinable_children(n, slot, kids);
    if (k > 0u) {
        push_level(lod - 1u, k, kids, n, slot);
    } else {
        emit_final(n, slot);
    }
}

#version 460
#extension GL_GOOGLE_include_directive : require
// The whole quadtree walk in ONE dispatch of ONE workgroup (Far Cry 5): the
// per-level node lists ping-pong in shared memory; nodes that stop refining
// go to the final list. Overflow keeps the coarser node, roots included
// (coverage is never lost), and is counted.
layout(local_size_x = 256) in;
#include "traverse_common.glsl"

// The two lists take 8 KiB of the 32 KiB lavapipe offers
// (constants.glsl SHARED_LIST_CAPACITY).
shared uint lists[2][SHARED_LIST_CAPACITY];
shared uint counts[2];

// Reserves `n` entries of list `l`, or fails (never over-reserves, so no
// half-written entries): a compare-and-swap loop on the shared count.
bool reserve(uint l, uint n, out uint at) {
    uint cur = counts[l];
    uint cap = min(pc.list_capacity, SHARED_LIST_CAPACITY);
    while (cur + n <= cap) {
        uint prev = atomicCompSwap(counts[l], cur, cur + n);
        if (prev == cur) {
            at = cur;
            return true;
        }
        cur = prev;
    }
    return false;
}

void main() {
    uint t = gl_LocalInvocationID.x;
    if (t == 0u) {
        counts[0] = 0u;
        counts[1] = 0u;
    }
    barrier();
    uint root_lod = pc.lod_count - 1u;
    uint roots = pc.root_grid_x * pc.root_grid_y;
    for (uint r = t; r < roots; r += gl_WorkGroupSize.x) {
        uint x = r % pc.root_grid_x, y = r / pc.root_grid_x;
        uint v = node_value(root_lod, x, y);
        if (v == NODE_EMPTY) {
            atomicAdd(traverse_out.header.missing_roots, 1u);
        } else if (v != NODE_INVALID) {
            uint at;
            if (reserve(0u, 1u, at)) {
                lists[0][at] = pack_node(root_lod, x, y);
            } else {
                // Dropping a root would leave its whole area undrawn.
                atomicAdd(traverse_out.header.overflow, 1u);
                emit_final(pack_node(root_lod, x, y), v);
            }
        }
    }
    barrier();
    uint src = 0u;
    for (int lod = int(root_lod); lod >= 0; --lod) {
        uint dst = 1u - src;
        uint count = counts[src];
        for (uint i = t; i < count; i += gl_WorkGroupSize.x) {
            uint n = lists[src][i];
            uint slot = node_value(node_lod(n), node_x(n), node_y(n));
            uint kids[4];
            uint k = refinable_children(n, slot, kids);
            uint at;
            if (k > 0u && reserve(dst, k, at)) {
                for (uint c = 0u; c < k; ++c) {
                    lists[dst][at + c] = kids[c];
                }
            } else {
                if (k > 0u) {
                    atomicAdd(traverse_out.header.overflow, 1u);
                }
                emit_final(n, slot);
            }
        }
        barrier();
        if (t == 0u) {
            counts[src] = 0u;
        }
        barrier();
        src = dst;
    }
    // barrier() orders only shared memory: other threads' node_count atomics could still be unseen.
    memoryBarrierBuffer();
    barrier();
    if (t == 0u) {
        uint n = min(atomicAdd(traverse_out.header.node_count, 0u), pc.final_capacity);
        traverse_out.header.dispatch_x = n;
        traverse_out.header.dispatch_y = 1u;
        traverse_out.header.dispatch_z = 1u;
    }
}

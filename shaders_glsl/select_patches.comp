#version 460
#extension GL_GOOGLE_include_directive : require
// Per-patch LOD selection (common/lod_select.glsl), one workgroup per
// listed node (indirect, from traverse), one thread per patch, in two
// dispatches: phase 0 picks each patch's coarse level (the coarsest
// ancestor whose patch meets the target, capped for the seams), phase 1
// refines the LOD-0 patches that LOD 0 itself does not serve (capped by the
// neighbours' coarse levels phase 0 wrote). cull_patches and cull_occluded
// draw what they decided.
layout(local_size_x = 256) in;

#define SELECT_WRITES 1
#include "lod_select.glsl"

layout(push_constant, std430) uniform SelectPush {
    uint phase;      // 0: coarse levels; 1: refinement
    uint lod_count;  // the world's LODs (the root is lod_count - 1)
    uint pad0;
    uint pad1;
} pc;

shared int s_finest;    // finest listed LOD along the node's edges (outside it)
shared int s_coarsest;  // coarsest one

// Scans the LOD map just outside the node's 4 edges.
void neighbour_lods(uint lod, ivec2 node, uint t) {
    if (t == 0u) {
        s_finest = int(NO_LEVEL);
        s_coarsest = -1;
    }
    barrier();
    int len = 1 << lod;
    ivec2 s0 = node << lod;
    for (int i = int(t); i < 4 * len; i += int(gl_WorkGroupSize.x)) {
        int e = i / len, k = i % len;
        ivec2 s = e == 0 ? ivec2(s0.x - 1, s0.y + k) : e == 1 ? ivec2(s0.x + len, s0.y + k)
                : e == 2 ? ivec2(s0.x + k, s0.y - 1) : ivec2(s0.x + k, s0.y + len);
        if (all(greaterThanEqual(s, ivec2(0))) && s.x < int(view.v.lod_map_w) && s.y < int(view.v.lod_map_h)) {
            uint l = imageLoad(lod_map, s).r;
            if (l != NO_LOD) {
                atomicMin(s_finest, int(l));
                atomicMax(s_coarsest, int(l));
            }
        }
    }
    barrier();
}

// Phase 0: the coarsest ancestor level whose patch meets the target, within
// [lift, cap] (see lod_select.glsl).
void coarse_level(uint lod, ivec2 node, uint slot, uint t) {
    neighbour_lods(lod, node, t);
    int n = int(lod);
    int amax = min(int(MAX_COARSEN), int(pc.lod_count) - 1 - n);
    int cap = s_finest == int(NO_LEVEL) ? amax : min(s_finest + int(MAX_LOD_DELTA) - n, amax);
    int lift = max(s_coarsest - int(MAX_LOD_DELTA) - n, 0);
    bool conflict = cap < 0 || lift > min(max(cap, 0), amax);
    // LOD-0 patches (here or next door) may be refined below the samples in
    // phase 1, up to the renderer's cap: coarsening stays within
    // MAX_LOD_DELTA of that too, so refinement is never refused for a seam
    // (which would break the target where it is needed most).
    int finest = min(s_finest == int(NO_LEVEL) ? n : s_finest, n);
    int finest_drawn = finest == 0 ? -int(view.v.lod_params.z) : finest;
    int refine_cap = finest_drawn + int(MAX_LOD_DELTA) - n;
    uint per_side = PATCHES_PER_SIDE;
    ivec2 pxy = ivec2(t % per_side, t / per_side);
    int a = 0;
    for (int k = 1; k <= amax; ++k) {
        ivec2 cell, apxy;
        ancestor_patch(node, pxy, uint(k), cell, apxy);
        uint aslot = node_slot(lod + uint(k), cell);
        vec3 lo, hi;
        patch_box(lod + uint(k), cell, apxy, aslot, lo, hi);
        if (!meets_target(patch_error(aslot, apxy).x, lo, hi)) {
            break;
        }
        a = k;
    }
    // Where the seams allow no choice, lifting the finer side keeps them closed.
    a = conflict ? min(lift, amax) : clamp(a, lift, max(min(cap, refine_cap), lift));
    select_levels.levels[2 * select_index(slot, t)] = n + a;
    if (t == 0u && conflict) {
        atomicAdd(select_levels.header.conflicts, 1u);
    }
    if (a > 0) {
        atomicAdd(select_levels.header.coarsened, 1u);
    }
}

// Phase 1: refinement of a LOD-0 patch drawn at LOD 0, by the errors of
// LOD 0 and of the 2x refinement (the 4x one is the finest surface: 0).
void refine_level(ivec2 node, uint slot, uint t) {
    int i = select_index(slot, t);
    if (select_levels.levels[2 * i] != 0) {
        return;
    }
    uint per_side = PATCHES_PER_SIDE, quads = PATCH_QUADS;
    ivec2 pxy = ivec2(t % per_side, t / per_side);
    vec3 lo, hi;
    patch_box(0u, node, pxy, slot, lo, hi);
    vec2 e = patch_error(slot, pxy);
    int r = meets_target(e.x, lo, hi) ? 0 : meets_target(e.y, lo, hi) ? 1 : int(REFINE_LEVELS);
    // The renderer's cap (LodOptions::refine_levels).
    r = min(r, int(view.v.lod_params.z));
    if (r > 0) {
        // Mid-edge samples just across each edge: the neighbours' coarse levels.
        int side = int(quads);
        ivec2 o = (node * int(per_side) + pxy) * side;
        int h = side / 2;
        int coarsest = 0;
        ivec2 across[4] = ivec2[4](ivec2(o.x - 1, o.y + h), ivec2(o.x + side, o.y + h), ivec2(o.x + h, o.y - 1), ivec2(o.x + h, o.y + side));
        for (uint e = 0u; e < 4u; ++e) {
            int l = level_at(across[e], false);
            if (l != int(NO_LEVEL)) {
                coarsest = max(coarsest, l);
            }
        }
        r = min(r, int(MAX_LOD_DELTA) - coarsest);
    }
    if (r > 0) {
        if (atomicAdd(select_levels.header.refined, 1u) >= MAX_REFINED_PATCHES) {
            atomicAdd(select_levels.header.refine_capped, 1u);
            r = 0;
        }
    }
    select_levels.levels[2 * i + 1] = -max(r, 0);
}

void main() {
    uint t = gl_LocalInvocationID.x;
    uvec2 entry = traverse_out.nodes[gl_WorkGroupID.x];
    uint n = entry.x, slot = entry.y, lod = node_lod(n);
    ivec2 node = ivec2(node_x(n), node_y(n));
    if (pc.phase == 0u) {
        coarse_level(lod, node, slot, t);
    } else if (lod == 0u) {
        refine_level(node, slot, t);
    }
}

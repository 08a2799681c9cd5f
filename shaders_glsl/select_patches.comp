#version 460
#extension GL_GOOGLE_include_directive : require
// Per-patch LOD selection (common/lod_select.glsl), one workgroup per
// listed node (indirect, from traverse), one thread per patch, in four
// dispatches: phase 0 picks each patch's coarse level (the coarsest
// ancestor whose patch meets the target, capped for the seams), phase 1
// asks to refine the LOD-0 patches that LOD 0 itself does not serve (capped
// by the neighbours' coarse levels phase 0 wrote) and counts them per
// priority bucket, phase 2 (one workgroup) finds the lowest bucket the
// refinement budget still holds whole, phase 3 refuses the rest. Which
// patches are refined thus depends on their errors alone, never on the
// order workgroups ran in. cull_patches and cull_occluded draw what they
// decided.
layout(local_size_x = 256) in;

#define SELECT_WRITES 1
#include "lod_select.glsl"

layout(push_constant, std430) uniform SelectPush {
    uint phase;       // 0: coarse levels; 1: refinement asked; 2: cut-off; 3: refinement decided
    uint lod_count;   // the world's LODs (the root is lod_count - 1)
    uint budget;      // LOD-0 patches refined at most (<= MAX_REFINED_PATCHES)
    uint buckets_at;  // index in `levels` of the REFINE_BUCKETS counts, then the cut-off
    uint reversed;    // 1: the node list and each node's patches taken in reverse order (tests: order independence)
    uint pad0;
    uint pad1;
    uint pad2;
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

// Which of REFINE_BUCKETS a patch asking for refinement falls in: its LOD-0
// error projected over the target, in REFINE_BUCKETS_PER_OCTAVE steps a
// doubling (higher: more in need).
uint priority_bucket(float err, vec3 lo, vec3 hi) {
    float over = max(projected_px(err, lo, hi) / view.v.lod_params.x, 1.0);
    return min(uint(log2(over) * float(REFINE_BUCKETS_PER_OCTAVE)), REFINE_BUCKETS - 1u);
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
        atomicAdd(select_levels.header.refined, 1u);
        uint b = priority_bucket(e.x, lo, hi);
        atomicAdd(select_levels.levels[pc.buckets_at + b], 1);
        // Phase 3 reads the bucket back: -(r | bucket << 2) until then.
        select_levels.levels[2 * i + 1] = -(r | int(b << 2u));
        return;
    }
    select_levels.levels[2 * i + 1] = 0;
}

// Phase 2 (one workgroup): the lowest bucket from which every bucket up
// fits the budget whole.
void cut_off(uint t) {
    if (t != 0u) {
        return;
    }
    uint kept = 0u;
    int cut = int(REFINE_BUCKETS);
    for (int b = int(REFINE_BUCKETS) - 1; b >= 0; --b) {
        uint n = uint(select_levels.levels[pc.buckets_at + uint(b)]);
        if (kept + n > pc.budget) {
            break;
        }
        kept += n;
        cut = b;
    }
    select_levels.levels[pc.buckets_at + REFINE_BUCKETS] = cut;
    select_levels.header.refine_capped = select_levels.header.refined - kept;
}

// Phase 3: a patch below the cut-off is drawn at LOD 0.
void decide_refinement(uint slot, uint t) {
    int i = select_index(slot, t);
    int asked = -select_levels.levels[2 * i + 1];
    if (select_levels.levels[2 * i] != 0 || asked <= 0) {
        return;
    }
    int cut = select_levels.levels[pc.buckets_at + REFINE_BUCKETS];
    int r = (asked >> 2) >= cut ? (asked & 3) : 0;
    select_levels.levels[2 * i + 1] = -r;
}

void main() {
    uint t = pc.reversed != 0u ? gl_WorkGroupSize.x - 1u - gl_LocalInvocationID.x : gl_LocalInvocationID.x;
    if (pc.phase == 2u) {
        cut_off(t);
        return;
    }
    uint w = pc.reversed != 0u ? traverse_out.header.dispatch_x - 1u - gl_WorkGroupID.x : gl_WorkGroupID.x;
    uvec2 entry = traverse_out.nodes[w];
    uint n = entry.x, slot = entry.y, lod = node_lod(n);
    ivec2 node = ivec2(node_x(n), node_y(n));
    if (pc.phase == 0u) {
        coarse_level(lod, node, slot, t);
    } else if (lod != 0u) {
        return;
    } else if (pc.phase == 1u) {
        refine_level(node, slot, t);
    } else {
        decide_refinement(slot, t);
    }
}
